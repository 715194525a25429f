"""Helpers shared by several test modules: one place for each, imported from here (``tests.helpers``, with
``regimes``, ``accuracy`` and ``datasets`` for the regime bodies, the accuracy scenes and every dataset kind).
Fixtures, and the context managers tests enter like fixtures (``installed_distribution``, ``mounted_tmpfs``), are in
``tests/conftest.py``."""

import importlib.util
import subprocess
import sys
from pathlib import Path

import xarray as xr

from gyrolab import app
from gyrolab.engine.config import ConfigSource, use_source

#: the checkout: pyproject.toml, conf/, docs/, examples/, benchmarks/
REPO = Path(__file__).resolve().parents[2]
#: the force plugin of docs/writing-a-force.md, an installable package of its own
VISCOUS_DRAG = REPO / "examples" / "gyrolab-viscous-drag"

# What legitimately differs between two runs of the same command: when, how long, which launcher ...
VOLATILE_ATTRS = ("date_created", "history", "sweep_launcher")
VOLATILE_VARIABLES = ("integrator_wall_time",)
# ... and what follows the source tree, should it be edited between the two runs (attributes, or variables when a
# sweep's jobs ran under several code versions)
CODE_DEPENDENT_ATTRS = ("git_commit", "git_dirty", "git_diff_sha256")
CODE_DEPENDENT_VARIABLES = ("job_id",)


def gyrolab(*args, cwd=None, timeout=300, **options) -> subprocess.CompletedProcess:
    """``gyrolab ARGS`` in a subprocess with this Python (this venv's gyrolab), its output captured as text;
    ``options`` go to ``subprocess.run`` (env, preexec_fn, ...)."""
    return subprocess.run([sys.executable, "-m", "gyrolab", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, **options)


def gyrolab_in_process(monkeypatch, *args):
    """``gyrolab ARGS`` in this process: its exit code."""
    monkeypatch.setattr(sys, "argv", ["gyrolab", *args])
    try:
        app.main()
    except SystemExit as stop:
        return stop.code
    return 0


def run_main(argv, monkeypatch, capsys):
    """``gyrolab ARGV`` in this process: (exit code, stderr); the config source is the packaged one again after."""
    try:
        code = gyrolab_in_process(monkeypatch, *argv)
    finally:
        use_source(ConfigSource())
    return code, capsys.readouterr().err


def one_error_line(done: subprocess.CompletedProcess, *phrases, code=None) -> str:
    """The one ``gyrolab: error:`` line of a finished command, which exits with ``code`` (non-zero when not given),
    prints no traceback, and names each of ``phrases``."""
    errors = [line for line in done.stderr.splitlines() if line.startswith("gyrolab: error:")]
    if code is None:
        assert done.returncode not in (0, None), done.stderr[-2000:]
    else:
        assert done.returncode == code, done.stderr[-2000:]
    assert len(errors) == 1 and "Traceback" not in done.stderr, done.stderr[-2000:]
    for phrase in phrases:
        assert phrase in errors[0], errors[0]
    return errors[0]


def files_under(root) -> list[str]:
    """Every file and folder below ``root``, as sorted relative paths."""
    return sorted(str(p.relative_to(root)) for p in Path(root).rglob("*"))


def load(path) -> xr.Dataset:
    """A dataset as written: times and durations as the numbers stored."""
    return xr.load_dataset(path, decode_times=False, decode_timedelta=False)


def example_tests(folder: str, test_file: str):
    """The test module of an example package (``examples/FOLDER/tests/TEST_FILE``), imported from its path."""
    spec = importlib.util.spec_from_file_location(f"example_tests_{folder.replace('-', '_')}",
                                                  REPO / "examples" / folder / "tests" / test_file)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
