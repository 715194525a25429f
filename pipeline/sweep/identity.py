"""A job's identity: a hash of its resolved config and of the code that runs it.

Two jobs with the same identity compute the same result (the integrators are
deterministic), so a sweep that is run again skips the jobs whose identity
already has a finished result in the sweep directory.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from omegaconf import DictConfig, OmegaConf

from gyrolab.output.provenance import provenance

#: bump when the meaning of an identity changes (invalidates every stored result)
SCHEME = "gyrolab-job-1"


def code_version(prov: dict[str, Any] | None = None) -> str:
    """gyrolab's version, git commit, the digest of uncommitted changes, and third-party plugin packages."""
    prov = provenance() if prov is None else prov
    parts = [f"gyrolab {prov['gyrolab_version']}", f"git {prov['git_commit']}"]
    if prov.get("git_dirty") == 1:
        parts.append(f"diff {prov.get('git_diff_sha256', '')[:16] or 'unknown'}")
    if prov.get("plugin_packages"):
        parts.append(f"plugins {prov['plugin_packages']}")
    return "; ".join(parts)


def canonical_config(cfg: DictConfig | dict[str, Any]) -> str:
    """The resolved config (without Hydra's own node) as sorted, compact JSON."""
    if isinstance(cfg, DictConfig):
        plain = OmegaConf.to_container(OmegaConf.masked_copy(cfg, [k for k in cfg if k != "hydra"]), resolve=True)
    else:
        plain = {k: v for k, v in cfg.items() if k != "hydra"}
    return json.dumps(plain, sort_keys=True, separators=(",", ":"), allow_nan=True)


def job_identity(cfg: DictConfig | dict[str, Any], code: str | None = None) -> str:
    """20 hex digits of sha256 over (scheme, code version, canonical config)."""
    text = "\n".join((SCHEME, code_version() if code is None else code, canonical_config(cfg)))
    return hashlib.sha256(text.encode()).hexdigest()[:20]
