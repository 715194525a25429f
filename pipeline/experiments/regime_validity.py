"""Validity of each regime: error of the analytic solution against the exact orbit and the full model over a log range.

For each regime in ``regime_validity.regimes`` the scene is rebuilt with its spin r0 set so that the
regime's parameter takes each value of a log range (``regime_validity.<regime>.values``); points
outside the domain are recorded as refused (NaN, with the reason). Error orders are fitted inside
``fit_below`` and compared with the theory's; a verdict is written to the dataset attrs and the log.
``large_parameter`` is refused by design: its row evaluates the evidence instead (the printed
formulas under the paper's reading μ = c/r0 against the full model, γ'' error over one τ period).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf, open_dict

from pipeline.dataset import write_dataset
from pipeline.errors import ConfigError
from pipeline.experiments.regime_run import compute, errors, prepare
from pipeline.provenance import provenance

log = logging.getLogger(__name__)
KEYS = ("pq", "r", "gamma", "gamma3", "period")
LONG = {"pq": "p, q", "r": "r", "gamma": "γ, γ'", "gamma3": "γ''", "period": "period"}


def _cfg_for(cfg: DictConfig, regime: str, r0: float) -> DictConfig:
    from pipeline.config import compose_config

    base = OmegaConf.to_container(cfg, resolve=True)
    new = compose_config([f"regime={regime}", "regime.periods=1"])
    with open_dict(new):
        for section in ("system", "body", "initial", "force", "time", "output"):
            new[section] = base[section]
        for key, value in (base["regime_validity"].get(regime, {}).get("scene") or {}).items():
            OmegaConf.update(new, key, value, force_add=True)
        new.initial.r0 = float(r0)
        gamma = base["regime_validity"].get(regime, {}).get("Gamma")
        if gamma is not None:  # seed 000's γ0'' = Γ c/r0 (eq. 28): the tilt follows the spin
            new.initial.theta0 = float(np.arccos(min(1.0, gamma / r0)))
    return new


def _scales(regime, system) -> dict[str, float]:
    s = regime.scene(system)
    g = s.gamma0pp if regime.name == "resonant_omega3" else 1.0
    return {"pq": np.sqrt(g) * s.c if regime.name == "resonant_omega3" else s.c, "r": s.r0 * s.c,
            "gamma": g, "gamma3": g, "period": 1 / (s.r0 * s.c)}


def _r0_for(regime: str, value: float, cfg: DictConfig) -> float:
    if regime == "resonant_omega3":
        theta0 = float(cfg.regime_validity[regime].scene["initial.theta0"])
        return float(np.sqrt(np.cos(theta0)) / value)
    return 1.0 / value  # c/r0 in units of c


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    spec = cfg.regime_validity
    rows, verdicts = [], []
    for regime_name in spec.regimes:
        values = [float(v) for v in spec[regime_name]["values"]]
        fit_below = float(spec[regime_name]["fit_below"])
        errs = {against: {k: [] for k in KEYS} for against in ("orbit", "full")}
        status = []
        for value in values:
            sub = _cfg_for(cfg, regime_name, _r0_for(regime_name, value, cfg))
            try:
                scene, regime, _ = prepare(sub)
            except ConfigError as error:
                status.append(f"refused: {error}")
                for against in errs:
                    for k in KEYS:
                        errs[against][k].append(np.nan)
                continue
            status.append("ok")
            T = regime.period(scene.system)
            t = np.linspace(0, T, 241)
            result = compute(scene, regime, t)
            sc = _scales(regime, scene.system)
            for against in errs:
                e = errors(result, against)
                for k in KEYS:
                    errs[against][k].append(e.get(k, np.nan) / sc[k] if k in e else np.nan)
        orders = {}
        for k in KEYS:
            x, y = np.array(values), np.array(errs["orbit"][k])
            ok = (x <= fit_below) & np.isfinite(y) & (y > 0)
            orders[k] = float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0]) if ok.sum() >= 2 else np.nan
        theory = getattr(_regime_class(regime_name), "order", {})
        good = all(abs(orders[k] - theory[k]) <= 0.2 for k in KEYS if k in theory and np.isfinite(orders[k]))
        refused = [v for v, s in zip(values, status) if s != "ok"]
        verdict = (f"{regime_name}: fitted orders (parameter ≤ {fit_below:g}) "
                   + ", ".join(f"{LONG[k]} {orders[k]:.2f} (theory {theory.get(k, float('nan')):g})" for k in KEYS)
                   + f"; {'consistent with' if good else 'NOT consistent with'} the theory; "
                   + (f"refused outside the domain at {spec[regime_name]['parameter']} = "
                      + ", ".join(f'{v:g}' for v in refused) if refused else "no refused point"))
        log.info("%s", verdict)
        verdicts.append(verdict)
        rows.append((regime_name, values, errs, orders, status))
    if "large_parameter" in spec.get("evidence", []):
        verdicts.append(_large_parameter_evidence(cfg, rows))
    ds = _dataset(rows, verdicts, cfg)
    written = [write_dataset(ds, Path(out_dir) / "regime_validity.nc")]
    written.append(_plot(rows, Path(out_dir) / "figures" / "regime_validity.png"))
    return written


def _regime_class(name: str):
    from pipeline import registry

    return registry.load("regime", name)


def _large_parameter_evidence(cfg: DictConfig, rows: list) -> str:
    """Printed (35) under μ = c/r0 against the full model: γ'' error over one τ period (seed 000 report §3)."""
    from pipeline.scene import Scene
    from plugins.regimes.base import nondimensional_scene
    from plugins.regimes.large_parameter import printed_reading_state

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
        from plugins.integrators.compiled_solvers import Taylor

        model = scene.system.compiled_model()
        y0 = np.concatenate([y0, scene.system.initial_state()[6:]])[: scene.system.state_size]
        exact = Taylor(order=24, tol=1e-16).integrate(scene.system.rhs, t, y0, None, model).y
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
    ds.attrs.update({"title": "validity of the expansion regimes", "Conventions": "CF-1.8",
                     "verdict": "\n".join(verdicts), "config": OmegaConf.to_yaml(cfg, resolve=True), **provenance()})
    return ds


def _plot(rows, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, len(rows), figsize=(5.5 * len(rows), 4.8), squeeze=False)
    for ax, (name, values, errs, orders, _) in zip(axes[0], rows):
        for k, e in errs["orbit"].items():
            e = np.array(e, dtype=float)
            label = f"{LONG[k]}" + (f" (slope {orders[k]:.2f})" if k in orders and np.isfinite(orders[k]) else "")
            ax.loglog(values, np.where(e > 0, e, np.nan), "o-", label=label)
        ax.set_xlabel(f"expansion parameter of {name} [1]")
        ax.set_ylabel("max relative error against the exact orbit / full model [1]")
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.suptitle("validity of the expansion regimes (errors of the analytic solutions)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
