"""Nothing in a directory or dataset someone sent you can write outside it, run code, hang or exhaust memory.

One test (or a few) per class of issue 33: planted links and locks, pickle folders others can write, tampered
stored configs and datasets, hostile ``--animate`` inputs, a second sweep into a sweep directory, signals and
floods. Hostile directories are built by hand; the CLI runs only where its behaviour is what is tested.
"""

from __future__ import annotations

import errno
import logging
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from gyrolab.errors import ConfigError
from gyrolab.output import trust
from gyrolab.output.atomic import atomic_open
from gyrolab.output.foreign import load_dataset, load_run
from gyrolab.output.lock import LOCK_NAME, try_lock, unlock, writing_in
from tests.helpers import one_error_line

SECRET = "the user's own file\n"


@pytest.fixture(scope="module")
def sweep_template(tmp_path_factory):
    """A real two-job sweep directory (made once; each test copies it)."""
    root = tmp_path_factory.mktemp("template")
    done = subprocess.run([sys.executable, "-m", "gyrolab", "-m", "initial.r0=1,2", "time.end=1", "time.n_output=20",
                           "output.figures=false", "hydra.sweep.dir=sweep"], cwd=root, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    return root / "sweep"


@pytest.fixture
def sweep(sweep_template, tmp_path):
    shutil.copytree(sweep_template, tmp_path / "sweep", symlinks=True)
    return tmp_path / "sweep"


@pytest.fixture
def victim(tmp_path):
    path = tmp_path / "outside" / "victim.txt"
    path.parent.mkdir()
    path.write_text(SECRET)
    return path


# ----------------------------------------------------------------------------- 1. planted links and locks


def test_a_planted_lock_link_is_refused_and_its_target_untouched(tmp_path, victim):
    run = tmp_path / "run"
    run.mkdir()
    (run / LOCK_NAME).symlink_to(victim)
    with pytest.raises(ConfigError, match="is a symbolic link"):
        try_lock(run)
    assert victim.read_text() == SECRET


def test_a_lock_never_truncates_a_file_it_did_not_create(tmp_path, victim):
    run = tmp_path / "run"
    run.mkdir()
    os.link(victim, run / LOCK_NAME)  # a hard link: a regular file, but not gyrolab's
    with writing_in(run):
        assert victim.read_text() == SECRET
    assert victim.read_text() == SECRET
    assert try_lock(tmp_path / "fresh")  # a lock it creates holds its owner's line
    assert (tmp_path / "fresh" / LOCK_NAME).read_text().startswith("pid ")
    unlock(tmp_path / "fresh")


@pytest.mark.parametrize("name", [LOCK_NAME, "gyrolab.log", "run.nc", "job.json", ".hydra", "figures"])
def test_a_planted_link_in_a_run_directory_is_refused(name, tmp_path, victim):
    run = tmp_path / "run"
    run.mkdir()
    (run / name).symlink_to(victim if "." in name.strip(".") else victim.parent)
    with pytest.raises(ConfigError, match=f"{name}' is a symbolic link"):
        trust.check_tree(run)


def test_a_linked_job_directory_and_a_fifo_are_refused_in_a_sweep(tmp_path):
    sweep = tmp_path / "sweep"
    (sweep / "0").mkdir(parents=True)
    os.mkfifo(sweep / "0" / "run.nc")
    with pytest.raises(ConfigError, match="a device, a FIFO or a socket"):
        trust.check_tree(sweep, sweep=True)
    (sweep / "0" / "run.nc").unlink()
    (sweep / "1").symlink_to(tmp_path)
    with pytest.raises(ConfigError, match="1' is a symbolic link"):
        trust.check_tree(sweep, sweep=True)


def test_figures_through_a_link_are_refused_and_nothing_lands_outside(tmp_path, victim):
    run = tmp_path / "run"
    run.mkdir()
    (run / "figures").symlink_to(victim.parent)
    with pytest.raises(ConfigError, match="symbolic link"), atomic_open(run / "figures" / "a.png") as out:
        out.write("x")
    assert sorted(p.name for p in victim.parent.iterdir()) == ["victim.txt"]


def test_an_atomic_write_never_replaces_a_device_or_a_link(tmp_path, victim):
    os.mkfifo(tmp_path / "fifo.nc")
    (tmp_path / "link.nc").symlink_to(victim)
    for name in ("fifo.nc", "link.nc"):
        with pytest.raises(ConfigError, match="not a regular file"), atomic_open(tmp_path / name) as out:
            out.write("x")
    assert (tmp_path / "link.nc").is_symlink() and victim.read_text() == SECRET
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_aggregate_refuses_a_planted_lock_link_in_one_sentence(sweep, victim, cli):
    (sweep / LOCK_NAME).symlink_to(victim)
    one_error_line(cli("aggregate", str(sweep)), "is a symbolic link")
    assert victim.read_text() == SECRET


def test_a_run_into_a_directory_with_a_linked_log_is_refused_before_anything(tmp_path, victim, cli):
    run = tmp_path / "run"
    run.mkdir()
    (run / "gyrolab.log").symlink_to(victim)
    one_error_line(cli("time.end=1", f"hydra.run.dir={run}"), "gyrolab.log' is a symbolic link")
    assert victim.read_text() == SECRET
    assert sorted(p.name for p in run.iterdir()) == ["gyrolab.log"]


def test_an_output_named_by_the_user_is_refused_when_it_is_not_a_regular_file(tmp_path):
    os.mkfifo(tmp_path / "device")
    with pytest.raises(ConfigError, match="-o '.*device' exists and is a device"):
        trust.check_output_target(tmp_path / "device", "-o")
    assert trust.check_output_target(tmp_path / "new.gif", "-o") == tmp_path / "new.gif"


# ----------------------------------------------------------------------------- 2. pickles from private folders


def test_a_pickle_folder_others_can_write_is_refused_and_a_new_one_is_private(tmp_path):
    created = trust.private_dir(tmp_path / "sweep" / ".submitit", "submitit's folder")
    assert created.stat().st_mode & 0o777 == 0o700
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    with pytest.raises(ConfigError, match="may be written by others"):
        trust.private_dir(shared, "submitit's folder")
    (tmp_path / "link").symlink_to(created)
    with pytest.raises(ConfigError, match="symbolic link"):
        trust.private_dir(tmp_path / "link", "submitit's folder")


def test_a_sweep_refuses_a_submitit_folder_others_can_write(tmp_path):
    from omegaconf import OmegaConf

    from gyrolab.sweep.sweeper import claim

    sweep = tmp_path / "sweep"
    (sweep / ".submitit").mkdir(parents=True)
    (sweep / ".submitit").chmod(0o777)
    config = OmegaConf.create({"hydra": {"overrides": {"task": ["initial.r0=1,2"]}, "sweeper": {"params": None},
                                         "launcher": {"submitit_folder": f"{sweep}/.submitit/%j"}}})
    with pytest.raises(ConfigError, match="submitit's folder .* may be written by others"):
        claim(sweep, config)
    assert not (sweep / "multirun.yaml").exists()


def test_numbas_cache_folder_writable_by_anyone_is_refused(tmp_path, monkeypatch):
    import numba

    import gyrolab.kernels.compiler  # noqa: F401 - sets numba's cache folder on import

    folder = tmp_path / "shared" / "numba-cache"
    folder.mkdir(parents=True)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(folder))
    trust.check_kernel_cache()   # the user's own folder
    folder.parent.chmod(0o777)   # a shared temporary folder without the sticky bit
    with pytest.raises(ConfigError, match="numba's cache folder .* may be written by anyone"):
        trust.check_kernel_cache()


