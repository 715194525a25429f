"""Sphinx configuration for gyrolab's documentation site (``sphinx-build -W -b html docs docs/_build/html``).

Sphinx rather than MkDocs: the API reference is rendered from numpydoc docstrings, the format scipy,
xarray and heyoka.py use, and myst-parser lets the existing Markdown pages stay Markdown.
"""
import os
import re
import shutil
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
    "sphinx_copybutton",  # a copy button on every code block, the prompts ($, >>>) left out of the copy
    "gyrolab_figure",  # docs/_ext: runs a gyrolab command at build time and shows its figure
]

# Links into numpy, scipy, xarray and Hydra's config library (a docstring's :class:`xarray.Dataset` becomes a
# link). Intersphinx downloads each project's objects.inv when the build starts, and a download that fails is a
# warning, which -W turns into a failed build: on a machine without network (CI's, the developers') the build
# must not depend on it, and no package on PyPI ships these inventories to read locally. So the links are made
# only when GYROLAB_DOCS_INTERSPHINX=1 (a build for publishing, with network); without it the same references
# render as plain code. gyrolab's own inventory (docs/_build/html/objects.inv) is written either way.
# Hydra's own site (hydra.cc) is not a Sphinx site and publishes no inventory; the config types gyrolab's
# docstrings name (DictConfig) are OmegaConf's, whose documentation is.
intersphinx_mapping = {
    "python": ("https://docs.python.org/3", None),
    "numpy": ("https://numpy.org/doc/stable", None),
    "scipy": ("https://docs.scipy.org/doc/scipy", None),
    "xarray": ("https://docs.xarray.dev/en/stable", None),
    "omegaconf": ("https://omegaconf.readthedocs.io/en/latest", None),
}
if os.environ.get("GYROLAB_DOCS_INTERSPHINX") == "1":
    extensions.append("sphinx.ext.intersphinx")

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# Derivation scripts and their notes are records beside the pages, not pages of their own; _build is output.
exclude_patterns = ["_build", "_generated", "_templates", "derivations/scripts", "Thumbs.db", ".DS_Store"]
templates_path = ["_templates"]

# Headings get anchors so that pages may link to `page.md#a-section` (myst's GitHub-style slugs).
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "deflist", "colon_fence"]

# One page per public object: api.md lists the names in autosummary tables (:toctree: api), whose stub pages
# (docs/api/, git-ignored) are written at every build from _templates/autosummary.
autosummary_generate = True
autosummary_generate_overwrite = True
# every member of a documented class is indexed (a link target), documented or not; Sphinx 9 took the former
# "undoc-members": False as on all the same, so the setting now says what the build does
autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": True}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()

# pydata-sphinx-theme, the theme of numpy, scipy and xarray: the sections in the header, the section's pages on
# the left, the page's own table of contents on the right, a light and a dark mode.
html_theme = "pydata_sphinx_theme"
html_title = f"gyrolab {release}"
html_static_path = ["_static"]
html_css_files = ["gyrolab.css"]
html_theme_options = {
    "navbar_align": "left",
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
# a page without sub-pages has no left-hand sidebar: its width goes to the text
html_sidebars = {page: [] for page in ("index", "getting-started", "tutorial", "gallery")}
html_show_sourcelink = False
# the in-page contents of an API page list its members by their own names (run, not Scene.run)
toc_object_entries_show_parents = "hide"

# sphinx-copybutton: copy the command, not the prompt ("$ " in the gallery's console blocks, ">>> " in doctests),
# and of a block with prompts only the prompted lines (not a doctest's output); a block without prompts whole
copybutton_prompt_text = r"\$ |>>> |\.\.\. "
copybutton_prompt_is_regexp = True

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


# Every member gets an entry (undoc-members), so that it is indexed and can be linked to. A dataclass field
# (Scene.config, Body.g, ...) has no docstring of its own, so its entry would be empty: its description is in its
# class's numpydoc "Attributes" or "Parameters" section, and the entry gets it, with its type.
_DOUBLE_BACKTICKS = re.compile(r"``(.+?)``")


def _describe_bare_fields(app, domain, objtype, contentnode):
    if domain != "py" or objtype != "attribute" or contentnode.astext().strip():
        return
    import importlib
    import inspect

    from docutils import nodes
    from numpydoc.docscrape import NumpyDocString

    signature = contentnode.parent[0]
    module, path = signature.get("module"), signature.get("fullname", "").split(".")
    if not module or len(path) < 2:
        return
    try:
        owner = importlib.import_module(module)
        for part in path[:-1]:
            owner = getattr(owner, part)
        sections = NumpyDocString(inspect.getdoc(owner) or "")
        documented = [*sections["Attributes"], *sections["Parameters"]]
    except Exception:  # noqa: BLE001 - nothing importable or parseable: the entry stays as autodoc made it
        return
    for entry in documented:
        if entry.name == path[-1] and entry.desc:
            paragraph = nodes.paragraph()
            if entry.type:
                paragraph += nodes.emphasis(text=entry.type)
                paragraph += nodes.Text(": ")
            for i, piece in enumerate(_DOUBLE_BACKTICKS.split(" ".join(entry.desc))):
                paragraph += nodes.literal(text=piece) if i % 2 else nodes.Text(piece.replace("`", ""))
            contentnode += paragraph
            return


# A page added to docs/ (docs/cli.md, docs/datasets.md, ...) joins the user guide without editing a toctree:
# the UNLISTED-PAGES line of user-guide.md's toctree becomes every top-level page that no section page names.
SECTION_PAGES = ("index", "user-guide", "papers", "api")


def _unlisted_pages(app, docname, source):
    if docname != "user-guide":
        return
    listed = set(SECTION_PAGES)
    for page in SECTION_PAGES:
        listed |= set(re.findall(r"(?m)^(?:[^<\n]*<)?([\w-]+)>?$", (Path(app.srcdir) / f"{page}.md").read_text()))
    pages = sorted(path.stem for path in Path(app.srcdir).glob("*.md") if path.stem not in listed)
    source[0] = source[0].replace("UNLISTED-PAGES\n", "".join(f"{page}\n" for page in pages))


# autosummary rewrites the stubs of the names api.md lists; a stub of a name no longer listed would stay a page
def _remove_stale_stubs(app, config):
    shutil.rmtree(Path(app.srcdir) / "api", ignore_errors=True)


def setup(app):
    app.connect("object-description-transform", _describe_bare_fields)
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("source-read", _unlisted_pages)
    app.connect("config-inited", _remove_stale_stubs, priority=100)
