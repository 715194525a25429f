"""Validity of each regime: error of the analytic solution against the exact orbit and the full model over a log range
of its parameter, fitted orders against the theory's, and ``small_parameter`` across the resonances ω → n
(docs/regimes.md, "Verdict"). ``large_parameter``'s row is the evidence against the paper's reading μ = c/r0.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf, open_dict

from gyrolab.contracts import registry
from gyrolab.engine.config import compose_config
from gyrolab.engine.scene import Scene
from gyrolab.engine.schemas import Task
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.experiments.regime_run import build_regime, compute, errors, integrate, prepare
from gyrolab.figures.redraw import write_and_draw
from gyrolab.output.cf import conform
from gyrolab.output.provenance import provenance
from gyrolab.plugins.regimes.base import nondimensional_scene
from gyrolab.plugins.regimes.large_parameter import printed_reading_state

log = logging.getLogger(__name__)

#: the domain warnings of the points this experiment probes on purpose (near resonances, at the edge of a domain,
#: non-physical bodies): collected, not printed one by one; their text goes into the dataset, a count to the log
_expected: list[str] = []


def _prepare(sub: DictConfig, where: str):
    """``prepare`` without its per-warning log lines; the warnings are collected in ``_expected``."""
    scene, regime, warnings = prepare(sub, report=False)
    _expected.extend(f"{where}: {regime.name}: {warning}" for warning in warnings)
    return scene, regime, warnings


KEYS = ("pq", "r", "gamma", "gamma3", "period")
LONG = {"pq": "p, q", "r": "r", "gamma": "γ, γ'", "gamma3": "γ''", "period": "period"}


def _group(cfg: DictConfig, entry: str) -> str:
    """The regime config group of a validity entry: its ``regime`` key (e.g. a branch of resonant_omega3), else its name."""
    return str((cfg.regime_validity.get(entry) or {}).get("regime", entry))


def _cfg_for(cfg: DictConfig, regime: str, r0: float) -> DictConfig:
    base = OmegaConf.to_container(cfg, resolve=True)
    new = compose_config([f"regime={_group(cfg, regime)}", "regime.periods=1"])
    with open_dict(new):
        for section in ("system", "body", "initial", "force", "time", "output"):
            new[section] = base[section]
        for key, value in (base["regime_validity"].get(regime, {}).get("scene") or {}).items():
            OmegaConf.update(new, key, value, force_add=True)
        new.initial.r0 = float(r0)
        gamma = base["regime_validity"].get(regime, {}).get("Gamma")
        if gamma is not None:  # Ismail's (2021) γ0'' = Γ c/r0 (eq. 28): the tilt follows the spin
            new.initial.theta0 = float(np.arccos(min(1.0, gamma / r0)))
    return new


def _scales(regime, system) -> dict[str, float]:
    s = regime.scene(system)
    g = s.gamma0pp if regime.name == "resonant_omega3" else 1.0
    return {"pq": np.sqrt(g) * s.c if regime.name == "resonant_omega3" else s.c, "r": s.r0 * s.c,
            "gamma": g, "gamma3": g, "period": 1 / (s.r0 * s.c)}


def _point(sub: DictConfig, where: str, against: tuple[str, ...] = ("orbit", "full"), *, check: bool = True):
    """(status, {against: relative error per key}, the regime or None) of the analytic solution over one period:
    ``refused`` outside the regime's domain (``check=False`` skips that check), ``failed`` where no exact orbit is
    found near it (the errors are then NaN)."""
    nan = {a: dict.fromkeys(KEYS, np.nan) for a in against}
    try:
        scene, regime = _prepare(sub, where)[:2] if check else (Scene.from_config(sub), build_regime(sub))
    except ConfigError as error:
        return f"refused: {error}", nan, None
    try:
        result = compute(scene, regime, np.linspace(0, regime.period(scene.system), 241), full="full" in against)
    except IntegrationError as error:  # no exact orbit near the series (far outside its domain)
        return f"failed: {error}", nan, regime
    sc, found = _scales(regime, scene.system), {a: errors(result, a) for a in against}
    return "ok", {a: {k: e.get(k, np.nan) / sc[k] for k in KEYS} for a, e in found.items()}, regime


def _r0_for(regime: str, value: float, cfg: DictConfig) -> float:
    if _group(cfg, regime) == "resonant_omega3":
        theta0 = float(cfg.regime_validity[regime].scene["initial.theta0"])
        return float(np.sqrt(np.cos(theta0)) / value)
    return 1.0 / value  # c/r0 in units of c


TASK = Task("regime_validity", section="regime_validity")


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    spec = cfg.regime_validity
    rows, verdicts = [], []
    _expected.clear()
    for regime_name in spec.regimes:
        values = [float(v) for v in spec[regime_name]["values"]]
        fit_below = float(spec[regime_name]["fit_below"])
        errs, status, theory = _regime_errors(cfg, regime_name, values)
        orders = _fitted_orders(values, errs["orbit"], fit_below)
        verdict = _verdict(regime_name, spec[regime_name]["parameter"], fit_below, values, status, orders, theory)
        log.info("%s", verdict)
        verdicts.append(verdict)
        rows.append((regime_name, values, errs, orders, status))
    if "large_parameter" in spec.get("evidence", []):
        verdicts.append(_large_parameter_evidence(cfg, rows))
    sweep = None
    if spec.get("resonance_sweep") is not None:
        sweep = resonance_sweep(cfg)
        verdicts.extend(sweep["verdicts"])
    ds = _dataset(rows, verdicts, cfg)
    if sweep is not None:
        ds = ds.merge(_resonance_dataset(sweep))
    ds.attrs["n_expected_warnings"] = len(_expected)
    ds.attrs["expected_warnings"] = "\n".join(_expected) or "none"
    conform(ds, source="regime_validity experiment")
    written = write_and_draw("regime_validity.nc", ds, out_dir, cfg.get("output"))
    if _expected:
        log.warning("%d expected domain warnings (points probed on purpose near resonances, at the edge of a "
                    "regime's domain or with non-physical bodies); their text is in %s (attribute expected_warnings)",
                    len(_expected), written[0])
    return written


def _regime_errors(cfg: DictConfig, regime_name: str, values: list[float]) -> tuple[dict, list[str], dict]:
    """(errors against the exact orbit and the full equations per key, each point's status, the theory's orders)
    of a regime's series at each value of its parameter."""
    errs: dict[str, dict[str, list]] = {against: {k: [] for k in KEYS} for against in ("orbit", "full")}
    status = []
    theory = getattr(registry.load("regime", _group(cfg, regime_name)), "order", {})
    for value in values:
        sub = _cfg_for(cfg, regime_name, _r0_for(regime_name, value, cfg))
        state, e, regime = _point(sub, f"{regime_name} at {cfg.regime_validity[regime_name]['parameter']} = {value:g}")
        status.append(state)
        if regime is not None:
            theory = regime.order  # the instance's: a branch may have other orders than the class default
        for against, table in errs.items():
            for k in KEYS:
                table[k].append(e[against][k])
    return errs, status, theory


