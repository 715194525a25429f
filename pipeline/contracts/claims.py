"""A force's claims, checked by numbers: its potential belongs to its torque (``Force`` rule 5), its area-integral
flag is true (rule 6); a false claim would make gyrolab monitor, and draw as conserved, a quantity that is not.

The scene checks a third-party force's claims when it is built (docs/plugins.md, "What the engine checks");
``gyrolab.testing.check_force`` checks them more tightly, with the same derivative from here.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from gyrolab.errors import ConfigError, shorten

#: step of the central differences of the potential under small rotations of the body
ROTATION_STEP = 1e-5
#: a potential's finite-difference torque may differ from the torque by this fraction of the larger of the two,
#: plus the round-off of the central difference (ROUNDOFF_FACTOR × eps × |V| / ROTATION_STEP)
POTENTIAL_RTOL = 1e-6
ROUNDOFF_FACTOR = 1e3
#: torque·γ below this fraction of |torque| counts as no component along the vertical γ (round-off is ~1e-16)
AREA_RTOL = 1e-9
#: deterministic random states checked besides the initial one (seeded: the verdict never changes between runs)
CLAIM_STATES = 4
CLAIM_SEED = 20211


def random_states(n: int = 20, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random angular velocities (n, 3) and attitudes (n, 3, 3): rows α, β, γ, a right-handed frame."""
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    q = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 0] *= -1
    frames = np.ascontiguousarray(q.transpose(0, 2, 1))  # rows e_0, e_1, e_2 with e_0 × e_1 = e_2
    return rng.normal(scale=2.0, size=(n, 3)), frames


def axes_of(force: Any, frame: np.ndarray) -> tuple:
    """The reference axes a force reads (``required_axes``) from frames (..., 3, 3); None for the others."""
    return tuple(frame[..., i, :] if i in force.required_axes else None for i in range(3))


def _rotation(axis: int, angle: float) -> np.ndarray:
    """Rotation matrix about body axis ``axis``: v → v + angle ê × v to first order."""
    c, s = math.cos(angle), math.sin(angle)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def rotation_torque(force: Any, frame: np.ndarray, h: float = ROTATION_STEP) -> np.ndarray:
    """Σ e_i × ∂V/∂e_i by central differences: component k is dV/dε for the axes rotated by ε about body axis k."""
    out = np.empty(3)
    for k in range(3):
        plus = frame @ _rotation(k, h).T  # rows e_i → R e_i
        minus = frame @ _rotation(k, -h).T
        v_plus = np.asarray(force.potential(axes_of(force, plus[None])), dtype=float)
        v_minus = np.asarray(force.potential(axes_of(force, minus[None])), dtype=float)
        out[k] = float((v_plus - v_minus).reshape(-1)[0]) / (2 * h)
    return out


def torque_problem(value: Any) -> str:
    """What is wrong with a torque's return value (rule 3: a finite float array of shape (3,)), or ''."""
    if value is None or isinstance(value, (str, bytes)):
        return f"returned {type(value).__name__} {shorten(repr(value), 40)}"
    try:
        array = np.asarray(value)
    except Exception:  # noqa: BLE001 - an object numpy cannot read is the problem itself
        return f"returned a {type(value).__name__} numpy cannot read"
    if array.dtype.kind not in "fiu" or array.shape != (3,):
        return f"returned {type(value).__name__} of shape {array.shape} and dtype {array.dtype}"
    if not np.isfinite(array).all():
        return f"returned the non-finite torque {array.tolist()}"
    return ""


def _torque(force: Any, omega: np.ndarray, frame: np.ndarray, t: float, where: str) -> np.ndarray:
    axes = axes_of(force, frame)
    try:
        value = force.torque(omega, axes, t) if force.time_dependent else force.torque(omega, axes)
    except Exception as exc:  # noqa: BLE001 - a plugin may raise anything; one sentence naming it
        raise ConfigError(f"{where}: the torque of force {force.name!r} raised {type(exc).__name__} while gyrolab "
                          f"checked its claims: {shorten(str(exc), 160) or '(no message)'}") from exc
    problem = torque_problem(value)
    if problem:
        raise ConfigError(f"{where}: the torque of force {force.name!r} {problem} while gyrolab checked its "
                          "claims; torque(omega, axes) must return a finite float array of shape (3,)")
    return np.asarray(value, dtype=float)