# ----------------------------------------------------------------------------- 3. stored configs and datasets

BOMB = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
    f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n"
    for i in range(9))


@pytest.mark.parametrize("text, phrase", [
    (BOMB, "expand to more than"),
    ("a: " + "[" * 3000 + "]" * 3000 + "\n", "nested more than"),
    ("hydra: !!python/object/apply:os.system ['touch PWNED']\n", "refuses tags"),
    ("x" * (2 * 1024 * 1024), "larger than"),
])
def test_a_stored_config_is_checked_as_a_user_file(text, phrase):
    from gyrolab.engine.safety import check_stored_config

    tic = time.perf_counter()
    with pytest.raises(ConfigError, match=phrase):
        check_stored_config(text, "the dataset's config attribute")
    assert time.perf_counter() - tic < 2


@pytest.mark.parametrize("edit, phrase", [
    (lambda text: BOMB + text, "expand to more than"),
    (lambda text: text.replace("initial.r0=1,2", "initial.r0=range(0,1e9,1)"), "makes 1e\\+09 jobs, beyond"),
    (lambda text: "x: !!python/object/apply:os.system ['touch PWNED']\n" + text, "refuses tags"),
])
def test_a_tampered_multirun_yaml_is_refused_by_aggregate(edit, phrase, sweep):
    from gyrolab.sweep.aggregate import aggregate_sweep

    saved = sweep / "multirun.yaml"
    saved.write_text(edit(saved.read_text()))
    tic = time.perf_counter()
    with pytest.raises(ConfigError, match=phrase):
        aggregate_sweep(sweep)
    assert time.perf_counter() - tic < 3


