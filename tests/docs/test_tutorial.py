"""docs/tutorial.md runs end to end: every bash and python block, in order, in an empty directory.

The tutorial installs a plugin package; it runs in an overlay environment of its own (a venv that sees this
environment's packages), so the install lands there and never in the environment the suite runs in.
"""

import os
import re
import site
import subprocess
import sys
import venv
from pathlib import Path

import pytest

from tests.helpers import REPO

TUTORIAL = REPO / "docs" / "tutorial.md"
BLOCK = re.compile(r"^```(bash|python)\n(.*?)^```", re.S | re.M)


def blocks() -> list[tuple[str, str]]:
    return BLOCK.findall(TUTORIAL.read_text())


def test_tutorial_has_blocks_of_both_kinds():
    kinds = {kind for kind, _ in blocks()}
    assert kinds == {"bash", "python"}


def overlay_environment(root: Path) -> Path:
    """A venv at ``root`` whose Python also sees this environment's site-packages (gyrolab, pip, pytest, ...) and
    has a ``gyrolab`` command; what is installed into it stays in it. Returns its bin directory."""
    venv.EnvBuilder(with_pip=False).create(root)
    bin_dir = root / ("Scripts" if os.name == "nt" else "bin")
    python = bin_dir / "python"
    purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    # an "import" line of a .pth runs at start-up: addsitedir also runs the parent's .pth files (the editable
    # install's finder among them), which a plain path line would not
    parents = [p for p in site.getsitepackages() if Path(p).is_dir()]
    Path(purelib, "_gyrolab_parent_env.pth").write_text(
        "import site; " + "; ".join(f"site.addsitedir({p!r})" for p in parents) + "\n")
    commands = {"gyrolab": "from gyrolab.app import main\nmain()\n",
                "pip": "import sys\nfrom pip._internal.cli.main import main\nsys.exit(main())\n"}
    for name, body in commands.items():  # the overlay's own, so that `pip install` installs into the overlay
        (bin_dir / name).write_text(f"#!{python}\n{body}")
        (bin_dir / name).chmod(0o755)
    return bin_dir


@pytest.mark.slow
def test_tutorial_runs_end_to_end(tmp_path):
    bin_dir = overlay_environment(tmp_path / "overlay")
    work = tmp_path / "work"
    work.mkdir()
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"  # the overlay's python, pip and gyrolab first
    env.pop("PYTHONHOME", None)
    for number, (kind, code) in enumerate(blocks(), start=1):
        command = ["bash", "-euo", "pipefail", "-c", code] if kind == "bash" else [str(bin_dir / "python"), "-c", code]
        done = subprocess.run(command, cwd=work, env=env, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, f"block {number} ({kind}) failed:\n{code}\n--- stderr ---\n{done.stderr[-3000:]}"
    # the plugin went into the overlay, not into the environment running the suite
    listed = subprocess.run([sys.executable, "-m", "pip", "list"], capture_output=True, text=True).stdout
    assert "gyrolab-my-drag" not in listed and "gyrolab_my_drag" not in listed
