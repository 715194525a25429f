"""gyrolab.batch: the grid as arrays (validated like single runs), chunks streamed to one file, resumable; and
``gyrolab --batch``: the same sweep.nc as a multirun of the same grid, computed in one batch."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest
import xarray as xr
from omegaconf import OmegaConf

from gyrolab import compose_scene
from gyrolab.batch import outputs
from gyrolab.batch.plan import plan_from_overrides, split_overrides
from gyrolab.batch.runner import chunks
from gyrolab.batch.integrate import integrate_arrays
from gyrolab.engine.config import compose_config
from gyrolab.engine.scene import Scene
from gyrolab.errors import ConfigError, GyrolabError
from gyrolab.batch.sweep import run_batch, run_batch_sweep

FIXED = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=1", "time.n_output=11", "output.figures=false"]


def _single(overrides):
    """What a single run of these overrides builds (its scene), or its error sentence."""
    try:
        return Scene.from_config(compose_config(list(overrides)))
    except GyrolabError as error:
        return str(error)


def test_plan_equals_single_runs_state_params_and_errors():
    """Every point's initial state and compiled parameters are the single run's bit for bit, and every
    invalid point carries the single run's error sentence (non-physical body, a value that is no number,
    NaN, a non-unit γ0 given with the angles unset)."""
    swept = ["body.a=1.5,3", "initial.theta0=0.3,nan", "initial.r0=abc,5"]
    plan = plan_from_overrides([*FIXED, "output.euler_angles=true", "initial.psi0=0.7", *swept])
    assert plan.shape == (2, 2, 2)
    for n in range(plan.size):
        position = np.unravel_index(n, plan.shape)
        point = [f"{d.key}={d.labels[p]}" for d, p in zip(plan.dims, position)]
        single = _single([*FIXED, "output.euler_angles=true", "initial.psi0=0.7", *point])
        if isinstance(single, str):
            assert plan.error[n] >= 0 and plan.messages[plan.error[n]] == single, point
        else:
            assert plan.error[n] < 0, point
            np.testing.assert_array_equal(plan.y0[n], single.system.initial_state())
            np.testing.assert_array_equal(plan.combo_params[plan.combo[n]], single.system.compiled_model().params)
    assert plan.valid.sum() == 1   # a = 1.5, θ0 = 0.3, r0 = 5
    gamma = plan_from_overrides([*FIXED, "initial.theta0=null", "initial.phi0=null",
                                 "initial.gamma0=[0,0,1],[0,0.6,0.8],[0,0,2]"])
    assert gamma.valid.tolist() == [True, True, False]
    assert gamma.messages[gamma.error[2]] == _single([*FIXED, "initial.theta0=null", "initial.phi0=null",
                                                      "initial.gamma0=[0,0,2]"])


def test_chunks_are_hyperslabs_covering_the_grid_once():
    for shape, size in [((7, 5, 3), 10), ((7, 5, 3), 4), ((4, 6), 100), ((9,), 2), ((3, 50), 7)]:
        flat = np.arange(int(np.prod(shape))).reshape(shape)
        seen = []
        for chunk in chunks(shape, size):
            assert chunk.stop - chunk.start <= max(size, shape[-1])
            np.testing.assert_array_equal(flat[chunk.slab].ravel(), np.arange(chunk.start, chunk.stop))
            seen.extend(range(chunk.start, chunk.stop))
        assert sorted(seen) == list(range(flat.size))


@pytest.mark.parametrize("euler_angles", [False, True])
def test_reductions_equal_the_systems_invariants(euler_angles):
    """The reductions (by blocks of points) against the system's own invariants computed here over the whole
    trajectories, with gravity, the Newtonian gradient and a magnetic dipole (torques along α and β when the frame
    is carried)."""
    forces = "force=[uniform_gravity,newtonian,magnetic]" if euler_angles else "force=[uniform_gravity,newtonian]"
    scene = compose_scene([*FIXED, forces, f"output.euler_angles={str(euler_angles).lower()}", "time.end=3"])
    compiled = scene.system.compiled_model()
    y0s = np.tile(scene.system.initial_state(), (4, 1))
    y0s[:, 0:3] += np.random.default_rng(1).normal(scale=0.5, size=(4, 3))
    y = integrate_arrays(compiled, scene.integrator, scene.times, y0s).y
    groups = [(scene.system, np.array([0, 2])), (scene.system, np.array([1, 3]))]   # two combinations' rows
    fast = outputs.state_outputs("reductions", 1, scene.times, y, groups)
    invariants = scene.system.invariant_values(y)
    for name in scene.system.invariants:  # independently: max |I(t) − I(0)| from the system's formulas
        expected = np.max(np.abs(invariants[name] - invariants[name][:, :1]), axis=1)
        np.testing.assert_allclose(fast[name + "_max_abs_drift"].data, expected, rtol=1e-9, atol=1e-13)
    theta = np.arccos(np.clip(y[:, :, 5] / np.linalg.norm(y[:, :, 3:6], axis=2), -1, 1))
    np.testing.assert_allclose(fast["max_nutation_deviation"].data, np.max(np.abs(theta - theta[:, :1]), axis=1),
                               atol=1e-9)


def test_final_mode_equals_single_runs_and_reads_lazily(tmp_path):
    fixed, dims = split_overrides([*FIXED, "output.euler_angles=false", "batch.output=final", "batch.chunk=2",
                                   "initial.r0=1,6", "body.b=1.2,1.5"])
    stats = run_batch(fixed, dims, tmp_path / "sweep.nc")
    assert stats.chunks == 2 and not (tmp_path / "sweep.nc.part").exists()
    with xr.open_dataset(tmp_path / "sweep.nc", chunks={}) as ds:
        assert ds.omega.dims == ("r0", "b", "axis") and ds.omega.chunks is not None   # dask: read lazily
        assert ds.r0.attrs["units"] == "1" and ds.attrs["n_finished"] == 4
        for variable in ds.data_vars.values():
            assert variable.attrs.get("long_name"), variable.name
        for i, r0 in enumerate([1, 6]):
            for j, b in enumerate([1.2, 1.5]):
                single = compose_scene([*FIXED, "output.euler_angles=false", f"initial.r0={r0}", f"body.b={b}"]).run()
                np.testing.assert_allclose(ds.omega[i, j].values, single.omega[-1].values, rtol=0, atol=1e-12)
                np.testing.assert_allclose(ds.energy[i, j].values, single.energy[-1].values, rtol=0, atol=1e-12)


def test_a_chunk_whose_trajectories_all_fail_is_stored_as_failed_points(tmp_path):
    """RK4 with a step far too long for a fast spin overflows: those points fail, the slow one is stored."""
    fixed, dims = split_overrides(["integrator=rk4_numba", "integrator.step=0.9", "time.end=200", "time.n_output=3",
                                   "output.euler_angles=false", "batch.chunk=1", "initial.r0=500,400,0.1"])
    run_batch(fixed, dims, tmp_path / "sweep.nc")
    with xr.open_dataset(tmp_path / "sweep.nc") as ds:
        assert ds.job_status.values.tolist() == [2, 2, 1]
        assert "became non-finite" in str(ds.error_message.values[ds.job_error.values[0]])
        assert np.isnan(ds.omega.values[:2]).all() and np.isfinite(ds.omega.values[2]).all()


def test_scipy_integrators_run_per_point_and_another_command_in_its_directory_is_refused(tmp_path):
    # no batch kernel (capability batch_kernel): one integrate() per point, each a single run's numbers
    scipy = ["integrator=rk45", "time.end=1", "time.n_output=11", "output.euler_angles=false"]
    with xr.open_dataset(run_batch_sweep([*scipy, "initial.r0=1,2"], tmp_path / "a")) as ds:
        assert ds.attrs["batch_path"] == "one integrate() call per point"
        for i, r0 in enumerate([1, 2]):
            single = compose_scene([*scipy, f"initial.r0={r0}"]).run()
            np.testing.assert_array_equal(ds.omega[i].values, single.omega[-1].values)
    with pytest.raises(ConfigError, match=r"^integrator 'rk45' has no variational equations \(capability variational\), "
                                          r"which the chaos indicators of batch.output=indicator need; valid choices: "
                                          r"rk4, rk4_numba, dop853 or dop853_numba$"):
        run_batch_sweep([*scipy, "batch.output=indicator", "initial.r0=1,2"], tmp_path / "c")
    run_batch_sweep([*FIXED, "initial.r0=1,2"], tmp_path / "b")
    with pytest.raises(ConfigError, match="holds another batch"):
        run_batch_sweep([*FIXED, "initial.r0=1,3"], tmp_path / "b")


KILLED = textwrap.dedent("""
    import os, signal, sys
    from gyrolab.batch import store
    from gyrolab.batch.sweep import run_batch_sweep

    written = store.Store._write
    calls = []

    def write_then_die(self, name, chunk, data):   # kill -9 in the middle of the third chunk's writes
        written(self, name, chunk, data)
        calls.append(chunk.start)
        if len(set(calls)) == 3 and name == "omega":
            os.kill(os.getpid(), signal.SIGKILL)

    store.Store._write = write_then_die
    run_batch_sweep(sys.argv[2:], sys.argv[1])
