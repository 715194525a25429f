"""``gyrolab new-force NAME``: a new force-plugin package, a renamed copy of the example plugin.

The templates below are the files of ``examples/gyrolab-viscous-drag`` (a test checks that
``new_force_package("viscous_drag")`` reproduces that directory exactly, and runs its tests): linear drag, torque
−c ω, with its entry point, a README and tests that call ``gyrolab.testing.check_force``.
"""

from __future__ import annotations

import re
from pathlib import Path

from gyrolab.errors import ConfigError
from gyrolab.output.atomic import atomic_path

EXAMPLE = "viscous_drag"

TEMPLATES: dict[str, str] = {}

TEMPLATES['pyproject.toml'] = r'''[build-system]
requires = ["setuptools>=64"]
build-backend = "setuptools.build_meta"

[project]
name = "gyrolab-viscous-drag"
version = "0.1.0"
description = "Linear viscous drag torque -c omega: an example gyrolab force plugin"
requires-python = ">=3.10"
dependencies = ["gyrolab"]

[project.optional-dependencies]
test = ["pytest"]

[project.entry-points."gyrolab.forces"]
viscous_drag = "gyrolab_viscous_drag:ViscousDrag"

[tool.setuptools]
packages = ["gyrolab_viscous_drag"]
'''

TEMPLATES['README.md'] = r'''# gyrolab-viscous-drag

A force plugin for gyrolab, made by `gyrolab --new-force viscous_drag` from gyrolab's example
plugin. It starts as that example's torque, linear viscous drag −c ω: edit the torque, its
parameters, `preserves_area_integral` and the tests' exact solution (gyrolab's documentation,
"Adding a force plugin", explains each part).

    pip install -e .          # registers force "viscous_drag" through its entry point
    python -m pytest tests    # gyrolab.testing.check_force plus the exact solution
    gyrolab force=[uniform_gravity,viscous_drag] force.viscous_drag.coefficient=0.2
'''

TEMPLATES['gyrolab_viscous_drag/__init__.py'] = r'''"""Linear viscous drag on the body: torque −c ω (a gyrolab force plugin)."""

from dataclasses import dataclass

from gyrolab.contracts import Force
from gyrolab.errors import as_number


@dataclass
class ViscousDragConfig:                  # the config's schema (force.viscous_drag): its keys and their types,
    _target_: str = "gyrolab_viscous_drag:ViscousDrag"   # checked by Hydra while composing (gyrolab.engine.schemas)
    coefficient: float = 0.1


class ViscousDrag(Force):
    name = "viscous_drag"
    schema = ViscousDragConfig
    required_axes = frozenset()           # reference axes the torque reads: none (2 would be the vertical γ)
    preserves_area_integral = False       # −c ω has a component along γ: Iω·γ decays, it is no invariant

    def __init__(self, body, *, coefficient=0.1):   # keyword defaults are the plugin's config
        self.coefficient = as_number(coefficient, "force.viscous_drag.coefficient", nonnegative=True)

    def torque(self, omega, axes):        # plain numpy on 3-vectors: gyrolab compiles it
        return -self.coefficient * omega

    def attributes(self):                 # stored in run.nc as force_viscous_drag_coefficient
        return {"coefficient": self.coefficient}
    # no potential(axes): drag is not conservative, so the energy is not monitored
'''

TEMPLATES['tests/test_viscous_drag.py'] = r'''"""The plugin's own tests: gyrolab's contract kit, and the drag's exact solution."""

import numpy as np
import pytest

from gyrolab import run
from gyrolab.errors import ConfigError
from gyrolab.testing import check_force
from gyrolab_viscous_drag import ViscousDrag


def test_contract():
    check_force(ViscousDrag, coefficient=0.3)


def test_bad_coefficient_is_one_sentence():
    with pytest.raises(ConfigError, match="coefficient"):
        ViscousDrag(None, coefficient="abc")


@pytest.mark.parametrize("integrator", ["dop853", "dop853_numba"])
def test_spherical_body_decays_exponentially(integrator):
    # A = B = C = 1: ω̇ = −c ω, so ω(t) = ω0 exp(−c t) in every component (the installed plugin, compiled or not).
    ds = run(["force=[viscous_drag]", "force.viscous_drag.coefficient=0.3", "body.a=1", "body.b=1",
              f"integrator={integrator}", "integrator.rtol=1e-12", "integrator.atol=1e-12",
              "time.end=5", "time.n_output=51"])
    expected = np.array([0.1, -0.05, 5.0]) * np.exp(-0.3 * ds.time.values)[:, None]
    np.testing.assert_allclose(ds.omega.values, expected, rtol=1e-9, atol=1e-12)
    assert "area_integral" not in ds.attrs["monitored_invariants"].split()
'''


def names(name: str) -> dict[str, str]:
    """The example's spellings of its name, and the new plugin's: config name, class, package, distribution."""
    if not re.fullmatch(r"[a-z][a-z0-9]*(_[a-z0-9]+)*", name or ""):
        raise ConfigError(f"--new-force {name!r}: a force name is lower-case letters and digits in words joined by _ "
                          "(e.g. viscous_drag), as used in force=[NAME]")
    return {
        f"gyrolab-{EXAMPLE.replace('_', '-')}": f"gyrolab-{name.replace('_', '-')}",
        f"gyrolab_{EXAMPLE}": f"gyrolab_{name}",
        "".join(w.title() for w in EXAMPLE.split("_")): "".join(w.title() for w in name.split("_")),
        EXAMPLE: name,
    }


def render(name: str) -> dict[str, str]:
    """The new package's files (relative path -> text)."""
    spellings = names(name)
    files = {}
    for path, text in TEMPLATES.items():
        for old, new in spellings.items():
            path, text = path.replace(old, new), text.replace(old, new)
        files[path] = text
    return files


def new_force_package(name: str, parent: Path = Path(".")) -> Path:
    """Write ``gyrolab-NAME/`` under ``parent`` (refusing to overwrite) and return its path."""
    files = render(name)
    root = Path(parent) / f"gyrolab-{name.replace('_', '-')}"
    if root.exists():
        raise ConfigError(f"--new-force {name}: {str(root)!r} already exists; choose another name or directory")
    for path, text in files.items():
        with atomic_path(root / path) as tmp:
            tmp.write_text(text)
    return root