def _fitted_orders(values: list[float], errs: dict[str, list], fit_below: float) -> dict[str, float]:
    """Per key, the slope of log error against log parameter over the points at or below ``fit_below``."""
    orders = {}
    for k in KEYS:
        x, y = np.array(values), np.array(errs[k])
        ok = (x <= fit_below) & np.isfinite(y) & (y > 0)
        orders[k] = float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0]) if ok.sum() >= 2 else np.nan
    return orders


def _verdict(regime_name: str, parameter: str, fit_below: float, values: list[float], status: list[str],
             orders: dict[str, float], theory: dict) -> str:
    """The regime's fitted orders against the theory's, and where it was refused or found no exact orbit."""
    # an order is consistent within 0.2 of the theory's; a faster decay is consistent too (the theory's
    # O(μⁿ) is a bound: a small coefficient shows as a higher fitted slope) but is named in the verdict
    checked = [k for k in KEYS if k in theory and np.isfinite(orders[k])]
    good = all(orders[k] >= theory[k] - 0.2 for k in checked)
    faster = [LONG[k] for k in checked if orders[k] > theory[k] + 0.2]
    return (f"{regime_name}: fitted orders (parameter ≤ {fit_below:g}) "
            + ", ".join(f"{LONG[k]} {orders[k]:.2f} (theory {theory.get(k, float('nan')):g})" for k in KEYS)
            + f"; {'consistent with' if good else 'NOT consistent with'} the theory"
            + (f" ({', '.join(faster)} faster than its bound)" if faster else "") + "; "
            + _missing_points(parameter, values, status))