""")


def test_kill_minus_9_then_the_same_command_resumes(tmp_path, caplog):
    grid = [*FIXED, "output.euler_angles=false", "batch.output=reductions", "batch.chunk=2", "initial.r0=1,2,3",
            "initial.theta0=0.5,1.0"]
    script = tmp_path / "killed.py"
    script.write_text(KILLED)
    killed = subprocess.run([sys.executable, str(script), str(tmp_path / "run"), *grid], capture_output=True,
                            text=True, timeout=300)
    assert killed.returncode == -9, killed.stderr[-2000:]
    assert not (tmp_path / "run" / "sweep.nc").exists() and (tmp_path / "run" / "sweep.nc.part").exists()
    journal = (tmp_path / "run" / "sweep.nc.chunks").read_text().splitlines()
    assert journal[1:] == ["0", "1"]   # two chunks stored; the third was being written
    with caplog.at_level("INFO", logger="gyrolab.batch"):
        run_batch_sweep(grid, tmp_path / "run")
    assert "2 stored already, 1 to run" in caplog.text
    run_batch_sweep(grid, tmp_path / "whole")
    with xr.open_dataset(tmp_path / "run" / "sweep.nc") as resumed, \
            xr.open_dataset(tmp_path / "whole" / "sweep.nc") as whole:
        assert int(resumed.job_status.min()) == 1
        for name in ("omega", "gamma", "energy_max_abs_drift", "max_nutation_deviation"):
            np.testing.assert_array_equal(resumed[name].values, whole[name].values)
    assert OmegaConf.create(resumed.attrs["config"]).batch.output == "reductions"


def test_stability_map_is_a_theta0_r0_batch_that_a_rerun_finds_complete(tmp_path, caplog):
    """The experiment's grid (batch.points as a square grid, r0 geometric) runs as one batch into stability_map.nc
    with dims (theta0, r0) and the chosen points' Poincaré sections; the indicator's values are
    gyrolab.analysis.chaos's (tested there)."""
    from gyrolab.experiments import stability_map

    cfg = compose_config(["experiment=stability_map", "batch.points=9", "time.end=1", "stability_map.section_time=20",
                          "stability_map.sections=[[0.6,3.0],[1.0,1.5]]", "output.figures=false"])
    # θ0 evenly spaced, r0 geometric: the middle value is the geometric mean of 0.05 and 10
    np.testing.assert_allclose([d.values for d in stability_map.grid(cfg)],
                               [[0.05, 1.57, 3.09], [0.05, np.sqrt(0.5), 10.0]], rtol=1e-15)
    written = stability_map.run(cfg, tmp_path)
    assert written == [tmp_path / "stability_map.nc"]
    with xr.open_dataset(written[0]) as ds:
        assert ds.indicator.dims == ds.max_nutation_deviation.dims == ("theta0", "r0")
        assert ds.theta0.attrs["units"] == "rad" and "MEGNO" in ds.indicator.attrs["indicator_name"]
        assert int(ds.job_status.min()) == 1
        np.testing.assert_array_equal(ds.section_theta0.values, [0.6, 1.0])
        assert ds.section_phi.dims == ("section_point", "crossing")
    with caplog.at_level("INFO", logger="gyrolab.batch"):
        stability_map.run(cfg, tmp_path)
    assert "holds this batch complete already" in caplog.text


