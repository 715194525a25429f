"""Check the built site's internal links: every relative ``href`` and ``src`` of every page leads somewhere.

    python docs/_ext/check_links.py [docs/_build/html]

Run after ``sphinx-build`` (``.ci/run`` does). For every ``*.html`` under the build directory, each relative
``href`` (``<a>``, ``<link>``) and ``src`` (``<img>``, ``<script>``, ``<source>``, ``<iframe>``) must name a file
that exists in the build, and a ``#fragment`` must be an ``id`` (or an ``<a name>``) in the page it names; a
bare ``#`` and ``#top`` are fine. Links with a scheme (``https:``, ``mailto:``, ``data:``) or to another host
(``//host``) are external and not checked here (the build machine has no network). Sphinx itself warns
about a cross-reference it cannot resolve, but not about a Markdown link to a file the build does not copy,
an anchor that a heading rename removed, or an image path typed by hand: this script catches those.

Exit status 0 when nothing is broken; 1 with one line per broken link (page: target, and why).
"""
from __future__ import annotations

import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

#: attributes that load or lead to another resource, by tag
LINK_ATTRIBUTES = {"a": ("href",), "link": ("href",), "img": ("src",), "script": ("src",), "source": ("src",),
                   "iframe": ("src",), "video": ("src", "poster"), "audio": ("src",)}
#: fragments every page has in effect (the browser's top of the page)
ALWAYS_THERE = {"", "top"}
#: folders of the build that hold no pages (pydata-sphinx-theme copies a Jinja macro file into _static)
SKIPPED = {"_static", "_sources"}


class _Page(HTMLParser):
    """The ids (anchors) a page defines and the links it makes."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[tuple[str, int]] = []   # (url, line)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if values.get("id"):
            self.ids.add(values["id"])
        if tag == "a" and values.get("name"):
            self.ids.add(values["name"])
        for attribute in LINK_ATTRIBUTES.get(tag, ()):
            url = values.get(attribute)
            if url is not None:
                self.links.append((url.strip(), self.getpos()[0]))
        if tag == "img" and values.get("srcset"):
            for candidate in values["srcset"].split(","):
                if candidate.strip():
                    self.links.append((candidate.split()[0], self.getpos()[0]))

    handle_startendtag = handle_starttag


def _parse(path: Path, cache: dict[Path, _Page]) -> _Page:
    if path not in cache:
        page = _Page()
        page.feed(path.read_text(encoding="utf-8", errors="replace"))
        page.close()
        cache[path] = page
    return cache[path]


def _pages(root: Path) -> list[Path]:
    """The built pages: every ``*.html`` but the theme's templates and sources copied into ``_static``."""
    return [path for path in sorted(root.rglob("*.html")) if path.relative_to(root).parts[0] not in SKIPPED]


def broken_links(root: Path) -> list[str]:
    """One line per broken internal link or image under ``root`` (a built HTML site)."""
    root = root.resolve()
    pages: dict[Path, _Page] = {}
    problems = []
    for path in _pages(root):
        page = _parse(path, pages)
        for url, line in page.links:
            parts = urlsplit(url)
            if parts.scheme or parts.netloc or url.startswith("//"):
                continue   # external: https:, mailto:, data:, javascript:, //host
            where = f"{path.relative_to(root)}:{line}"
            target = path if not parts.path else (path.parent / unquote(parts.path)).resolve()
            if parts.path.startswith("/"):
                problems.append(f"{where}: {url}: an absolute path (the site must work from any folder)")
                continue
            if not target.is_relative_to(root):
                problems.append(f"{where}: {url}: leads out of the built site")
                continue
            if target.is_dir():
                target = target / "index.html"
            if not target.is_file():
                problems.append(f"{where}: {url}: no such file")
                continue
            fragment = unquote(parts.fragment)
            if fragment in ALWAYS_THERE or target.suffix != ".html":
                continue
            if fragment not in _parse(target, pages).ids:
                problems.append(f"{where}: {url}: no anchor #{fragment} in {target.relative_to(root)}")
    return problems


def main(argv: list[str]) -> int:
    root = Path(argv[0]) if argv else Path(__file__).resolve().parents[1] / "_build" / "html"
    if not (root / "index.html").is_file():
        print(f"check_links: {root} holds no built site (index.html); run sphinx-build first", file=sys.stderr)
        return 2
    problems = broken_links(root)
    for problem in problems:
        print(problem)
    count = len(_pages(root.resolve()))
    print(f"check_links: {count} pages, {len(problems)} broken internal links or images", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
