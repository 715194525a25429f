"""Sphinx configuration for gyrolab's documentation site (``sphinx-build -W -b html docs docs/_build/html``).

Sphinx rather than MkDocs: the API reference is rendered from numpydoc docstrings, the format scipy,
xarray and heyoka.py use, and myst-parser lets the existing Markdown pages stay Markdown.
"""
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent / "_ext"))

import gyrolab  # noqa: E402

project = "gyrolab"
author = "the gyrolab developers"
copyright = "2026, the gyrolab developers"  # noqa: A001 (Sphinx's name for the setting)
release = gyrolab.__version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "gyrolab_figure",  # docs/_ext: runs a gyrolab command at build time and shows its figure
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# Derivation scripts and their notes are records beside the pages, not pages of their own; _build is output.
exclude_patterns = ["_build", "_generated", "derivations/scripts", "Thumbs.db", ".DS_Store"]

# Headings get anchors so that pages may link to `page.md#a-section` (myst's GitHub-style slugs).
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "deflist", "colon_fence"]

autosummary_generate = False
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()

html_theme = "alabaster"
html_title = f"gyrolab {release}"
html_static_path: list[str] = []

# gyrolab's docstrings write absolute values and norms as |x| (they are read in terminals first), which
# reStructuredText would take for substitutions. Escape a bar outside ``literals`` and literal blocks; a line
# that starts with a bar (a table row) is left alone.
_LITERAL = re.compile(r"(``.*?``)")


def _escape_bars(app, what, name, obj, options, lines):
    in_block, block_indent = False, 0
    for i, line in enumerate(lines):
        stripped = line.strip()
        if in_block and stripped and not line.startswith(" " * (block_indent + 1)):
            in_block = False
        if not in_block and stripped.endswith("::"):
            in_block, block_indent = True, len(line) - len(line.lstrip())
            continue
        if in_block or "|" not in line or stripped.startswith("|"):
            continue
        pieces = _LITERAL.split(line)
        lines[i] = "".join(p if p.startswith("``") else p.replace("|", r"\|") for p in pieces)


# A page added to docs/ (docs/cli.md, docs/datasets.md, ...) joins the user guide without editing index.md:
# the UNLISTED-PAGES line of its user-guide toctree becomes every top-level page index.md does not name.
def _unlisted_pages(app, docname, source):
    if docname != "index":
        return
    listed = set(re.findall(r"(?m)^([\w-]+)$", source[0]))
    pages = sorted(path.stem for path in Path(app.srcdir).glob("*.md") if path.stem not in listed | {"index"})
    source[0] = source[0].replace("UNLISTED-PAGES\n", "".join(f"{page}\n" for page in pages))


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("source-read", _unlisted_pages)