# ----------------------------------------------------------------------------- a list of points

POINTS_CSV = "initial.r0,initial.theta0,body.a\n2,0.3,1.5\n5,0.6,3\n3,0.4,1.2\n"   # a = 3: non-physical body


def test_points_file_and_zip_give_a_point_dimension_equal_to_single_runs(tmp_path):
    """Each row of a hand-written points file is one point along ``point`` (the keys its coordinates, the file's
    values), with the single run's final state or error; the same points zipped on the command line give the
    same dataset; an edited file rerun into the same directory is another command, refused."""
    points = tmp_path / "points.csv"
    points.write_text(POINTS_CSV)
    fixed = [*FIXED, "output.euler_angles=false", "batch.output=final", "batch.chunk=2"]
    listed = run_batch_sweep([*fixed, f"batch.points_file={points}"], tmp_path / "file")
    zipped = run_batch_sweep([*fixed, "batch.zip=true", "initial.r0=2,5,3", "initial.theta0=0.3,0.6,0.4",
                              "body.a=1.5,3,1.2"], tmp_path / "zip")
    rows = [(2, 0.3, 1.5), (5, 0.6, 3), (3, 0.4, 1.2)]
    with xr.open_dataset(listed) as ds, xr.open_dataset(zipped) as z:
        assert ds.omega.dims == ("point", "axis") and ds.job_status.dims == ("point",)
        for name, column in zip(("r0", "theta0", "a"), zip(*rows)):
            assert ds[name].dims == ("point",) and ds[name].values.tolist() == list(column)
            assert ds[name].attrs["override_key"] in POINTS_CSV and "units" in ds[name].attrs
        assert ds.r0.attrs["units"] == "1" and ds.theta0.attrs["units"] == "rad"
        for n, (r0, theta0, a) in enumerate(rows):
            single = _single([*FIXED, "output.euler_angles=false", f"initial.r0={r0}", f"initial.theta0={theta0}",
                              f"body.a={a}"])
            if isinstance(single, str):
                assert int(ds.job_status[n]) == 2 and str(ds.error_message.values[int(ds.job_error[n])]) == single
                continue
            final = single.run()
            assert int(ds.job_status[n]) == 1
            np.testing.assert_allclose(ds.omega[n].values, final.omega[-1].values, rtol=0, atol=1e-12)
            np.testing.assert_allclose(ds.energy[n].values, final.energy[-1].values, rtol=0, atol=1e-12)
        assert ds.job_status.values.tolist() == [1, 2, 1]
        for name in ("omega", "gamma", "job_status", "r0", "a"):
            np.testing.assert_array_equal(z[name].values, ds[name].values)
        assert z.attrs["batch_points_kind"] == "zip" and ds.attrs["batch_points_kind"] == "points_file"
    points.write_text(POINTS_CSV.replace("3,0.4,1.2", "3,0.4,1.25"))
    with pytest.raises(ConfigError, match="holds another batch"):
        run_batch_sweep([*fixed, f"batch.points_file={points}"], tmp_path / "file")


