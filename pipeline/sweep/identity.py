"""A job's identity: a hash of its resolved config and of the code it loads, gyrolab's own (version, git trees of its
code folders, uncommitted changes) and the third-party plugins the config names; a sweep run again skips the jobs
whose identity has a settled result (docs/cluster.md, "Resuming a multirun").
"""

from __future__ import annotations

import hashlib
import json
from functools import cache
from importlib.util import find_spec
from pathlib import Path
from typing import Any

from omegaconf import DictConfig, OmegaConf

from gyrolab.contracts.registry import _normalise, plugin_entry_points
from gyrolab.output.provenance import code_tree, provenance

#: bump when the meaning of an identity changes (invalidates every stored result)
SCHEME = "gyrolab-job-2"


def code_version() -> str:
    """gyrolab's own code: its version, the git trees of its code (or the commit) and the digest of uncommitted
    changes to it."""
    prov = provenance()
    parts = [f"gyrolab {prov['gyrolab_version']}"]
    tree = code_tree() if prov["git_commit"] != "unknown" else ""
    parts.append(f"code {tree}" if tree else f"git {prov['git_commit']}")
    if prov.get("git_dirty") == 1:
        parts.append(f"diff {prov.get('git_diff_sha256', '')[:16] or 'unknown'}")
    return "; ".join(parts)


def plain_config(cfg: DictConfig | dict[str, Any]) -> dict[str, Any]:
    """The resolved config without Hydra's own node, as plain data."""
    if isinstance(cfg, DictConfig):
        return OmegaConf.to_container(OmegaConf.masked_copy(cfg, [k for k in cfg if k != "hydra"]), resolve=True)
    return {k: v for k, v in cfg.items() if k != "hydra"}


def canonical_config(cfg: DictConfig | dict[str, Any]) -> str:
    """The resolved config (without Hydra's own node) as sorted, compact JSON."""
    return json.dumps(plain_config(cfg), sort_keys=True, separators=(",", ":"), allow_nan=True)


def plugins_named(cfg: DictConfig | dict[str, Any]) -> str:
    """The third-party plugins a config names (system, forces, integrator, regime: every ``_target_`` outside
    gyrolab), each as 'distribution==version module@digest', sorted; '' when it names only gyrolab's own."""
    return " ".join(sorted({_plugin_code(t) for t in _targets(plain_config(cfg))} - {""}))


def job_code(cfg: DictConfig | dict[str, Any], code: str | None = None) -> str:
    """The code a job of config ``cfg`` loads: gyrolab's (``code``, default ``code_version()``) and its plugins'."""
    plugins = plugins_named(cfg)
    code = code_version() if code is None else code
    return f"{code}; plugins {plugins}" if plugins else code


def job_identity(cfg: DictConfig | dict[str, Any], code: str | None = None) -> str:
    """20 hex digits of sha256 over (scheme, the code the job loads, canonical config); ``code`` is gyrolab's own
    code version (``code_version()`` when not given), the plugins the config names are added here."""
    plain = plain_config(cfg)
    text = "\n".join((SCHEME, job_code(plain, code), canonical_config(plain)))
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def _targets(node: Any) -> set[str]:
    """Every ``_target_`` string in a plain config."""
    if isinstance(node, dict):
        own = {str(node["_target_"])} if isinstance(node.get("_target_"), str) else set()
        return own.union(*map(_targets, node.values()))
    return set().union(*map(_targets, node)) if isinstance(node, list) else set()


@cache
def _plugin_code(target: str) -> str:
    """'' for gyrolab's own classes; else 'distribution==version module@digest' of the plugin's module (the digest of
    its package's Python files: an editable install's new commit counts even when its version stays)."""
    target = _normalise(target)
    module = target.rpartition(".")[0]
    if not module or module == "gyrolab" or module.startswith("gyrolab."):
        return ""
    dist = next((f"{ep.dist.metadata['Name']}=={ep.dist.version} " for ep in plugin_entry_points()
                 if _normalise(ep.value) == target and getattr(ep, "dist", None) is not None), "")
    try:
        digest = _source_digest(module)
    except Exception:  # noqa: BLE001 - not importable here: the job refuses it; its name still counts
        digest = "unknown"
    return f"{dist}{module}@{digest}"


#: a plugin's package folder larger than this is counted by the module's own file only
MAX_PACKAGE_FILES = 500


def _source_digest(module: str) -> str:
    """12 hex digits of sha256 over the Python files of the package that holds ``module`` (its folder, with
    subfolders: the helpers the plugin imports), or of the module's own file when it is not in a package."""
    spec = find_spec(module)
    origin = Path(spec.origin)  # type: ignore[union-attr, arg-type]
    in_package = origin.name == "__init__.py" or "." in module
    files = sorted(origin.parent.rglob("*.py")) if in_package else [origin]
    if len(files) > MAX_PACKAGE_FILES:
        files = [origin]
    digest = hashlib.sha256()
    for path in files:
        digest.update(f"\0{path.relative_to(origin.parent).as_posix()}\0".encode() + path.read_bytes())
    return digest.hexdigest()[:12]