def test_a_bomb_in_a_jobs_stored_config_refuses_plot_of_the_sweep(sweep):
    from gyrolab.figures.redraw import redraw

    with netCDF4.Dataset(sweep / "0" / "run.nc", "a") as nc:
        nc.config = BOMB
    tic = time.perf_counter()
    with pytest.raises(ConfigError, match="expand to more than"):
        redraw(sweep)
    assert time.perf_counter() - tic < 3 and not (sweep / "0" / "figures").exists()


def test_hydras_experimental_rerun_which_unpickles_is_refused(tmp_path, monkeypatch):
    from gyrolab.app import preflight
    from gyrolab.app.parser import parse_command_line

    monkeypatch.chdir(tmp_path)
    (tmp_path / "config.pickle").write_bytes(b"cos\nsystem\n(S'touch PWNED'\ntR.")
    with pytest.raises(ConfigError, match="would load a pickle"):
        preflight(parse_command_line(["--experimental-rerun", "config.pickle"])[1])
    assert not (tmp_path / "PWNED").exists()


@pytest.mark.parametrize("content", ["[" * 100_000, '{"run": "../../outside/victim.txt", "job_id": "x", '
                                                    '"status": "finished", "overrides": [], "code_version": ""}'])
def test_a_hostile_job_record_is_no_record(content, tmp_path):
    from gyrolab.sweep.record import read_record

    (tmp_path / "job.json").write_text(content)
    assert read_record(tmp_path) is None


def test_a_dataset_declaring_more_than_it_holds_is_refused_before_reading(tmp_path):
    path = tmp_path / "run.nc"
    with netCDF4.Dataset(path, "w") as nc:   # 6 kB declaring 10^8 time steps
        nc.createDimension("time", 10**8)
        nc.createDimension("axis", 3)
        nc.createVariable("time", "f8", ("time",))
        nc.createVariable("omega", "f8", ("time", "axis"))
        nc.config = "time: {end: 1}"
    assert path.stat().st_size < 64 * 1024
    with pytest.raises(ConfigError, match=r"declares 3.0 GiB of data in a file of .*at most 4×"):
        load_run(path)


def test_text_where_gyrolab_writes_numbers_is_refused(tmp_path):
    path = tmp_path / "run.nc"
    xr.Dataset({"omega": (("time", "axis"), np.array([["a", "b", "c"]] * 3, dtype=object))},
               coords={"time": [0.0, 1.0, 2.0]}, attrs={"config": "time: {end: 1}"}).to_netcdf(path)
    with pytest.raises(ConfigError, match="variable 'omega' holds text where gyrolab writes numbers"):
        load_dataset(path, "a run.nc that gyrolab wrote")


# ----------------------------------------------------------------------------- --animate


def _run_dataset(path: Path, **changes) -> Path:
    n = 5
    alpha = np.tile([1.0, 0.0, 0.0], (n, 1))
    gamma = np.tile([0.0, 0.0, 1.0], (n, 1))
    variables = {"alpha": (("time", "axis"), alpha), "gamma": (("time", "axis"), gamma)}
    variables.update(changes)
    path.parent.mkdir(parents=True, exist_ok=True)
    xr.Dataset(variables, coords={"time": np.linspace(0, 1, n)}, attrs={"config": "time: {end: 1}"}).to_netcdf(path)
    return path


@pytest.mark.parametrize("changes, phrase", [
    ({"alpha": (("time", "axis"), np.full((5, 3), np.nan))}, "alpha holds NaN or inf"),
    ({"gamma": (("time",), np.zeros(5))}, "not the \\(time, 3\\) numbers"),
    ({"alpha": (("time", "axis"), np.array([["x"] * 3] * 5, dtype=object))}, "holds text"),
])
def test_animate_refuses_a_hostile_run_in_one_sentence(changes, phrase, tmp_path):
    from gyrolab.figures.animation import animate

    path = _run_dataset(tmp_path / "run" / "run.nc", **changes)
    with pytest.raises(ConfigError, match=phrase):
        animate(path, frames=2)
    assert not (tmp_path / "run" / "figures").exists()


def test_animate_refuses_a_sweep_a_figures_file_and_a_device_output(sweep, tmp_path):
    from gyrolab.figures.animation import animate

    with pytest.raises(ConfigError, match="is a sweep dataset, not a run"):
        animate(sweep / "sweep.nc", frames=2)
    run = _run_dataset(tmp_path / "run" / "run.nc")
    (run.parent / "figures").write_text("a file")
    with pytest.raises(ConfigError, match="figures' is a file, where gyrolab keeps a folder"):
        animate(run, frames=2)
    os.mkfifo(tmp_path / "device")
    with pytest.raises(ConfigError, match="exists and is a device"):
        animate(run, output=tmp_path / "device", frames=2)
    assert (tmp_path / "device").exists() and not (tmp_path / "device").is_file()