@pytest.mark.parametrize("text, says", [
    (None, "cannot be read"),
    ("initial.r0,initial.nope\n1,2\n", "'initial.nope' is not a key of this config"),
    ("initial.r0,body.a\n1,1.5\n2\n", "line 3: 1 value, but the header names 2 keys"),
    ("initial.r0\n1\nabc\n", "line 3, initial.r0: 'abc' is not a number"),
    ("integrator.step\n0.1\n", "not a body, initial or force parameter"),
])
def test_a_bad_points_file_is_one_sentence_and_writes_nothing(tmp_path, text, says):
    points = tmp_path / "points.csv"
    if text is not None:
        points.write_text(text)
    with pytest.raises(ConfigError) as caught:
        run_batch_sweep([*FIXED, f"batch.points_file={points}"], tmp_path / "out")
    assert says in str(caught.value) and "\n" not in str(caught.value) and caught.value.exit_code == 2
    assert not (tmp_path / "out").exists()


def test_zip_needs_equal_lengths_and_a_grid_refuses_repeated_values():
    with pytest.raises(ConfigError, match="each needs as many values; got initial.r0 3, body.a 2"):
        plan_from_overrides([*FIXED, "batch.zip=true", "initial.r0=1,2,3", "body.a=1.5,1.2"])
    with pytest.raises(ConfigError, match="sweeps the value 2 twice"):
        plan_from_overrides([*FIXED, "initial.r0=1,2,2"])
    assert plan_from_overrides([*FIXED, "batch.zip=true", "initial.r0=1,2,2", "body.a=1.5,1.5,1.2"]).shape == (3,)