def _missing_points(parameter: str, values: list[float], status: list[str]) -> str:
    """Where a regime was refused outside its domain, and where no exact orbit was found near its series."""
    refused = ", ".join(f"{v:g}" for v, s in zip(values, status) if s.startswith("refused"))
    failed = ", ".join(f"{v:g}" for v, s in zip(values, status) if s.startswith("failed"))
    return ((f"refused outside the domain at {parameter} = {refused}" if refused else "no refused point")
            + (f"; no exact orbit found near the series at {parameter} = {failed}" if failed else ""))


def a_for_omega(omega: float, b: float) -> float:
    """The body's a = A/C that gives natural frequency ω at fixed b: (1−a)(1−b) = ω² a b."""
    return (1.0 - b) / ((1.0 - b) + omega * omega * b)


def resonance_cfg(cfg: DictConfig, omega: float) -> DictConfig:
    """The small_parameter scene of the resonance sweep with the body's ω set through a (b fixed)."""
    spec = cfg.regime_validity.resonance_sweep
    b = float(spec.b)
    sub = _cfg_for(cfg, spec.regime, float(spec.r0))
    with open_dict(sub):
        sub.body.a = a_for_omega(float(omega), b)
        sub.body.b = b
        sub.body.allow_nonphysical = True  # ω > 1 needs A + B < C (ω² − 1 = (1 − a − b)/(ab))
    return sub


def resonance_point(cfg: DictConfig, omega: float, *, check: bool = True) -> tuple[str, dict[str, float]]:
    """(status, relative errors against the exact orbit over one period) at natural frequency ω.

    ``check=False`` skips the regime's domain check (to measure the error inside the refused band).
    """
    status, e, _ = _point(resonance_cfg(cfg, omega), f"resonance sweep at ω = {float(omega):g}", ("orbit",),
                          check=check)
    return status, e["orbit"]


def resonance_sweep(cfg: DictConfig) -> dict:
    """Errors of small_parameter against exact orbits across the resonances ω → n (both sides)."""
    spec = cfg.regime_validity.resonance_sweep
    resonances = [float(n) for n in spec.resonances]
    distances = np.array([float(d) for d in spec.distances])
    fit_within, tol = float(spec.fit_within), float(spec.tolerance)
    sides = np.array([-1.0, 1.0])
    shape = (len(resonances), 2, len(distances))
    err = {k: np.full(shape, np.nan) for k in (*KEYS, "max")}
    status = np.empty(shape, dtype=object)
    omega = np.array(resonances)[:, None, None] + sides[:, None] * distances  # (resonance, side, distance)
    exponents = {k: np.full(len(resonances), np.nan) for k in (*KEYS, "max")}
    holds = np.full(len(resonances), np.nan)
    verdicts = []
    for i, n in enumerate(resonances):
        for j, m in np.ndindex(shape[1:]):
            status[i, j, m], e = resonance_point(cfg, omega[i, j, m])
            for k in KEYS:
                err[k][i, j, m] = e[k]
            err["max"][i, j, m] = max(e.values()) if status[i, j, m] == "ok" else np.nan
        small = np.abs(n * n - omega[i] ** 2)
        for k in exponents:
            exponents[k][i] = _growth_exponent(err[k][i], small, distances, fit_within)
        worst, computed, failed_at, refused_at = _worst_over_sides(status[i], err["max"][i])
        holds[i] = _holds_from(distances, worst, computed, tol)
        verdicts.append(_resonance_verdict(spec, n, {k: v[i] for k, v in exponents.items()}, holds[i], distances,
                                           worst, computed, sorted(distances[np.any(refused_at, axis=0)]),
                                           omega[i][failed_at]))
        log.info("%s", verdicts[-1])
    return {"resonances": resonances, "distances": distances, "sides": sides, "omega": omega, "errors": err,
            "status": status, "exponents": exponents, "holds": holds, "verdicts": verdicts,
            "fit_within": fit_within, "tolerance": tol, "epsilon": 1 / float(spec.r0)}


