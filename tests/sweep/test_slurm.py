"""gyrolab on a real SLURM: the submitit launcher preset and a dask-jobqueue SLURMCluster give the datasets
the same command gives locally.

The cluster is a single node on this machine (gyrolab.sweep.slurm_local: Debian's slurm-wlm and munge,
installed with apt-get when missing, started as root). Without root or apt-get the tests skip with the
reason (or fail, when GYROLAB_REQUIRE_SLURM is set); CI runs as root on Debian, so there they run. The
commands are read from docs/cluster.md ("SLURM, tested") and run as written; the expected datasets come from the same commands run locally (Hydra's basic
launcher, the batch in this process), never from a stored file.
"""

import contextlib
import os
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest
import xarray as xr

from gyrolab.sweep import slurm_local
from tests.helpers import (
    CODE_DEPENDENT_ATTRS,
    CODE_DEPENDENT_VARIABLES,
    REPO,
    VOLATILE_ATTRS,
    VOLATILE_VARIABLES,
    gyrolab,
    load,
)

pytestmark = [pytest.mark.slurm, pytest.mark.slow]  # a real cluster: end to end, seconds per test

# docs/cluster.md, "SLURM, tested": the tests run its blocks verbatim, so the page is the tested recipe.
DOCS = REPO / "docs" / "cluster.md"
# set (to anything but 0) where the SLURM tests must run, e.g. in CI: then a cluster that cannot start fails them
REQUIRED = "GYROLAB_REQUIRE_SLURM"


@pytest.fixture(scope="module")
def slurm():
    """A running single-node SLURM for this file's tests; its daemons are ended at teardown, pass or fail.

    Module scope, not session: under ``pytest -n N --dist loadfile`` this file runs in one worker, which may go
    on with other files; the cluster (and ``SLURM_CONF`` in the environment) ends with this file."""
    try:
        cluster = slurm_local.start()
    except slurm_local.Unavailable as reason:
        if os.environ.get(REQUIRED, "0") not in ("", "0"):
            pytest.fail(f"{REQUIRED} is set and {reason}")
        pytest.skip(str(reason))
    print(f"\nslurm: apt-get install {cluster.install_seconds:.1f} s, start {cluster.start_seconds:.1f} s "
          f"(node {cluster.node}, partition {cluster.partition}, {cluster.directory})")
    try:
        yield cluster
    finally:
        began = time.monotonic()
        cluster.stop()
        print(f"slurm: stopped in {time.monotonic() - began:.1f} s")


def recipe(name):
    """The fenced block of docs/cluster.md after ``<!-- tests/sweep/test_slurm.py runs the next block: NAME -->``."""
    marker = f"<!-- tests/sweep/test_slurm.py runs the next block: {name} -->"
    text = DOCS.read_text()
    assert marker in text, f"docs/cluster.md has no block {name!r}"
    block = text.split(marker, 1)[1].split("```", 2)[1]
    return block.split("\n", 1)[1]   # without the fence's language


def commands(name):
    """The recipe's command lines, each split as the shell splits it."""
    return [shlex.split(line) for line in recipe(name).splitlines() if line.strip()]


def run_line(command, cwd):
    """A recipe line ``gyrolab ...``, run with this Python (this venv's gyrolab)."""
    assert command[0] == "gyrolab", command
    return gyrolab(*command[1:], cwd=cwd)


@contextlib.contextmanager
def children_killed_after(seconds):
    """A hung recipe must not hang the suite: SIGKILL this process's children (the script's gyrolab) after
    ``seconds``, as ``subprocess.run(timeout=...)`` does for the commands run here."""
    def kill_children():
        for entry in Path("/proc").iterdir():
            with contextlib.suppress(OSError, ValueError, IndexError):
                if entry.name.isdigit() and int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1]) == os.getpid():
                    os.kill(int(entry.name), signal.SIGKILL)

    timer = threading.Timer(seconds, kill_children)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def assert_same_dataset(ran, expected):
    """The dataset at ``ran`` equals the one at ``expected`` exactly (values, coordinates, attributes), except
    for what says when and how long, and the code's provenance (git_*, job_id) where it differs: the working
    tree changed between the two runs (someone editing it meanwhile)."""
    a, b = (load(p) for p in (ran, expected))
    provenance = [k for k in (*CODE_DEPENDENT_ATTRS, *CODE_DEPENDENT_VARIABLES) if a.attrs.get(k) != b.attrs.get(k)
                  or (k in a.variables and k in b.variables and not a[k].equals(b[k]))]
    for ds in (a, b):
        ds.attrs = {k: v for k, v in ds.attrs.items() if k not in VOLATILE_ATTRS and k not in provenance}
    a, b = (ds.drop_vars([v for v in (*VOLATILE_VARIABLES, *provenance) if v in ds.variables]) for ds in (a, b))
    xr.testing.assert_identical(a, b)