def test_auto_chooses_once_for_the_whole_batch(tmp_path, monkeypatch):
    """integrator=auto: one choice in the parent, the same method and tolerance in every chunk, recorded in the
    attributes. The expectation is the single runs' own choices: the batch samples its first point (r0 = 0.5)
    and its largest state (r0 = 12) and takes the tighter tolerance; each chunk alone would have sampled its
    own points (r0 0.5 and 1, r0 8 and 12), which here choose differently."""
    from gyrolab.batch import runner

    scene = ["integrator=auto", "integrator.accuracy=1e-8", "time.end=1", "time.n_output=3", "output.figures=false",
             "output.euler_angles=false"]
    tolerance = {r0: compose_scene([*scene, f"initial.r0={r0}"]).run().attrs["auto_tolerance"]
                 for r0 in (0.5, 1, 8, 12)}
    assert min(tolerance[0.5], tolerance[1]) != min(tolerance[8], tolerance[12])   # chunks alone would differ
    seen = []
    chunk = runner.run_chunk

    def recorded(task):
        result = chunk(task)
        seen.append((task.integrator.name, result.settings))
        return result

    monkeypatch.setattr(runner, "run_chunk", recorded)
    fixed, dims = split_overrides([*scene, "batch.output=final", "batch.chunk=2", "initial.r0=0.5,1,8,12"])
    run_batch(fixed, dims, tmp_path / "sweep.nc")
    assert len(seen) == 2 and seen[0] == seen[1]
    with xr.open_dataset(tmp_path / "sweep.nc") as ds:
        assert ds.attrs["auto_tolerance"] == min(tolerance[0.5], tolerance[12])
        assert ds.attrs["accuracy"] == 1e-8 and ds.attrs["auto_method"] == seen[0][0]
        tol = "integrator_tol" if seen[0][0] == "taylor" else "integrator_rtol"
        assert seen[0][1][tol] == ds.attrs["auto_tolerance"]
        assert int(ds.job_status.min()) == 1


def test_batch_reports_each_chunk_as_it_starts_and_names_the_kernels_first_load(tmp_path, caplog, monkeypatch):
    """Issue 24 item 5: a chunk is reported when it starts (a one-chunk batch is not silent until it ends); the
    first chunk of a process says it loads (or compiles) the kernels, and the summary separates that time."""
    from gyrolab.batch import runner

    monkeypatch.setattr(runner, "_kernels_called", False)   # as in a fresh process
    grid = [*FIXED, "output.euler_angles=false", "batch.output=final", "batch.chunk=2", "initial.r0=1,2,3"]
    with caplog.at_level("INFO", logger="gyrolab.batch"):
        run_batch_sweep(grid, tmp_path / "run")
    lines = [r.getMessage() for r in caplog.records]
    starts = [line for line in lines if "batch: chunk" in line and "integrating" in line]
    assert [line.split(":")[1].strip() for line in starts] == ["chunk 1", "chunk 2"]
    assert "loads the integration kernels" in starts[0] and "loads" not in starts[1]
    assert any("loading or compiling" in line for line in lines if "in the integration kernels" in line)


