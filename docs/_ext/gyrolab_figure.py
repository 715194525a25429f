"""``gyrolab-figure``: run a ``gyrolab ...`` command at build time and show the figure it wrote.

The gallery's images are therefore never stale: each is regenerated from the command printed beside it.
A command runs once per build (results are kept by the command's text in ``docs/_generated``, which is
git-ignored and emptied by a clean build).

    ```{gyrolab-figure} gyrolab time.end=20 output.figures=[state]
    :figure: state.png
    :width: 80%
    ```
"""
from __future__ import annotations

import hashlib
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.util.docutils import SphinxDirective

_RUN_CACHE: dict[str, Path] = {}


def _run(command: str) -> Path:
    """Run ``command`` (it must start with ``gyrolab``) in a fresh directory; return that directory."""
    if command in _RUN_CACHE:
        return _RUN_CACHE[command]
    words = shlex.split(command)
    if not words or words[0] != "gyrolab":
        raise ValueError(f"gyrolab-figure runs gyrolab commands only, not {command!r}")
    workdir = Path(tempfile.mkdtemp(prefix="gyrolab-figure-"))
    # a single run writes to hydra.run.dir, a sweep (-m) to hydra.sweep.dir: give both, one is unused
    argv = [sys.executable, "-m", "gyrolab", *words[1:], f"hydra.run.dir={workdir / 'run'}",
            f"hydra.sweep.dir={workdir / 'run'}"]
    done = subprocess.run(argv, cwd=workdir, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{command!r} failed (exit {done.returncode}): {done.stderr.strip()[-2000:]}")
    _RUN_CACHE[command] = workdir / "run"
    return workdir / "run"


class GyrolabFigure(SphinxDirective):
    required_arguments = 1
    final_argument_whitespace = True
    option_spec = {"figure": directives.unchanged_required, "width": directives.unchanged, "alt": directives.unchanged}

    def run(self) -> list[nodes.Node]:  # noqa: D102
        command = self.arguments[0].strip()
        figure_name = self.options["figure"]
        try:
            rundir = _run(command)
        except (RuntimeError, ValueError) as err:
            raise self.error(str(err)) from err
        found = sorted(rundir.rglob(figure_name))
        if not found:
            written = sorted(p.name for p in rundir.rglob("*.png"))
            raise self.error(f"{command!r} wrote no {figure_name} (it wrote: {', '.join(written) or 'no figure'})")
        key = hashlib.sha1(f"{command}|{figure_name}".encode()).hexdigest()[:12]
        generated = Path(self.env.srcdir) / "_generated"
        generated.mkdir(exist_ok=True)
        target = generated / f"{key}-{Path(figure_name).name}"
        shutil.copyfile(found[0], target)
        self.env.note_dependency(__file__)
        image = nodes.image(uri=f"/_generated/{target.name}", alt=self.options.get("alt", figure_name))
        if "width" in self.options:
            image["width"] = self.options["width"]
        block = nodes.literal_block(f"$ {command}", f"$ {command}", language="console")
        return [block, image]


def _remove_run_dirs(app, exception) -> None:
    for rundir in _RUN_CACHE.values():
        shutil.rmtree(rundir.parent, ignore_errors=True)
    _RUN_CACHE.clear()


def setup(app):
    app.add_directive("gyrolab-figure", GyrolabFigure)
    app.connect("build-finished", _remove_run_dirs)
    return {"version": "1", "parallel_read_safe": True}
