"""``gyrolab --reproduce PATH/run.nc``: rerun a dataset's stored config and say whether the result is identical.

Identical means every data variable and coordinate is equal bit for bit.
Otherwise the report names each differing variable with its largest
absolute difference. Provenance that differs (commit, library versions,
platform) is listed as a hint to why.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.engine.budget import check_budget
from gyrolab.engine.safety import check_stored_config
from gyrolab.errors import GyrolabError
from gyrolab.output.foreign import FOREIGN_ERRORS, load_run, not_gyrolabs
from gyrolab.output.provenance import provenance
from gyrolab.engine.scene import Scene

#: provenance attributes worth comparing (the wall time differs by nature)
PROVENANCE_KEYS = ("gyrolab_version", "git_commit", "git_dirty", "git_diff_sha256", "python_version", "platform",
                   "plugin_packages")


@dataclass
class Comparison:
    same: list[str] = field(default_factory=list)
    differ: list[str] = field(default_factory=list)          # one sentence per differing variable
    provenance: list[str] = field(default_factory=list)      # stored vs now, where they differ

    @property
    def identical(self) -> bool:
        return not self.differ


def stored_config(stored: xr.Dataset, where: str = "the dataset's config attribute") -> DictConfig:
    """The config a dataset stores, read with a safe YAML loader and checked as any config is.

    A dataset may come from someone else: its config is parsed without YAML tags,
    may not contain interpolations (gyrolab stores it resolved), may name only
    registered plugins (``gyrolab.engine.safety``) and must be within the budget.
    """
    cfg = check_stored_config(stored.attrs["config"], where)
    plain = OmegaConf.to_container(cfg)
    time = plain.get("time")
    if isinstance(time, dict) and {"start", "end", "n_output"} <= set(time) and (
            isinstance(time["n_output"], int) or time["n_output"] == "auto"):
        probe = cfg.copy()
        probe.time.n_output = 2
        check_budget(plain, Scene.from_config(probe).system.initial_state().size)
    return cfg


def rerun(stored: xr.Dataset) -> xr.Dataset:
    return Scene.from_config(stored_config(stored)).run()


def compare(stored: xr.Dataset, new: xr.Dataset) -> Comparison:
    result = Comparison()
    for kind, names_old, names_new in (("coordinate", stored.coords, new.coords),
                                       ("variable", stored.data_vars, new.data_vars)):
        for name in sorted(set(names_old) | set(names_new)):
            if name not in names_new:
                result.differ.append(f"{kind} {name}: in the dataset, not in the rerun")
            elif name not in names_old:
                result.differ.append(f"{kind} {name}: in the rerun, not in the dataset")
            else:
                message = _difference(stored[name], new[name])
                (result.differ.append(f"{kind} {name}: {message}") if message else result.same.append(name))
    now = provenance()
    for key in PROVENANCE_KEYS:
        then = stored.attrs.get(key)
        if then is not None and str(then) != str(now.get(key)):
            result.provenance.append(f"{key}: {then} then, {now.get(key)} now")
    for key, then in stored.attrs.items():
        if key.startswith("version_") and str(then) != str(now.get(key)):
            result.provenance.append(f"{key[len('version_'):]}: {then} then, {now.get(key, 'not installed')} now")
    return result


def _difference(old: xr.DataArray, new: xr.DataArray) -> str:
    """'' if bit-for-bit equal, else one phrase saying how they differ."""
    a, b = np.asarray(old.values), np.asarray(new.values)
    if old.dims != new.dims or a.shape != b.shape:
        return f"shape {dict(zip(old.dims, a.shape))} in the dataset, {dict(zip(new.dims, b.shape))} in the rerun"
    if a.dtype.kind in "fc" and b.dtype.kind in "fc":
        a, b = a.astype(np.float64), b.astype(np.float64)
        if a.tobytes() == b.tobytes():  # the bits in C order, whatever either array's memory layout
            return ""
        nan_a, nan_b = np.isnan(a), np.isnan(b)
        if (nan_a != nan_b).any():
            return f"NaN at {int((nan_a != nan_b).sum())} places where the other has a number"
        delta = np.abs(a - b)
        delta[nan_a] = 0.0
        scale = float(np.max(np.abs(a))) or 1.0
        worst = np.unravel_index(int(np.argmax(delta)), delta.shape)
        where = ", ".join(f"{d}={old[d].values[i]}" if d in old.coords else f"{d}[{i}]"
                          for d, i in zip(old.dims, worst))
        return (f"max |Δ| = {float(delta[worst]):.3g} (relative to max |value| {float(delta[worst]) / scale:.3g}) "
                f"at {where or 'the only value'}; {int((delta > 0).sum())} of {delta.size} values differ")
    if a.dtype == b.dtype and np.array_equal(a, b):
        return ""
    if a.dtype.kind in "iub" and b.dtype.kind in "iub":
        return f"max |Δ| = {int(np.max(np.abs(a.astype(np.int64) - b.astype(np.int64))))}"
    equal = np.asarray(a.astype(str) == b.astype(str))
    return "" if equal.all() else f"{int((~equal).sum())} of {equal.size} values differ"


def reproduce(path: Path) -> tuple[Comparison, xr.Dataset]:
    stored = load_run(path)
    expected = "a run.nc that gyrolab wrote"
    try:
        scene = Scene.from_config(stored_config(stored))
    except GyrolabError:
        raise
    except FOREIGN_ERRORS as error:  # a stored config without what gyrolab's runs always have
        raise not_gyrolabs(path, error, expected) from None
    new = scene.run()
    try:
        return compare(stored, new), stored
    except GyrolabError:
        raise
    except FOREIGN_ERRORS as error:  # variables that gyrolab's runs always have are missing
        raise not_gyrolabs(path, error, expected) from None


def report(path: Path, comparison: Comparison, stored: xr.Dataset) -> list[str]:
    head = (f"reproducing {path} ({stored.attrs.get('title', '?')}; {stored.attrs.get('integrator', '?')}, "
            f"{stored.sizes.get('time', '?')} output times)")
    lines = [head]
    lines += [f"  provenance differs: {p}" for p in comparison.provenance]
    if comparison.identical:
        lines.append(f"identical: {len(comparison.same)} variables and coordinates equal bit for bit "
                     f"({', '.join(comparison.same)})")
    else:
        lines += [f"  {d}" for d in comparison.differ]
        lines.append(f"NOT identical: {len(comparison.differ)} of {len(comparison.differ) + len(comparison.same)} "
                     "variables and coordinates differ")
    return lines