def _reproduce(monkeypatch, capsys, *args):
    from gyrolab import app

    monkeypatch.setattr(sys, "argv", ["gyrolab", "reproduce", *args])
    with pytest.raises(SystemExit) as stop:
        app.main()
    captured = capsys.readouterr()
    return stop.value.code, captured.out, captured.err


def test_reproduce_reruns_a_batch_sweep_nc_all_points_or_the_chosen_ones(tmp_path, monkeypatch, capsys):
    grid = [*FIXED, "batch.chunk=2", "initial.r0=1,2,3", "body.a=1.5,3"]   # a=3: non-physical, failed points
    path = run_batch_sweep(grid, tmp_path / "b")
    code, out, _ = _reproduce(monkeypatch, capsys, str(path))
    assert code == 0, out
    assert "all 6 of 6 points, in 3 of 3 chunks" in out and "identical:" in out and "NOT" not in out

    tampered = xr.load_dataset(path, decode_times=False, decode_timedelta=False)
    tampered["omega"].values[2, 0, 1] += 1e-9       # point 4 (r0=3, a=1.5), in the third chunk
    tampered.to_netcdf(tmp_path / "tampered.nc")
    code, out, _ = _reproduce(monkeypatch, capsys, str(tmp_path / "tampered.nc"), "--points", "0-3")
    assert code == 0, out
    assert "4 of 6 points, in 2 of 3 chunks" in out and "NOT" not in out   # the tampered chunk is not rerun
    code, out, _ = _reproduce(monkeypatch, capsys, str(tmp_path / "tampered.nc"), "--points", "1,4")
    assert code == 1, out
    assert "variable omega: max |Δ|" in out and "1 of 6 values differ" in out and "NOT identical" in out

    code, _, err = _reproduce(monkeypatch, capsys, str(path), "--points", "6")
    assert code == 2 and err.strip().splitlines() == [
        "gyrolab: error: --points '6': 6 is outside the points 0 to 5; e.g. --points 0,5,10-19"]


# ---- gyrolab --batch against a multirun of the same grid ------------------------------------------------------------

GRID = ["integrator=rk4_numba", "integrator.step=0.01", "output.euler_angles=false", "output.figures=false",
        "time.end=2", "time.n_output=5", "initial.r0=2,5", "body.a=1.5,3"]  # a = 3 is non-physical


def test_batch_sweep_equals_the_multirun(cli, tmp_path):
    multi = cli("-m", *GRID, "hydra.sweep.dir=multi")
    batch = cli("--batch", *GRID, "batch.output=trajectory", "hydra.sweep.dir=batch")
    assert batch.returncode == multi.returncode == 1, batch.stderr[-2000:]  # the non-physical points fail in
    assert "2 of 4 points failed" in batch.stderr                             # both, without stopping the sweep
    with xr.open_dataset(tmp_path / "multi" / "sweep.nc") as m, xr.open_dataset(tmp_path / "batch" / "sweep.nc") as b:
        assert m.omega.dims == b.omega.dims == ("r0", "a", "time", "axis")
        np.testing.assert_array_equal(m.job_status.values, b.job_status.values)
        np.testing.assert_array_equal(m.time.values, b.time.values)
        # the batch kernel sums the torque terms in another order: equal to rounding
        np.testing.assert_allclose(b.omega.values, m.omega.values, rtol=0, atol=1e-12, equal_nan=True)
        np.testing.assert_allclose(b.gamma.values, m.gamma.values, rtol=0, atol=1e-12, equal_nan=True)
        assert int(b.n_failed) == int(m.n_failed) == 2
        errors = b.error_message.values[b.job_error.values[b.job_status.values == 2]]
        assert all("triangle inequality" in str(e) for e in errors) and len(errors) == 2


def test_batch_refuses_to_vary_the_integrator(cli):
    done = cli("--batch", "integrator=rk4,rk4_numba", "hydra.sweep.dir=x")
    assert done.returncode == 2
    assert "varies body, initial and force parameters only" in done.stderr
