"""gyrolab on a real SLURM: the submitit launcher preset and a dask-jobqueue SLURMCluster give the datasets
the same command gives locally.

The cluster is a single node on this machine (tests/slurm_cluster.py: Debian's slurm-wlm and munge,
installed with apt-get when missing, started as root). Without root or apt-get the tests skip with the
reason; CI runs as root on Debian, so there they run. The commands are docs/cluster.md's recipe
("SLURM, tested"); the expected datasets come from the same commands run locally (Hydra's basic
launcher, the batch in this process), never from a stored file.
"""

import contextlib
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr

import slurm_cluster

pytestmark = pytest.mark.slurm

# The recipe's sweep (docs/cluster.md): two tiny scenes, one SLURM array task each.
SWEEP = ["initial.r0=1,2", "time.end=1", "time.n_output=11", "output.figures=false"]
# The recipe's batch: four points in four chunks, so that both workers get chunks.
BATCH = ["integrator=rk4_numba", "initial.r0=1,2,3,4", "time.end=1", "time.n_output=11", "batch.chunk=1"]
# What legitimately differs between two runs of the same command: when, how long, which launcher.
VOLATILE_ATTRS = ("date_created", "history", "sweep_launcher")
VOLATILE_VARIABLES = ("integrator_wall_time",)


@pytest.fixture(scope="session")
def slurm(tmp_path_factory):
    """A running single-node SLURM for the session; its daemons are ended at teardown, pass or fail."""
    try:
        cluster = slurm_cluster.start()
    except slurm_cluster.Unavailable as reason:
        pytest.skip(str(reason))
    print(f"\nslurm: apt-get install {cluster.install_seconds:.1f} s, start {cluster.start_seconds:.1f} s "
          f"(node {cluster.node}, partition {cluster.partition}, {cluster.directory})")
    try:
        yield cluster
    finally:
        began = time.monotonic()
        cluster.stop()
        print(f"slurm: stopped in {time.monotonic() - began:.1f} s")


