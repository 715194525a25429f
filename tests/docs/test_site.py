"""The documentation site's sources: the Sphinx config exists, every public name has its page in the API
reference, the pages teach the current command spellings, the README's links lead to pages that exist, and
the link check finds a broken link. (The build itself, warnings as errors, and the link check over the built
site run in .ci/run.)"""
import importlib
import re
import shutil
import subprocess
import sys

import pytest

from tests.helpers import REPO

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


#: the subcommands' spellings before ``gyrolab SUBCOMMAND`` (they still work; the pages teach the new ones)
OLD_SPELLINGS = re.compile(r"--(batch|plot|reproduce|aggregate|new-force)\b")


def documented() -> dict[str, set[str]]:
    """module -> the names the ``autosummary`` tables of docs/api*.md list under its ``automodule``."""
    found: dict[str, set[str]] = {}
    for page in sorted(DOCS.glob("api*.md")):
        module, in_table = None, False
        for line in page.read_text().splitlines():
            if line.startswith(".. automodule:: "):
                module, in_table = line.split()[-1], False
            elif line.startswith(".. autosummary::"):
                in_table = True
            elif in_table and line.startswith("   ") and not line.strip().startswith(":"):
                found.setdefault(module, set()).add(line.strip())
            elif in_table and line.strip() and not line.startswith(" "):
                in_table = False
    return found


def test_the_build_config_exists():
    conf = (DOCS / "conf.py").read_text()
    for extension in ("myst_parser", "numpydoc", "sphinx.ext.autodoc", "sphinx.ext.autosummary", "sphinx_copybutton"):
        assert f'"{extension}"' in conf
    assert 'html_theme = "pydata_sphinx_theme"' in conf
    assert (DOCS / "index.md").exists() and (DOCS / "api.md").exists()


def test_the_docs_extra_lists_what_conf_py_loads():
    pyproject = (REPO / "pyproject.toml").read_text()
    extra = re.search(r"^docs = \[(.*?)\]", pyproject, flags=re.M | re.S).group(1)
    for package in ("sphinx", "myst-parser", "numpydoc", "pydata-sphinx-theme", "sphinx-copybutton"):
        assert f'"{package}' in extra, package


def test_nothing_in_the_api_reference_is_left_out_of_the_index():
    for page in DOCS.glob("api*.md"):
        assert ":no-index:" not in page.read_text(), page.name
        assert ":noindex:" not in page.read_text(), page.name


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


def test_the_pages_teach_the_subcommand_spellings():
    found = []
    for page in sorted(DOCS.rglob("*.md")):
        if "_build" in page.parts:
            continue
        for paragraph in page.read_text().split("\n\n"):
            # cli.md's paragraph saying the old spellings keep working; an error message gyrolab prints, quoted
            if "keep working" in paragraph or "is not read from a config" in paragraph:
                continue
            found += [f"{page.relative_to(DOCS)}: {line.strip()}" for line in paragraph.splitlines()
                      if OLD_SPELLINGS.search(line)]
    assert not found, "\n".join(found)


def test_the_link_check_finds_a_broken_link_and_a_missing_anchor(tmp_path):
    (tmp_path / "index.html").write_text(
        '<html><body><h1 id="top-heading">x</h1><a href="page.html#there">ok</a><a href="#top-heading">ok</a>'
        '<a href="https://example.org/x">external</a><img src="_images/a.png"></body></html>')
    (tmp_path / "page.html").write_text('<html><body><section id="there"><a href="index.html#gone">x</a>'
                                        '<a href="missing.html">x</a></section></body></html>')
    (tmp_path / "_images").mkdir()
    done = subprocess.run([sys.executable, str(DOCS / "_ext" / "check_links.py"), str(tmp_path)],
                          capture_output=True, text=True)
    assert done.returncode == 1
    assert done.stdout.splitlines() == ["index.html:1: _images/a.png: no such file",
                                        "page.html:1: index.html#gone: no anchor #gone in index.html",
                                        "page.html:1: missing.html: no such file"]
    (tmp_path / "_images" / "a.png").write_bytes(b"")
    (tmp_path / "page.html").write_text('<html><body><section id="there">x</section></body></html>')
    assert subprocess.run([sys.executable, str(DOCS / "_ext" / "check_links.py"), str(tmp_path)]).returncode == 0


@pytest.mark.skipif(not any(shutil.which(b) for b in ("chromium", "chromium-browser", "google-chrome")),
                    reason="no Chromium (apt-get install chromium)")
def test_the_layout_check_finds_a_table_wider_than_the_column(tmp_path):
    column = '<div class="bd-article" style="width: 600px">{}</div>'
    (tmp_path / "wide.html").write_text("<html><body>" + column.format(
        '<table style="width: 900px"><tr><td>a</td></tr></table>') + "</body></html>")
    (tmp_path / "narrow.html").write_text("<html><body>" + column.format("<p>fits</p>") + "</body></html>")
    check = [sys.executable, str(DOCS / "_ext" / "check_layout.py"), str(tmp_path)]
    wide = subprocess.run([*check, "wide.html"], capture_output=True, text=True, timeout=300)
    assert wide.returncode == 1 and "wide.html: text column: table" in wide.stdout, wide.stdout + wide.stderr
    assert subprocess.run([*check, "narrow.html"], capture_output=True, timeout=300).returncode == 0
