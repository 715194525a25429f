"""Families of exact periodic orbits of the heavy body about a fixed point: shooting on a section and
pseudo-arclength continuation in the spin r0, with Floquet stability and bifurcation labels.

A section fixes γ''(0) = cos θ0 and r(0) = r0 and one more coordinate, leaving two state unknowns and the period:

* ``"gamma_prime"`` — γ'(0) = 0, unknowns (p0, q0): the seeds' section (``gyrolab.analysis.periodic.shoot``);
* ``"turning"`` — q(0) = 0, unknowns (p0, γ'0): the turning point of a swing about the body y axis, the section
  that stays transversal at r0 = 0, where the seeds' one contains the whole planar pendulum orbit (γ' ≡ 0).

Continuation unknowns z = (p0, x0, ln T, ln r0), with the exact Jacobian [Φ(T)D − D, f(y(T)), (Φ(T) − 1) e_r r0];
the tangent is its null vector. Stability from s = tr Φ(T) − 4 = ρ + 1/ρ (four trivial multipliers 1), bifurcations
from s crossing ±2 and d ln r0/ds changing sign (docs/regimes.md, "Orbit families from fast to slow spin").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.analysis.periodic import FixedPointModel

SECTIONS = ("gamma_prime", "turning")
MAX_LOG_STEP = 0.5
STABILITY_TOL = 1e-6  # |s| ≤ 2 + this counts as stable (s is computed to ~1e-10 on these orbits)


@dataclass(frozen=True)
class Section:
    kind: str
    gpp: float  # γ''(0) = cos θ0

    def __post_init__(self) -> None:
        if self.kind not in SECTIONS:
            raise ConfigError(f"section {self.kind!r} is not valid; valid choices: {', '.join(SECTIONS)}")

    def state(self, u: np.ndarray, r0: float) -> np.ndarray:
        """y0 from the two unknowns u = (p0, q0) or (p0, γ'0)."""
        p0, x = float(u[0]), float(u[1])
        if self.kind == "gamma_prime":
            return np.array([p0, x, r0, np.sqrt(max(0.0, 1 - self.gpp ** 2)), 0.0, self.gpp])
        return np.array([p0, 0.0, r0, np.sqrt(max(0.0, 1 - x ** 2 - self.gpp ** 2)), x, self.gpp])

    def derivative(self, u: np.ndarray) -> np.ndarray:
        """∂y0/∂u (6 × 2)."""
        D = np.zeros((6, 2))
        D[0, 0] = 1.0
        if self.kind == "gamma_prime":
            D[1, 1] = 1.0
        else:
            g = np.sqrt(max(1e-300, 1 - u[1] ** 2 - self.gpp ** 2))
            D[4, 1], D[3, 1] = 1.0, -u[1] / g
        return D


@dataclass
class FamilyPoint:
    r0: float
    period: float
    y0: np.ndarray
    monodromy: np.ndarray
    residual: float
    tangent: np.ndarray = field(default_factory=lambda: np.full(4, np.nan))
    multipliers: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.multipliers = np.linalg.eigvals(self.monodromy)

    @property
    def stability_index(self) -> float:
        """s = tr Φ(T) − 4 = ρ + 1/ρ of the non-trivial pair."""
        return float(np.trace(self.monodromy) - 4.0)

    @property
    def stable(self) -> bool:
        return bool(abs(self.stability_index) <= 2.0 + STABILITY_TOL)


def _evaluate(model: FixedPointModel, section: Section, z: np.ndarray, r0: float | None = None):
    """Residual (relative), raw residual, Jacobian in z = (p0, x, ln T, ln r0), start state, monodromy.

    With ``r0`` given, the spin is that value (r0 = 0 allowed) and z[3] is ignored."""
    u, T = z[:2], float(np.exp(z[2]))
    r0 = float(np.exp(z[3])) if r0 is None else float(r0)
    y0 = section.state(u, r0)
    yT, phi = model.flow(y0, T)
    scale = max(1.0, float(np.max(np.abs(y0))))
    D = section.derivative(u)
    e_r = np.eye(6)[2]  # the direction of r0
    J = np.column_stack([phi @ D - D, model.rhs(yT) * T, (phi @ e_r - e_r) * r0]) / scale
    res = (yT - y0) / scale
    return float(np.max(np.abs(res))), res, J, y0, phi


def _newton(model, section, z, *, tangent=None, anchor=None, fixed_r0=None, tol=1e-13, accept=1e-11,
            max_iter=25):
    """Gauss–Newton on the return residual (+ the arclength condition), damped when the residual grows.

    ``fixed_r0``: the spin held at that value (plain shooting in (p0, x, ln T))."""
    fixed = fixed_r0 is not None

    def system(zz):
        norm, res, J, y0, phi = _evaluate(model, section, zz, fixed_r0)
        if fixed:
            J = J[:, :3]
        elif tangent is not None:
            res = np.append(res, tangent @ (zz - anchor))
            J = np.vstack([J, tangent])
        return norm, res, J, y0, phi

    norm, res, J, y0, phi = system(z)
    history = [norm]
    for _ in range(max_iter):
        if norm < tol:
            break
        step = np.linalg.lstsq(J, -res, rcond=None)[0]
        if fixed:
            step = np.append(step, 0.0)
        largest = float(np.max(np.abs(step[2:])))
        if largest > MAX_LOG_STEP:  # a Newton step may not multiply T or r0 by more than e^MAX_LOG_STEP
            step *= MAX_LOG_STEP / largest
        for damping in 0.5 ** np.arange(0, 12):
            try:
                trial = system(z + damping * step)
            except IntegrationError:
                continue
            if trial[0] < max(history[-4:]) or damping == 1.0 and trial[0] < 10 * norm:
                break
        else:
            break
        z = z + damping * step
        norm, res, J, y0, phi = trial
        history.append(norm)
        if len(history) > 3 and norm > 0.5 * history[-2] and norm < accept:
            break  # at the rounding floor
    if not norm < accept:
        raise IntegrationError(f"shooting did not converge: return residual {norm:.2e} (needs < {accept:.0e}) "
                               f"after {len(history) - 1} iterations")
    return z, norm, y0, phi


def shoot_section(model: FixedPointModel, section: Section, u: np.ndarray, period: float, r0: float,
                  **kwargs) -> FamilyPoint:
    """The periodic orbit through the section at spin r0 (fixed), Newton from (u, period)."""
    z = np.array([u[0], u[1], np.log(period), 0.0])
    z, norm, y0, phi = _newton(model, section, z, fixed_r0=float(r0), **kwargs)
    return FamilyPoint(float(r0), float(np.exp(z[2])), y0, phi, norm)


def _tangent(model, section, z, previous=None):
    _, _, J, _, _ = _evaluate(model, section, z)
    t = np.linalg.svd(J)[2][-1]
    if previous is not None and t @ previous < 0:
        t = -t
    return t


class Family(list):
    """The points of a continued family, in order; ``stop_reason`` says why the continuation ended."""

    stop_reason: str = ""


def continue_family(model: FixedPointModel, section: Section, start: FamilyPoint, r0_end: float, *,
                    step: float = 0.1, max_step: float = 0.4, min_step: float = 1e-4, max_points: int = 400,
                    max_period: float = 200.0) -> Family:
    """Pseudo-arclength continuation from ``start`` (r0 > 0) until ln r0 passes ln ``r0_end``, the step grown by 1.3
    after a success and halved after a failure; stops early below ``min_step``, after ``max_points`` points or past
    ``max_period`` (the period diverges near an equilibrium or a homoclinic loop), as ``stop_reason`` says.
    """
    if start.r0 <= 0 or r0_end <= 0:
        raise ConfigError("continuation in ln r0 needs r0 > 0 at both ends")
    z = _family_z(section, start)
    direction = np.sign(np.log(r0_end) - z[3])
    t = _tangent(model, section, z)
    if t[3] * direction < 0:
        t = -t
    start.tangent = t
    points = Family([start])
    h = step
    points.stop_reason = "reached r0_end"
    while (np.log(r0_end) - z[3]) * direction > 0:
        if len(points) >= max_points:
            points.stop_reason = f"{max_points} points (orbit_family max_points)"
            break
        anchor = z + h * t
        try:
            z_new, norm, y0, phi = _newton(model, section, anchor.copy(), tangent=t, anchor=anchor, max_iter=12)
        except IntegrationError as error:
            h *= 0.5
            if h < min_step:
                points.stop_reason = f"the corrector failed down to the smallest step {min_step:g} ({error})"
                break
            continue
        t_new = _tangent(model, section, z_new, t)
        if np.arccos(np.clip(t_new @ t, -1, 1)) > 0.3 or (z_new - z) @ t <= 0.2 * h:  # sharp turn or going back
            h *= 0.5
            if h < min_step:
                points.stop_reason = (f"the family turns too sharply to follow with the smallest step {min_step:g} "
                                      "(a cusp, or a branch the tangent cannot choose)")
                break
            continue
        if np.exp(z_new[2]) > max_period:
            points.stop_reason = (f"the period {np.exp(z_new[2]):.4g} passed the period limit {max_period:g} "
                                  "(an orbit approaching an equilibrium or a homoclinic loop)")
            break
        z, t = z_new, t_new
        points.append(FamilyPoint(float(np.exp(z[3])), float(np.exp(z[2])), y0, phi, norm, t))
        h = min(max_step, 1.3 * h)
    return points


@dataclass(frozen=True)
class Event:
    """A bifurcation located on a family: ``index`` the point after it, ``r0`` where it happens."""

    index: int
    kind: str  # "fold", "branch point", "period doubling"
    r0: float
    stability_index: float  # s at r0: ±2 for a located branch point or period doubling
    period: float
    located: str  # how r0 was found
    y0: np.ndarray = field(default_factory=lambda: np.full(6, np.nan))  # the orbit's state at the event (NaN: fold)


def locate_events(model: FixedPointModel, section: Section, points: list[FamilyPoint],
                  events: list[tuple[int, str]] | None = None, tol: float = 1e-9) -> list[Event]:
    """Each bifurcation of ``bifurcations(points)`` located in r0, not just bracketed by two family points: a crossing
    of s = ±2 by regula falsi along the family to |s ∓ 2| < ``tol``, a fold by the vertex of the parabola of ln r0
    through the three points around it (docs/regimes.md, "Orbit families from fast to slow spin").
    """
    located = []
    for index, kind in bifurcations(points) if events is None else events:
        a, b = points[index - 1], points[index]
        if kind == "fold":
            located.append(_fold(points, index))
            continue
        target = 2.0 if kind == "branch point" else -2.0
        try:
            try:
                located.append(_crossing(model, section, a, b, index, kind, target, tol))
            except IntegrationError:  # the chord strays too far from a long arc: follow the arc in small steps
                located.append(_crossing_on_dense_arc(model, section, a, b, index, kind, target, tol))
        except IntegrationError as error:  # shooting failed inside the bracket: keep the bracket, say so
            r0 = float(np.sqrt(a.r0 * b.r0))
            located.append(Event(index, kind, r0, float("nan"), float(np.sqrt(a.period * b.period)),
                                 f"bracketed only, between r0/c = {a.r0:.6g} and {b.r0:.6g} ({error})"))
    return located


def _family_z(section: Section, point: FamilyPoint) -> np.ndarray:
    """The continuation unknowns z = (p0, x, ln T, ln r0) of a family point."""
    x = point.y0[1] if section.kind == "gamma_prime" else point.y0[4]
    return np.array([point.y0[0], x, np.log(point.period), np.log(point.r0)])


def _crossing(model, section, a, b, index, kind, target, tol) -> Event:
    """s = target between family points a and b, by regula falsi (Illinois) in λ along the chord z_a → z_b: each
    trial is the family's orbit on the hyperplane through z_a + λ (z_b − z_a) normal to the chord (the corrector
    of the continuation), which stays well posed at a fold, where shooting at a fixed r0 does not."""
    za, zb = _family_z(section, a), _family_z(section, b)
    chord = (zb - za) / np.linalg.norm(zb - za)
    lo, hi = 0.0, 1.0
    f_lo, f_hi = a.stability_index - target, b.stability_index - target
    best, side = None, 0
    for _ in range(60):
        lam = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        anchor = za + lam * (zb - za)
        z, norm, y0, phi = _newton(model, section, anchor.copy(), tangent=chord, anchor=anchor)
        best = FamilyPoint(float(np.exp(z[3])), float(np.exp(z[2])), y0, phi, norm)
        f = best.stability_index - target
        if abs(f) < tol or hi - lo < 1e-14:
            break
        if f * f_lo > 0:
            lo, f_lo = lam, f
            f_hi = f_hi / 2 if side == -1 else f_hi  # Illinois: halve the stale end's value
            side = -1
        else:
            hi, f_hi = lam, f
            f_lo = f_lo / 2 if side == 1 else f_lo
            side = 1
    return Event(index, kind, best.r0, best.stability_index, best.period,
                 f"regula falsi on s {'-' if target > 0 else '+'} 2 along the family between its points (|residual| "
                 f"{abs(best.stability_index - target):.1e})", np.array(best.y0, dtype=float))


def _crossing_on_dense_arc(model, section, a, b, index, kind, target, tol) -> Event:
    """``_crossing`` on the pair of points that brackets s = target once the arc from a to b is continued again in
    small steps (for two family points far apart along a curved arc)."""
    dense = continue_family(model, section, a, b.r0, step=0.005, max_step=0.02, max_points=400)
    for c, d in zip(dense, dense[1:]):
        if (c.stability_index - target) * (d.stability_index - target) < 0:
            return _crossing(model, section, c, d, index, kind, target, tol)
    raise IntegrationError(f"no crossing of s = {target:g} found on the arc continued again in small steps "
                           f"({len(dense)} points)")


def _fold(points, index) -> Event:
    i = min(max(index, 1), len(points) - 2)
    trio = points[i - 1:i + 2]
    x = np.log([p.r0 for p in trio])
    s = np.arange(3.0)  # the three points' order along the family stands in for arclength
    c = np.polyfit(s, x, 2)
    vertex = -c[1] / (2 * c[0]) if c[0] != 0 else 1.0
    r0 = float(np.exp(np.polyval(c, vertex))) if 0 <= vertex <= 2 else points[index].r0
    near = points[index]
    return Event(index, "fold", r0, near.stability_index, near.period,
                 "vertex of the parabola of ln r0 through the three points around the turn")


def bifurcations(points: list[FamilyPoint]) -> list[tuple[int, str]]:
    """(index of the point after the event, label): "fold" (d ln r0/ds changes sign), "branch point" (s through
    +2 without a fold), "period doubling" (s through −2)."""
    events = []
    for i in range(1, len(points)):
        a, b = points[i - 1], points[i]
        fold = np.sign(a.tangent[3]) != np.sign(b.tangent[3]) and np.all(np.isfinite([a.tangent[3], b.tangent[3]]))
        if fold:
            events.append((i, "fold"))
        if (a.stability_index - 2) * (b.stability_index - 2) < 0 and not fold:
            events.append((i, "branch point"))
        if (a.stability_index + 2) * (b.stability_index + 2) < 0:
            events.append((i, "period doubling"))
    return events