def test_the_cluster_runs_a_job(slurm):
    """The fixture's cluster itself: a job step runs on the node, in the partition."""
    where = slurm.run("srun", "--partition", slurm.partition, "--ntasks", "1", "--time", "1",
                      "sh", "-c", "echo $SLURM_JOB_PARTITION $SLURMD_NODENAME", timeout=60)
    assert where.split() == [slurm.partition, slurm.node]


def test_submitit_launcher_sweep_equals_the_local_sweep(slurm, tmp_path):
    local, on_slurm = commands("sweep")
    assert "hydra/launcher=slurm" in on_slurm and f"hydra.launcher.partition={slurm.partition}" in on_slurm
    done = run_line(local, tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    began = time.monotonic()
    done = run_line(on_slurm, tmp_path)
    print(f"slurm: the sweep through submitit took {time.monotonic() - began:.1f} s")
    assert done.returncode == 0, done.stderr[-3000:] + slurm.logs()
    sweep = tmp_path / "slurm"
    # the jobs ran as SLURM jobs: submitit's folder has one log per SLURM array task
    assert len(list((sweep / ".submitit").rglob("*_log.out"))) == 2
    assert xr.load_dataset(sweep / "sweep.nc").attrs["sweep_launcher"] == "SlurmLauncher"
    assert_same_dataset(sweep / "sweep.nc", tmp_path / "local" / "sweep.nc")


def test_dask_jobqueue_batch_equals_the_local_batch(slurm, tmp_path, monkeypatch):
    local, on_slurm = commands("batch")
    assert on_slurm[:2] == ["python", "slurm_batch.py"]
    done = run_line(local, tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    # python slurm_batch.py ..., in this process, so that the test can ask its Dask scheduler what ran
    monkeypatch.chdir(tmp_path)   # SLURM writes the workers' slurm-JOBID.out here
    monkeypatch.setattr(sys, "argv", on_slurm[1:])
    script = {"__name__": "__main__"}
    began = time.monotonic()
    with pytest.raises(SystemExit) as exited, children_killed_after(300):
        exec(compile(recipe("slurm_batch.py"), "slurm_batch.py", "exec"), script)
    print(f"slurm: slurm_batch.py (2 SLURM jobs as Dask workers, the batch on them) took {time.monotonic() - began:.1f} s")
    assert exited.value.code == 0, slurm.logs()
    # the scheduler the script started timed gyrolab's chunk tasks (map_chunks' keys): they ran on its workers
    chunk_tasks = script["cluster"].scheduler.task_prefixes.get("gyrolab-chunk")
    assert chunk_tasks is not None and chunk_tasks.duration_average > 0
    assert_same_dataset(tmp_path / "slurm" / "sweep.nc", tmp_path / "local" / "sweep.nc")


def test_a_killed_sessions_cluster_is_ended_by_the_next_start(slurm):
    """A session killed with SIGKILL leaves its daemons running; the next start ends them and removes their
    directory, and starts although SLURM's default ports (6817, 6818) are taken."""
    base = Path(tempfile.mkdtemp(prefix="gyrolab-test-slurm-"))   # short: munged's socket path is in it
    code = ("import sys, time; from gyrolab.sweep import slurm_local; cluster = slurm_local.start(sys.argv[1]); "
            "print(cluster.directory, flush=True); time.sleep(600)")
    child = subprocess.Popen([sys.executable, "-c", code, str(base)], stdout=subprocess.PIPE, text=True)
    try:
        directory = Path(child.stdout.readline().strip())
        daemons = {name: int((directory / f"{name}.pid").read_text()) for name in ("munged", "slurmctld", "slurmd")}
    finally:
        child.kill()
        child.wait()
    assert all(slurm_local.alive(pid) for pid in daemons.values()), daemons   # left behind
    with contextlib.ExitStack() as stack:
        for port in (6817, 6818):
            taken = stack.enter_context(socket.socket())
            with contextlib.suppress(OSError):   # already taken by something else: as good
                taken.bind(("0.0.0.0", port))
                taken.listen()
        again = slurm_local.start(base)
    try:
        assert not directory.exists()
        assert not [name for name, pid in daemons.items() if slurm_local.alive(pid)]
        assert again.node_state() == "idle"
        assert os.environ["SLURM_CONF"] == str(again.conf)
    finally:
        again.stop()
        shutil.rmtree(base, ignore_errors=True)
    assert os.environ["SLURM_CONF"] == str(slurm.conf)   # the session's cluster is the clients' one again
    assert slurm.node_state() == "idle"
