"""The documentation site's sources: the Sphinx config exists, every public name is in the API reference,
and the README's links lead to pages that exist. (The build itself, warnings as errors, runs in .ci/run.)"""
import importlib
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"

# What is public: the names a script, a notebook or a plugin imports. Modules with __all__ give theirs.
PUBLIC = {
    "gyrolab": ["compose_scene", "Scene", "run"],
    "gyrolab.errors": ["GyrolabError", "ConfigError"],
    "gyrolab.batch.integrate": ["integrate_batch", "integrate_points", "integrate_arrays", "BatchSolution"],
    "gyrolab.contracts": "__all__",
    "gyrolab.testing": "__all__",
    "gyrolab.analysis.chaos": ["megno_run", "indicator_outputs", "poincare_section", "section_dataset",
                               "variational_settings"],
    "gyrolab.analysis.precession": "__all__",
    "gyrolab.physics.body": ["ModelUnits", "Body"],
    "gyrolab.physics.attitude": ["gamma_from_angles", "frame_from_angles", "nutation_and_spin", "euler_angles",
                                 "angles_from_states"],
    "gyrolab.physics.pendulum": ["kappa", "check_libration", "period", "swing"],
    "gyrolab.physics.lindstedt": ["Body", "LindstedtSeries", "series"],
    "gyrolab.physics.reference": ["fixed_point_reference"],
    "gyrolab.physics.gyrostat_body": ["GyrostatBody"],
    "gyrolab.physics.gyrostat_euler": ["GyrostatParameters", "kinematic_matrix", "mass_matrix", "gyroscopic_terms",
                                       "potential_gradient", "lagrange_equations", "rhs_euler_angles"],
}


def documented() -> dict[str, set[str]]:
    """module -> the members its ``automodule`` directive in docs/api.md lists."""
    text = (DOCS / "api.md").read_text()
    found: dict[str, set[str]] = {}
    for module, members in re.findall(r"\.\. automodule:: (\S+)\n\s+:members: ([^\n]+)", text):
        found.setdefault(module, set()).update(m.strip() for m in members.split(","))
    return found


def test_the_build_config_exists():
    conf = (DOCS / "conf.py").read_text()
    for extension in ("myst_parser", "numpydoc", "sphinx.ext.autodoc"):
        assert f'"{extension}"' in conf
    assert (DOCS / "index.md").exists() and (DOCS / "api.md").exists()


@pytest.mark.parametrize("module", sorted(PUBLIC))
def test_every_public_name_is_in_the_api_reference(module):
    names = PUBLIC[module]
    if names == "__all__":
        names = importlib.import_module(module).__all__
    missing = set(names) - documented().get(module, set())
    assert not missing, f"{module}: {sorted(missing)} missing from docs/api.md"


def test_every_documented_name_exists_and_has_a_docstring():
    for module, members in documented().items():
        imported = importlib.import_module(module)
        for name in members:
            assert (getattr(imported, name).__doc__ or "").strip(), f"{module}.{name} has no docstring"


def test_the_readme_links_lead_to_pages_that_exist():
    links = re.findall(r"\]\((docs/[^)#]+)", (REPO / "README.md").read_text())
    assert len(links) >= 15
    for link in links:
        assert (REPO / link).exists(), link