# ----------------------------------------------------------------------------- 4. one sweep directory, one sweep


def test_a_second_different_sweep_is_refused_and_the_first_kept(sweep, cli):
    before = (sweep / "sweep.nc").read_bytes()
    done = cli("-m", "initial.r0=1,3", "time.end=1", "time.n_output=20", "output.figures=false",
               f"hydra.sweep.dir={sweep}")
    one_error_line(done, "holds another sweep")
    assert (sweep / "sweep.nc").read_bytes() == before
    assert sorted(p.name for p in sweep.iterdir() if not p.name.startswith(".")) == ["0", "1", "multirun.yaml",
                                                                                    "sweep.nc"]


def _claim_after(barrier, sweep: Path, values: str, outcomes) -> None:
    from omegaconf import OmegaConf

    from gyrolab.sweep.sweeper import claim

    config = OmegaConf.create({"hydra": {"overrides": {"task": [f"initial.r0={values}"]}, "sweeper": {"params": None}}})
    barrier.wait()
    try:
        claim(sweep, config)
        outcomes.put((values, "claimed"))
    except ConfigError as error:
        outcomes.put((values, str(error)))


def test_two_different_sweeps_started_at_once_cannot_interleave(tmp_path):
    import multiprocessing

    context = multiprocessing.get_context("fork")
    barrier, outcomes = context.Barrier(2), context.Queue()
    workers = [context.Process(target=_claim_after, args=(barrier, tmp_path / "sweep", values, outcomes))
               for values in ("1,2", "3,4")]
    for worker in workers:
        worker.start()
    results = dict(outcomes.get(timeout=30) for _ in workers)
    for worker in workers:
        worker.join(timeout=30)
    winner = next(values for values, outcome in results.items() if outcome == "claimed")
    loser = "3,4" if winner == "1,2" else "1,2"
    assert "holds another sweep" in results[loser]
    assert f"initial.r0={winner}" in (tmp_path / "sweep" / "multirun.yaml").read_text()


def test_the_same_sweep_resumes_and_a_batch_directory_is_refused(sweep, tmp_path):
    from omegaconf import OmegaConf

    from gyrolab.sweep.sweeper import claim

    stored = OmegaConf.load(sweep / "multirun.yaml")
    claim(sweep, stored)   # the same sweep: claimed again (resumed)
    (sweep / "multirun.yaml").unlink()
    with pytest.raises(ConfigError, match="holds a sweep.nc of a batch"):
        claim(sweep, stored)


# ----------------------------------------------------------------------------- 5. signals, floods, types, umask


def test_sigterm_is_one_line_exit_143_and_nothing_half_written(tmp_path):
    process = subprocess.Popen([sys.executable, "-m", "gyrolab", "time.end=100000", "time.n_output=1000",
                                "integrator=rk4", "integrator.step=0.001", "allow_large=true",
                                "output.figures=false", "hydra.run.dir=run"], cwd=tmp_path, text=True,
                               stderr=subprocess.PIPE, stdout=subprocess.DEVNULL)
    for line in process.stderr:
        if "integrating" in line:
            break
    process.send_signal(signal.SIGTERM)
    err = process.stderr.read()
    assert process.wait(timeout=60) == 143
    assert "Traceback" not in err and "gyrolab: interrupted; the same command resumes" in err
    assert not (tmp_path / "run" / "run.nc").exists()
    assert not [p for p in (tmp_path / "run").iterdir() if p.name.endswith(".tmp") or p.name == LOCK_NAME]


def test_a_log_that_cannot_be_written_is_said_once(capfd):
    from gyrolab.app import quiet_logging_failures

    class Full:
        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        def flush(self):
            pass

    quiet_logging_failures()
    handler = logging.StreamHandler(Full())
    logger = logging.getLogger("gyrolab.test_trust_flood")
    logger.addHandler(handler)
    try:
        for _ in range(100):
            logger.warning("a line")
    finally:
        logger.removeHandler(handler)
    err = capfd.readouterr().err
    assert err.count("no space left on device") == 1 and "Logging error" not in err


def test_a_null_default_is_type_checked():
    from gyrolab.engine.config import check_scene_config, compose_config

    with pytest.raises(ConfigError, match="output.error_estimate='maybe' must be true, false or null"):
        check_scene_config(compose_config(["output.error_estimate=maybe"]))
    assert check_scene_config(compose_config(["output.error_estimate=true"]))["output"]["error_estimate"] is True


def test_the_umask_is_read_without_changing_it(monkeypatch):
    expected = os.umask(0o022)
    os.umask(expected)
    monkeypatch.setattr(os, "umask", lambda mask: pytest.fail("the umask was changed"))
    assert trust.umask() == expected
