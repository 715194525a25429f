import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture
def cli(tmp_path):
    """Run the real ``gyrolab`` command in a subprocess (cwd = tmp_path)."""
    import subprocess

    def _run(*args, env_extra=None):
        env = dict(os.environ)
        env.update(env_extra or {})
        return subprocess.run([sys.executable, "-m", "gyrolab", *args], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=300)

    return _run