def claim_states(omega0: np.ndarray | None, frame0: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The states a scene checks claims at: the initial one (when its frame is known), then CLAIM_STATES seeded
    random ones."""
    omegas, frames = random_states(CLAIM_STATES, CLAIM_SEED)
    if frame0 is not None:
        omega0 = np.zeros(3) if omega0 is None else np.asarray(omega0, dtype=float)
        omegas, frames = np.vstack([omega0, omegas]), np.concatenate([np.asarray(frame0, dtype=float)[None], frames])
    return omegas, frames


def check_claims(force: Any, omegas: np.ndarray, frames: np.ndarray, t0: float = 0.0, where: str = "",
                 initial: bool = True) -> None:
    """ConfigError (one sentence naming the force, the false claim and the measured numbers) when the force's
    potential does not belong to its torque or its ``preserves_area_integral = True`` is false, at the states
    (omegas (n, 3), frames (n, 3, 3)); the first state is checked at ``t0`` and is the scene's initial one
    when ``initial``."""
    where = where or f"force.{force.name}"
    labels = [("the initial state" if initial and k == 0 else f"test state {k}") for k in range(len(frames))]
    times = t0 + 0.7 * np.arange(len(frames))
    torques = np.array([_torque(force, w, f, t, where) for w, f, t in zip(omegas, frames, times)])
    if bool(force.preserves_area_integral):
        along = np.abs(np.einsum("ij,ij->i", torques, frames[:, 2, :]))
        size = np.linalg.norm(torques, axis=1)
        broken = np.flatnonzero(along > AREA_RTOL * size)
        if broken.size:
            worst = int(broken[0])  # the first state that breaks the claim: the initial one when it does
            raise ConfigError(f"{where}: force {force.name!r} declares preserves_area_integral = True, but its torque "
                              f"has the component torque·γ = {along[worst]:.3g} along the vertical γ (|torque| = "
                              f"{size[worst]:.3g}, {labels[worst]}), so Iω·γ is not conserved; declare "
                              "preserves_area_integral = False")
    if getattr(force, "conservative", False):
        for k, (torque, frame) in enumerate(zip(torques, frames)):
            _check_potential(force, torque, frame, labels[k], where)


def _check_potential(force: Any, torque: np.ndarray, frame: np.ndarray, label: str, where: str) -> None:
    try:
        value = float(np.asarray(force.potential(axes_of(force, frame[None])), dtype=float).reshape(-1)[0])
        expected = rotation_torque(force, frame)
    except Exception as exc:  # noqa: BLE001 - one sentence naming the force
        raise ConfigError(f"{where}: the potential of force {force.name!r} failed on axes of shape (1, 3): "
                          f"{type(exc).__name__}: {shorten(str(exc), 160)}; potential(axes) must be vectorised "
                          "over (n, 3) axes") from exc
    error = float(np.max(np.abs(torque - expected)))
    allowed = POTENTIAL_RTOL * max(float(np.max(np.abs(torque))), float(np.max(np.abs(expected)))) \
        + ROUNDOFF_FACTOR * np.finfo(float).eps * abs(value) / ROTATION_STEP
    if not error <= allowed:
        raise ConfigError(f"{where}: the potential of force {force.name!r} does not belong to its torque: at {label} "
                          f"the torque is {np.round(torque, 9).tolist()} but Σ e_i × ∂V/∂e_i of the potential is "
                          f"{np.round(expected, 9).tolist()} (difference {error:.3g}); fix potential or torque, or "
                          "remove potential if the force is not conservative")
