"""Render built pages in headless Chromium at 1280 px and report what is wider than its column.

    python docs/_ext/check_layout.py [docs/_build/html] [PAGE.html ...]

Run after ``sphinx-build``. Each page (by default the key pages below; ``all`` for every page) is opened in
headless Chromium with a window 1280 px wide; a small script, added to a temporary copy of the page, lists
every element of the text column whose right edge passes the column's (a clipped table, a code line that
runs under the right-hand sidebar), every element of a sidebar that passes the sidebar's, and whether the
page is wider than the window (a horizontal scroll bar). Exit status 0 when nothing overflows, 1 with one
line per element, 2 when Chromium is not installed (``apt-get install chromium``: ``.ci/run`` skips the check
then and says so).
"""
from __future__ import annotations

import html
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

WIDTH, HEIGHT = 1280, 900
#: the pages a reader sees first, and those with the widest tables and command blocks
KEY_PAGES = ["index.html", "getting-started.html", "tutorial.html", "gallery.html", "cli.html", "plugins.html",
             "cluster.html", "batch.html", "datasets.html", "integrators.html", "performance.html", "api.html",
             "api/gyrolab.Scene.html", "api/gyrolab.compose_scene.html"]
BROWSERS = ("chromium", "chromium-browser", "google-chrome")

PROBE = """<script>
window.addEventListener('load', () => { setTimeout(() => {
  const out = [];
  const describe = (el) => el.tagName.toLowerCase() + (el.className && typeof el.className === 'string'
      ? '.' + el.className.trim().split(/\\s+/).join('.') : '') + ' "' +
      (el.textContent || '').trim().replace(/\\s+/g, ' ').slice(0, 50) + '"';
  const over = (box, selector, what) => {
    if (!box) return;
    const limit = box.getBoundingClientRect().right + 1;
    for (const el of box.querySelectorAll(selector)) {
      const r = el.getBoundingClientRect();
      if (r.width > 0 && r.right > limit)
        out.push(what + ': ' + describe(el) + ' ends at ' + Math.round(r.right) + ' px, the column at ' +
                 Math.round(limit - 1) + ' px');
    }
  };
  over(document.querySelector('.bd-article'), 'table, pre, img, p, li, h1, h2, h3, h4, dt, code', 'text column');
  over(document.querySelector('.bd-sidebar-primary'), 'a, code', 'left sidebar');
  over(document.querySelector('.bd-sidebar-secondary'), 'a, code', 'right sidebar');
  const page = document.documentElement;
  if (page.scrollWidth > page.clientWidth + 1)
    out.push('page: ' + page.scrollWidth + ' px wide in a ' + page.clientWidth + ' px window');
  const result = document.createElement('pre');
  result.id = 'gyrolab-layout-probe';
  result.textContent = 'PROBED\\n' + out.join('\\n');
  document.body.appendChild(result);
}, 200); });
</script>"""


def browser() -> str | None:
    return next((found for name in BROWSERS if (found := shutil.which(name))), None)


def overflows(page: Path, chromium: str) -> list[str]:
    """What overflows on ``page`` (a built HTML file) at WIDTH px; ['not rendered: ...'] when Chromium failed."""
    # the copy sits beside the page, so that its relative links (CSS, scripts, images) still resolve
    with tempfile.NamedTemporaryFile("w", suffix=".html", dir=page.parent, prefix=".layout-probe-",
                                     delete=False, encoding="utf-8") as copy:
        copy.write(page.read_text(encoding="utf-8").replace("</body>", PROBE + "</body>", 1))
    try:
        done = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                               f"--window-size={WIDTH},{HEIGHT}", "--virtual-time-budget=5000", "--dump-dom",
                               Path(copy.name).as_uri()], capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return ["not rendered: Chromium took more than 120 s"]
    finally:
        Path(copy.name).unlink(missing_ok=True)
    found = re.search(r'<pre id="gyrolab-layout-probe">(.*?)</pre>', done.stdout, re.S)
    if not found or not html.unescape(found[1]).startswith("PROBED"):
        return [f"not rendered (Chromium exit {done.returncode}): {done.stderr.strip()[-300:]}"]
    return [line for line in html.unescape(found[1]).splitlines()[1:] if line]


def main(argv: list[str]) -> int:
    root = Path(argv[0]) if argv else Path(__file__).resolve().parents[1] / "_build" / "html"
    names = argv[1:] or KEY_PAGES
    if names == ["all"]:
        names = [str(p.relative_to(root)) for p in sorted(root.rglob("*.html"))
                 if p.relative_to(root).parts[0] not in ("_static", "_sources")]
    chromium = browser()
    if chromium is None:
        print("check_layout: no Chromium (apt-get install chromium); pages not rendered", file=sys.stderr)
        return 2
    problems = []
    for name in names:
        if not (root / name).is_file():
            problems.append(f"{name}: no such page in {root}")
            continue
        problems += [f"{name}: {line}" for line in overflows(root / name, chromium)]
    for problem in problems:
        print(problem)
    print(f"check_layout: {len(names)} pages at {WIDTH} px, {len(problems)} overflowing", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
