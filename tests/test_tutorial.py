"""docs/tutorial.md runs end to end: every bash and python block, in order, in an empty directory."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

TUTORIAL = Path(__file__).resolve().parent.parent / "docs" / "tutorial.md"
BLOCK = re.compile(r"^```(bash|python)\n(.*?)^```", re.S | re.M)


def blocks() -> list[tuple[str, str]]:
    return BLOCK.findall(TUTORIAL.read_text())


def test_tutorial_has_blocks_of_both_kinds():
    kinds = {kind for kind, _ in blocks()}
    assert kinds == {"bash", "python"}


@pytest.mark.slow
def test_tutorial_runs_end_to_end(tmp_path):
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"  # this environment's gyrolab
    try:
        for number, (kind, code) in enumerate(blocks(), start=1):
            command = ["bash", "-euo", "pipefail", "-c", code] if kind == "bash" else [sys.executable, "-c", code]
            done = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
            assert done.returncode == 0, f"block {number} ({kind}) failed:\n{code}\n--- stderr ---\n{done.stderr[-3000:]}"
    finally:  # the tutorial installs its plugin package: leave the environment as it was
        subprocess.run([sys.executable, "-m", "pip", "uninstall", "-q", "-y", "gyrolab-my-drag"], capture_output=True,
                       timeout=120)