def _growth_exponent(y: np.ndarray, small: np.ndarray, distances: np.ndarray, fit_within: float) -> float:
    """s of error ∝ |n² − ω²|^−s, fitted over the points within ``fit_within`` of the resonance (NaN: too few)."""
    ok = (distances[None, :] <= fit_within) & np.isfinite(y) & (y > 0)
    return -float(np.polyfit(np.log(small[ok]), np.log(y[ok]), 1)[0]) if ok.sum() >= 3 else np.nan


def _worst_over_sides(status: np.ndarray, max_error: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per distance, the worst point over both sides (+inf where shooting failed, NaN where refused on both),
    whether any point was computed there, and where points failed or were refused."""
    failed_at = np.vectorize(lambda x: str(x).startswith("failed"))(status)
    refused_at = np.vectorize(lambda x: str(x).startswith("refused"))(status)
    worst = np.where(failed_at, np.inf, max_error)
    computed = ~np.all(refused_at, axis=0)
    worst = np.array([np.nanmax(worst[:, m]) if computed[m] else np.nan for m in range(worst.shape[1])])
    return worst, computed, failed_at, refused_at


def _holds_from(distances: np.ndarray, worst: np.ndarray, computed: np.ndarray, tol: float) -> float:
    """The smallest swept distance from which every computed point on both sides has error ≤ ``tol``."""
    holds = np.nan
    for m in np.argsort(distances)[::-1]:
        if not computed[m]:
            continue
        if not worst[m] <= tol:
            break
        holds = distances[m]
    return holds


def _resonance_verdict(spec: DictConfig, n: float, exponents: dict[str, float], holds: float, distances: np.ndarray,
                       worst: np.ndarray, computed: np.ndarray, refused_distances: list, failed_omegas: np.ndarray) -> str:
    """How the error grows towards the resonance ω = n, and from which distance the regime holds."""
    refused = [f"{d:g}" for d in refused_distances]
    failed = [f"{w:.4g}" for w in failed_omegas]
    fit_within, tol = float(spec.fit_within), float(spec.tolerance)
    far = worst[np.argmax(distances)]
    edge = worst[computed][np.argmin(distances[computed])] if computed.any() else np.nan
    return (f"{spec.regime} near the resonance ω = {n:g} (c/r0 = {1 / float(spec.r0):g}, b = {float(spec.b):g}, ω set "
            f"through a): max relative error against the exact orbit grows as |{n:g}² − ω²|^−s with s = "
            f"{exponents['max']:.2f} (p, q {exponents['pq']:.2f}, γ, γ' {exponents['gamma']:.2f}, "
            f"γ'' {exponents['gamma3']:.2f}; fitted for |ω − {n:g}| ≤ {fit_within:g}); {far:.2g} at |ω − {n:g}| = "
            f"{distances.max():g}, {edge:.2g} at the closest accepted point; the regime holds (error ≤ {tol:g}) for "
            f"|ω − {n:g}| ≥ {holds:g}; " + (f"refused at |ω − {n:g}| = {', '.join(refused)}" if refused else
                                            "no refused point")
            + (f"; shooting failed at ω = {', '.join(failed)}" if failed else ""))


def _resonance_dataset(sweep: dict) -> xr.Dataset:
    dims = ("resonance", "side", "resonance_distance")
    names = dict(LONG, max="all variables (max)")
    data = {"resonance_omega": (dims, sweep["omega"], {"units": "1", "long_name": "natural frequency ω of the body "
                                                       "(ω² = (C−A)(C−B)/(AB)), in units of the spin r0"}),
            "resonance_status": (dims, sweep["status"].astype(str), {"units": "1", "long_name": "ok, refused (reason) "
                                                                     "or failed (shooting did not converge)"}),
            "resonance_holds_from": ("resonance", sweep["holds"], {
                "units": "1", "long_name": f"smallest |ω − n| from which the max relative error is ≤ "
                                           f"{sweep['tolerance']:g} on both sides"})}
    for k, e in sweep["errors"].items():
        data[f"resonance_error_{k}_vs_orbit"] = (dims, e, {
            "units": "1", "long_name": f"max relative error of {names[k]} of small_parameter against the exact orbit "
                                       f"at c/r0 = {sweep['epsilon']:g}"})
        data[f"resonance_exponent_{k}"] = ("resonance", sweep["exponents"][k], {
            "units": "1", "long_name": f"fitted s in error of {names[k]} ∝ |n² − ω²|^−s "
                                       f"(|ω − n| ≤ {sweep['fit_within']:g})"})
    coords = {"resonance": ("resonance", np.array(sweep["resonances"]), {"units": "1", "long_name": "excluded resonance n (ω = n)"}),
              "side": ("side", sweep["sides"], {"units": "1", "long_name": "side of the resonance: sign of ω − n"}),
              "resonance_distance": ("resonance_distance", sweep["distances"], {"units": "1", "long_name": "|ω − n|"})}
    return xr.Dataset(data, coords=coords)


def _large_parameter_evidence(cfg: DictConfig, rows: list) -> str:
    """Printed (35) under μ = c/r0 against the full model: γ'' error over one τ period (Ismail (2021) report §3)."""
    errs = []
    mus = [float(v) for v in cfg.regime_validity.large_parameter["values"]]
    for mu in mus:
        sub = _cfg_for(cfg, "small_parameter", 1.0 / mu)
        with open_dict(sub):
            sub.initial.theta0 = float(np.arccos(0.5 / mu))
        scene = Scene.from_config(sub)
        s = nondimensional_scene(scene.system, "large_parameter")
        t = np.linspace(0, 2 * np.pi / s.r0, 201)
        approx = printed_reading_state(t, s)
        y0 = approx[0].copy()
        y0[3:6] /= np.linalg.norm(y0[3:6])
        y0 = np.concatenate([y0, scene.system.initial_state()[6:]])[: scene.system.state_size]
        exact = integrate(scene, y0, t, taylor=True)
        errs.append(float(np.abs(approx[:, 5] - exact[:, 5]).max()))
    rows.append(("large_parameter", mus, {"orbit": {"gamma3": errs}}, {}, ["evidence"] * len(mus)))
    verdict = ("large_parameter (paper's reading μ = c/r0): γ'' error of the printed formulas against the full model "
               + ", ".join(f"{e:.2f} at μ = {m:g}" for m, e in zip(mus, errs))
               + "; O(1) for every μ: no consistent expansion, the plugin refuses (use small_parameter)")
    log.info("%s", verdict)
    return verdict


def _dataset(rows, verdicts, cfg) -> xr.Dataset:
    data = {}
    for name, values, errs, orders, status in rows:
        dim = f"{name}_parameter"
        coords_attrs = {"units": "1", "long_name": f"expansion parameter of {name}"}
        data[dim] = (dim, np.array(values), coords_attrs)
        for against, table in errs.items():
            for k, e in table.items():
                data[f"{name}_error_{k}_vs_{against}"] = (dim, np.array(e, dtype=float), {
                    "units": "1", "long_name": f"max relative error of {LONG[k]} of {name} against the "
                                               f"{'exact periodic orbit' if against == 'orbit' else 'full model'}"})
        data[f"{name}_status"] = (dim, np.array(status), {"units": "1", "long_name": "ok, refused (reason) or evidence"})
        for k, v in orders.items():
            data[f"{name}_order_{k}"] = ((), v, {"units": "1", "long_name": f"fitted error order of {LONG[k]}"})
    ds = xr.Dataset(data)
    ds.attrs.update({"title": "validity of the expansion regimes",
                     "verdict": "\n".join(verdicts), "config": OmegaConf.to_yaml(cfg, resolve=True), **provenance()})
    return ds