def gyrolab(*args, cwd, env=None):
    return subprocess.run([sys.executable, "-m", "gyrolab", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env=env)


def comparable(path):
    ds = xr.load_dataset(path, decode_times=False, decode_timedelta=False)
    ds = ds.drop_vars([v for v in VOLATILE_VARIABLES if v in ds.variables])
    for key in VOLATILE_ATTRS:
        ds.attrs.pop(key, None)
    return ds


def test_the_cluster_runs_a_job(slurm):
    """The fixture's cluster itself: a job step runs on the node, in the partition."""
    where = slurm.run("srun", "--partition", slurm.partition, "--ntasks", "1", "--time", "1",
                      "sh", "-c", "echo $SLURM_JOB_PARTITION $SLURMD_NODENAME", timeout=60)
    assert where.split() == [slurm.partition, slurm.node]


def test_submitit_launcher_sweep_equals_the_local_sweep(slurm, tmp_path):
    for where in ("local", "slurm"):
        (tmp_path / where).mkdir()
    local = gyrolab("-m", *SWEEP, "hydra.sweep.dir=sweep", cwd=tmp_path / "local")
    assert local.returncode == 0, local.stderr[-3000:]
    began = time.monotonic()
    on_slurm = gyrolab("-m", "hydra/launcher=slurm", f"hydra.launcher.partition={slurm.partition}",
                       "hydra.launcher.mem_gb=1", *SWEEP, "hydra.sweep.dir=sweep",
                       cwd=tmp_path / "slurm")
    print(f"slurm: the sweep through submitit took {time.monotonic() - began:.1f} s")
    assert on_slurm.returncode == 0, on_slurm.stderr[-3000:] + slurm.logs()
    # the jobs ran as SLURM jobs, not here: submitit's logs carry SLURM's job ids
    logs = list((tmp_path / "slurm" / "sweep" / ".submitit").rglob("*_log.out"))
    assert len(logs) == 2, logs
    ran = comparable(tmp_path / "slurm" / "sweep" / "sweep.nc")
    assert xr.load_dataset(tmp_path / "slurm" / "sweep" / "sweep.nc").attrs["sweep_launcher"] == "SlurmLauncher"
    xr.testing.assert_identical(ran, comparable(tmp_path / "local" / "sweep" / "sweep.nc"))


def test_dask_jobqueue_batch_equals_the_local_batch(slurm, tmp_path):
    from dask_jobqueue import SLURMCluster
    from distributed import Client

    local = gyrolab("--batch", *BATCH, "hydra.sweep.dir=local", cwd=tmp_path)
    assert local.returncode == 0, local.stderr[-3000:]
    began = time.monotonic()
    # docs/cluster.md, "SLURM, tested": the same lines, with this test cluster's partition
    cluster = SLURMCluster(
        cores=1, processes=1, memory="2GB",               # one single-threaded worker per SLURM job
        walltime="00:30:00", queue=slurm.partition,
        python=sys.executable,                            # the workers run this Python (this venv)
        job_script_prologue=["export NUMBA_NUM_THREADS=1 OMP_NUM_THREADS=1"],
        scheduler_options={"dashboard_address": None},
    )
    try:
        cluster.scale(jobs=2)
        with Client(cluster) as client:
            client.wait_for_workers(2, timeout=120)
        started = time.monotonic() - began
        env = {**os.environ, "DASK_SCHEDULER_ADDRESS": cluster.scheduler_address}
        on_slurm = gyrolab("--batch", *BATCH, "hydra.sweep.dir=slurm", cwd=tmp_path, env=env)
        with Client(cluster) as client:   # the chunks ran on the SLURM jobs' workers
            workers = client.scheduler_info()["workers"]
        # the scheduler timed gyrolab's chunk tasks (map_chunks' keys) on those workers
        chunk_tasks = cluster.scheduler.task_prefixes.get("gyrolab-chunk")
    finally:
        cluster.close()
    print(f"slurm: SLURMCluster with 2 workers up in {started:.1f} s, batch on it {time.monotonic() - began - started:.1f} s")
    assert on_slurm.returncode == 0, on_slurm.stderr[-3000:] + slurm.logs()
    assert len(workers) == 2
    assert chunk_tasks is not None and chunk_tasks.duration_average > 0
    xr.testing.assert_identical(comparable(tmp_path / "slurm" / "sweep.nc"), comparable(tmp_path / "local" / "sweep.nc"))


def test_a_killed_sessions_cluster_is_ended_by_the_next_start(slurm, tmp_path):
    """A session killed with SIGKILL leaves its daemons running; the next start ends them and removes their
    directory, and starts although SLURM's default ports (6817, 6818) are taken."""
    code = ("import sys, time, slurm_cluster; cluster = slurm_cluster.start(sys.argv[1]); "
            "print(cluster.directory, flush=True); time.sleep(600)")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).parent), os.environ.get("PYTHONPATH", "")])}
    child = subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], stdout=subprocess.PIPE, text=True, env=env)
    try:
        directory = Path(child.stdout.readline().strip())
        daemons = {name: int((directory / f"{name}.pid").read_text()) for name in ("munged", "slurmctld", "slurmd")}
    finally:
        child.kill()
        child.wait()
    assert all(slurm_cluster.alive(pid) for pid in daemons.values()), daemons   # left behind
    with contextlib.ExitStack() as stack:
        for port in (6817, 6818):
            taken = stack.enter_context(socket.socket())
            with contextlib.suppress(OSError):   # already taken by something else: as good
                taken.bind(("0.0.0.0", port))
                taken.listen()
        again = slurm_cluster.start(tmp_path)
    try:
        assert not directory.exists()
        assert not [name for name, pid in daemons.items() if slurm_cluster.alive(pid)]
        assert again.node_state() == "idle"
        assert os.environ["SLURM_CONF"] == str(again.conf)
    finally:
        again.stop()
    assert os.environ["SLURM_CONF"] == str(slurm.conf)   # the session's cluster is the clients' one again
    assert slurm.node_state() == "idle"
