"""Bad input: one sentence naming the bad value and what is valid, a non-zero exit, no run.nc."""

import sys

import pytest

from gyrolab import app
from gyrolab.errors import ConfigError
from tests.helpers import files_under, run_main

CASES = {
    "unknown integrator": (["integrator=foo"], ["'foo'", "dop853", "rk4"]),
    "unknown force": (["force=[uniform_gravity,gravity]"], ["'gravity'", "newtonian", "magnetic"]),
    "unknown body": (["body=brick"], ["'brick'", "asymmetric_top"]),
    "unknown swept integrator": (["-m", "integrator=rk4,rk5"], ["'rk5'", "dop853"]),
    "non-positive inertia": (["body.a=-1"], ["body.a=-1", "positive"]),
    "zero inertia (SI)": (["body=si_gyroscope", "body.inertia=[0.02,0,0.01]"], ["B=0", "positive"]),
    "triangle inequality": (["body.a=3", "body.b=1.5"], ["(3, 1.5, 1)", "allow_nonphysical"]),
    "gamma0 not unit": (["initial.gamma0=[1,0,0.1]", "initial.theta0=null", "initial.phi0=null"],
                        ["|γ0| = 1", "1.00498"]),
    "gamma0 and angles both": (["initial.gamma0=[1,0,0]"], ["gamma0", "theta0"]),
    "NaN": (["initial.r0=nan"], ["initial.r0=nan", "finite"]),
    "inf": (["force.newtonian.k=inf"], ["force.newtonian.k=inf", "finite"]),
    "not a number": (["initial.p0=fast"], ["initial.p0='fast'", "number"]),
    "non-positive step": (["integrator=rk4", "integrator.step=0"], ["integrator.step=0", "positive"]),
    "non-positive tolerance": (["integrator.rtol=-1e-9"], ["integrator.rtol=-1e-09", "positive"]),
    "end before start": (["time.end=-1"], ["time.end=-1", "time.start=0"]),
    "too few samples": (["time.n_output=1"], ["time.n_output=1", "≥ 2"]),
    "malformed override": (["body.a=[2"], ["malformed override", "body.a=[2"]),
    "unknown key": (["body.mass_kg=3"], ["mass_kg"]),
    "foreign target": (["integrator._target_=os.system"], ["os.system", "dop853"]),
    "SI parameter on a nondimensional body": (["body.mass=2"], ["body.mass", "nondimensional"]),
    "Newtonian R without SI body": (["force.newtonian.k=null", "force.newtonian.R=10"], ["R=10", "SI body"]),
    "magnetic direction not unit": (["force=[magnetic]", "force.magnetic.direction=[1,1,0]"],
                                    ["direction=[1.0, 1.0, 0.0]", "unit vector"]),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_input_is_one_sentence_and_writes_nothing(name, tmp_path, monkeypatch, capsys):
    argv, must_mention = CASES[name]
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", *argv, "hydra.run.dir=out", "hydra.sweep.dir=sweep"])
    with pytest.raises(SystemExit) as stop:
        app.main()
    assert stop.value.code not in (0, None)
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith("gyrolab: error: ")
    for text in must_mention:
        assert text in err, (text, err)
    assert not list(tmp_path.rglob("run.nc"))


def test_unwritable_output_directory(tmp_path, monkeypatch, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", f"hydra.run.dir={blocker}/run"])
    with pytest.raises(SystemExit) as stop:
        app.main()
    assert stop.value.code != 0
    err = capsys.readouterr().err.strip()
    assert "not writable" in err and str(blocker) in err and len(err.splitlines()) == 1
    assert not list(tmp_path.rglob("run.nc"))


def test_nonphysical_body_runs_when_allowed_and_says_so():
    from gyrolab import run

    ds = run(["body.a=3", "body.b=1.5", "body.allow_nonphysical=true", "time.end=1", "time.n_output=3"])
    assert ds.attrs["body_nonphysical"] == 1


def test_command_line_exit_code_and_no_partial_output(cli, tmp_path):
    done = cli("initial.r0=nan", "hydra.run.dir=out")
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == ["gyrolab: error: initial.r0=nan is not a finite number; "
                                                "every numeric setting must be finite"]
    assert not (tmp_path / "out").exists()


def test_regime_outside_its_domain_writes_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", "regime=large_parameter", "hydra.run.dir=out"])
    with pytest.raises(SystemExit) as stop:
        app.main()
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "large_parameter" in err and "small_parameter" in err
    assert not (tmp_path / "out").exists()


# ---- the corpus: every bad input is one sentence, a non-zero exit, nothing created -------------------------

LONG = "x" * 100_000
DIGITS = "1" * 400
SITE = __import__("sysconfig").get_paths()["purelib"]

#: (command line, a phrase the sentence must contain); hydra.run.dir / hydra.sweep.dir are added unless given
CORPUS = [
    # Hydra's override grammar
    (["=5"], "has no key"), (["="], "valid forms"), (["~"], "valid forms"),
    (["+"], "malformed override"), (["time.end=[1"], "valid forms"), (["time.end={a"], "valid forms"),
    (["time.end='5"], "valid forms"), (["time..end=5"], "valid forms"), ([".time=5"], "valid forms"),
    (["time.end=${"], "valid forms"), (["time.end=1,2"], "run it with -m"),
    (["-m", "time.end=interval(0,1)"], "not a list of values"), (["-m", "time.end=1,1"], "time.end"),
    (["@=5"], "valid forms"),
    # interpolations
    (["initial.r0=${nope.key}"], "${nope.key}"), (["initial.r0=${time}"], "initial.r0"),
    (["initial.r0=${oc.env:GYROLAB_SURELY_UNSET_VARIABLE}"], "initial.r0"),
    (["hydra.run.dir=${nope.key}/x"], "cannot be resolved before the run starts"),
    # sections deleted or replaced by a value
    (["~time"], "deletes the section time"),
    (["~body"], "deletes the section body"),
    (["~system"], "deletes the section system"),
    (["time=5"], "`time` is a section"), (["output=5"], "`output` is a section"),
    # unknown keys, with the closest valid one
    (["+foo=1"], "`foo` is not a key of the config"), (["++foo=1"], "`foo` is not a key of the config"),
    (["+time.ennd=5"], "did you mean `time.end`?"), (["time.ennd=5"], "did you mean `time.end`?"),
    (["output.figure=false"], "did you mean `output.figures`?"), (["+body.mass_kg=3"], "body.mass_kg"),
    (["+integrator.rtoll=1e-9"], "did you mean `integrator.rtol`?"),
    (["+force.newtonian.kk=1"], "force.newtonian.kk"),
    (["integrater=rk4"], "did you mean `integrator`?"),
    (["+time.end=5"], "exists already"), (["+experiment=nope"], "unknown experiment 'nope'"),
    (["experiment=perf_referenc"], "did you mean experiment=perf_reference?"),
    (["force=[newtonian,magnet]"], "'magnet'"),
    ([f"{LONG}=1"], "characters"),
    ([f"time.end={LONG}"], "characters"), ([f"+time.{'e' * 5000}=1"], "longer than 200 characters"),
    (["task=nope"], "unknown task 'nope'"),
    # types
    (["output.figures=maybe"], "output.figures='maybe' must be true or false"),
    (["time.n_output=2.5"], "time.n_output=2.5 must be an integer"),
    (["time.start=abc"], "time.start='abc' must be a number"),
    (["time.end=true"], "must be a number"),
    (["task=5"], "task=5"), (["allow_large=maybe"], "true or false"),
    (["accuracy=abc"], "accuracy='abc' must be a number"),
    (["body.com_direction=[1,0]"], "three"),
    # numbers that are not representable
    ([f"initial.r0={DIGITS}"], "too large"),
    ([f"time.n_output={DIGITS}"], "too large"), (["time.end=1e400"], "finite"), (["initial.r0=-inf"], "finite"),
    # output paths
    (["hydra.run.dir="], "working directory"), (["hydra.run.dir=."], "working directory"),
    (["hydra.run.dir=.."], "working directory or one of its parents"),
    (["-m", "time.end=1,2", "hydra.sweep.dir="], "hydra.sweep.dir"),
    (["hydra.output_subdir=../x"], "hydra.output_subdir"),
    (["-m", "time.end=1,2", "hydra.sweep.subdir=../x"], "hydra.sweep.subdir"),
    (["hydra.job.name=../x"], "hydra.job.name"), ([f"hydra.run.dir={SITE}/gyrolab_out"], "where Python loads code"),
    # tolerances outside (0, 1)
    (["integrator.rtol=2"], "integrator.rtol=2 is outside (0, 1)"),
    (["integrator.rtol=0"], "outside (0, 1)"), (["integrator.atol=5"], "integrator.atol=5"),
    (["integrator=taylor", "integrator.tol=1.5"], "integrator.tol=1.5"), (["integrator=auto", "accuracy=2"], "accuracy=2"),
    # infeasible requests (the budget)
    (["time.n_output=1000000000"], "67.1 GiB"),
    (["time.end=1e12"], "integrator steps"), (["integrator=rk4", "integrator.step=1e-9"], "1e+11 integrator steps"),
    (["integrator.max_step=1e-9"], "integrator.max_step"),
    # Hydra settings swept, config sources
    (["-m", "hydra.launcher.n_jobs=1,2"], "sweeps a Hydra setting"),
    (["-m", "+hydra.callbacks.x._target_=a,b"], "sweeps a Hydra setting"),
    (["--config-dir", "/nonexistent/gyrolab-conf"], "--config-dir"), (["--config-name", "nope"], "primary config 'nope'"),
    (["--config-path", "/nonexistent/gyrolab-conf"], "--config-path"),
    # the other commands
    (["--reproduce"], "exactly one path"), (["--reproduce", "a.nc", "b.nc"], "exactly one path"),
    (["--reproduce", "missing.nc"], "No such file"), (["--batch", "hydra.run.dir=x"], "hydra.sweep.dir only"),
    (["--batch", "time.end=1,2"], "varies body, initial and force"), (["--batch", "=5"], "has no key"),
    (["--batch", "+foo=1"], "`foo` is not a key"), (["--batch", "integrator.rtol=2"], "outside (0, 1)"),
    (["--batch", "hydra.sweep.dir="], "working directory"),
]


@pytest.mark.parametrize("argv, phrase", CORPUS, ids=[" ".join(a)[:60] for a, _ in CORPUS])
def test_corpus_of_bad_inputs(argv, phrase, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    given = " ".join(argv)
    extra = [] if "hydra.run.dir" in given or argv[0].startswith("--") and argv[0] != "--config-name" else \
        ["hydra.run.dir=out"]
    if "-m" in argv and "hydra.sweep.dir" not in given:
        extra.append("hydra.sweep.dir=sweep")
    code, err = run_main([*argv, *extra], monkeypatch, capsys)
    assert code not in (0, None)
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gyrolab: error: "), err
    assert phrase in lines[0], (phrase, lines[0])
    assert len(lines[0]) < 1200
    assert list(tmp_path.iterdir()) == []


def test_corpus_has_at_least_100_cases():
    assert len(CORPUS) + len(CASES) >= 100


# ---- the hostile corpus (issue 23): user files, oversize requests, foreign datasets, degenerate vectors, paths ----

G = "# @package _global_\n"
BOMB = G + "".join(f"{c}: &{c} [{', '.join([f'*{p}'] * 9) if p else ', '.join(['x'] * 9)}]\n"
                   for p, c in zip(["", "a", "b", "c", "d", "e", "f"], "abcdefg"))


def _user_file(text, selected="experiment=bad", name="experiment/bad.yaml"):
    """A --config-dir holding one file ``name``, and the command line that reads it."""
    return ["--config-dir", "cd", selected], {f"cd/{name}": text}


#: (command line, files to create first (relative to the working directory), a phrase the sentence must contain)
FILE_CORPUS = [
    # YAML syntax and structure in a user's --config-dir: one sentence with file and line
    (*_user_file(G + "time:\n  end: [1\n"), "bad.yaml, line 4: not valid YAML"),
    (*_user_file(G + "time:\n\tend: 1\n"), "a tab"),
    (*_user_file(G + "time:\n  end: 1\n  end: 2\n"), "line 4: the key 'end' is given twice"),
    (*_user_file(G + "time: {end: 1, end: 2}\n"), "given twice"),
    (*_user_file((G + "time:\n  end: 1\x00\n").encode()), "line 3: a control character (code 0)"),
    (*_user_file(G + "x: \x07\n"), "control character (code 7)"),
    (*_user_file(b"\xff\xfe\x00garbage"), "not UTF-8 text"),
    (*_user_file(G + "5\n"), "a single value, not a mapping"),
    (*_user_file(G + "'just a string'\n"), "a single value, not a mapping"),
    (*_user_file(G + "- 1\n- 2\n"), "a list, not a mapping"),
    (*_user_file(BOMB), "anchors and aliases expand to more than"),
    (*_user_file(G + "a: &a\n  b: *a\n"), "refers to itself"),
    (*_user_file(G + "a: *undefined\n"), "not valid YAML"),
    (*_user_file(G + "key: 'unterminated\n"), "not valid YAML"),
    (*_user_file(G + "time:\n  end: 1\n   start: 2\n"), "not valid YAML"),
    (*_user_file(G + "time:\n  end: !!python/object/apply:os.system ['echo hi']\n"), "YAML tag"),
    (*_user_file(G + "time:\n  end: !custom 5\n"), "YAML tag"),
    (*_user_file(G + "? [a, b]\n: 1\n"), "a key is a list or a mapping"),
    (*_user_file(G + "%YAML 9.9\n---\na: 1\n"), "not valid YAML"),
    (*_user_file(G + "a: 1\n---\nb: 2\n"), "not valid YAML"),
    (*_user_file(G + "defaults: 5\n"), "`defaults` must be a list"),
    (*_user_file(G + "a: " + "[" * 200 + "]" * 200 + "\n"), "nested more than"),
    (*_user_file(G + "a: " + "{b: " * 200 + "1" + "}" * 200 + "\n"), "nested more than"),
    (*_user_file(G + "a: 1\n" * 2), "given twice"),
    (*_user_file(G + "".join(f"a{i}: 1\n" for i in range(120_000))), "larger than"),
    (*_user_file(G + "initial: [1]\n"), "a list and a section (a mapping)"),
    (*_user_file(G + "time:\n  end: .inf\n"), "finite"),
    (*_user_file(G + "task: {a: 1}\n"), "task"),
    (["--config-path", "cp", "--config-name", "bad"], {"cp/bad.yaml": "defaults:\n  - _self_\ntime: [1\n"},
     "bad.yaml, line 4"),
    (["--config-path", "cp", "--config-name", "bad"], {"cp/bad.yaml": "5\n"}, "not a mapping"),
    (*_user_file("time:\n  end: [1\n", "time.end=1", "config.yaml"), "config.yaml, line 3"),
    # a list where a mapping belongs, and a value where a section belongs
    (*_user_file(G + "time: [1, 2]\n"), "a list and a section (a mapping)"),
    (*_user_file(G + "body: [1, 2, 3]\n"), "a list and a section (a mapping)"),
    (*_user_file(G + "body:\n  com_direction: {a: 1}\n"), "a list and a section (a mapping)"),
    (*_user_file(G + "time: 5\n"), "time"),
    (*_user_file(G + "force: 5\n"), "`force` is a section"),
    (*_user_file(G + "integrator: 5\n"), "`integrator` is a section"),
    (*_user_file(G + "initial:\n  r0: 1e300\n"), "too large"),
    (*_user_file(G + "time:\n  n_output: abc\n"), "time.n_output='abc' must be an integer"),
    (*_user_file(G + "body:\n  com_direction: [0, 0, 0]\n"), "zero vector"),
    # points files: read as CSV of known keys; their contents never echoed
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": "SECRET LINE\n1,2\n"}, "header column 1"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": b"\x89PNG\x00\x01secret"}, "not UTF-8"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": b"initial.r0\n1\x00\n"}, "not UTF-8"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": "initial.r0\nsecret value here\n"},
     "the value is not a number"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": "initial.r0\n1e300\n"}, "too large"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": "initial.r0\ninf\n"}, "finite"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"],
     {"p.csv": "-----BEGIN OPENSSH PRIVATE KEY-----\nb3BlbnNzaC1rZXktdjEAAAAA\n"}, "not a dotted key name"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": "<html>secret</html>\n"}, "header column"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": ""}, "is empty"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": "initial.r0\n"}, "no points"),
    (["--batch", "batch.points_file=p.csv", "hydra.sweep.dir=b"], {"p.csv": "time.end\n5\n"}, "header column"),
    (["--batch", "batch.points_file=/etc/passwd", "hydra.sweep.dir=b"], {}, "not a dotted key name"),
    (["--batch", "batch.points_file=d", "hydra.sweep.dir=b"], {"d/x": ""}, "cannot be read"),
    (["--batch", "batch.points_file=/dev/zero", "hydra.sweep.dir=b"], {}, "cannot be read"),
    (["--batch", "batch.points_file=missing.csv", "hydra.sweep.dir=b"], {}, "cannot be read"),
    # datasets that are not gyrolab's
    (["--plot", "ds/run.nc"], {"ds/run.nc": "hello, not netCDF\n"}, "not a netCDF file"),
    (["--plot", "ds"], {"ds/run.nc": b""}, "is empty"),
    (["--plot", "ds/run.nc"], {"ds/run.nc": b"CDF\x01" + bytes(range(200))}, "not a netCDF file"),
    (["--reproduce", "ds/run.nc"], {"ds/run.nc": "hello, not netCDF\n"}, "not a netCDF file"),
    (["--reproduce", "ds/run.nc"], {"ds/run.nc": b""}, "is empty"),
    (["--reproduce", "ds"], {"ds/x": ""}, "not a regular file"),
    (["--plot", "/dev/null"], {}, "neither a directory nor a dataset file"),
    (["--reproduce", "/dev/null"], {}, "not a regular file"),
]

#: netCDF files that are not gyrolab's: (command, file name, attributes, a phrase)
FOREIGN = [
    ("--plot", "run.nc", {}, "not a dataset gyrolab wrote"),
    ("--plot", "sweep.nc", {}, "not a dataset gyrolab wrote"),
    ("--plot", "regime.nc", {}, "not a dataset gyrolab wrote"),
    ("--plot", "work_precision.nc", {}, "not a dataset gyrolab wrote"),
    ("--plot", "stability_map.nc", {}, "a stability map needs a variable 'indicator'"),
    ("--plot", "regime_validity.nc", {}, "not a dataset gyrolab wrote"),
    ("--plot", "orbit_family.nc", {}, "not a dataset gyrolab wrote"),
    ("--plot", "foreign.nc", {}, "not a dataset gyrolab draws figures from"),
    ("--reproduce", "run.nc", {}, "no 'config' attribute"),
    ("--reproduce", "run.nc", {"config": "time: 5"}, "not a dataset gyrolab wrote"),
    ("--reproduce", "run.nc", {"config": "!!python/object/apply:os.system ['id']"}, "not plain YAML"),
    ("--reproduce", "run.nc", {"config": "[1, 2]"}, "not a YAML mapping"),
]


def _one_sentence(argv, files, phrase, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for name, content in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)
    before = files_under(tmp_path)
    extra = [] if argv[0] in ("--batch", "--plot", "--reproduce") or "hydra.run.dir" in " ".join(argv) else \
        ["hydra.run.dir=out"]
    code, err = run_main([*argv, *extra], monkeypatch, capsys)
    assert code not in (0, None)
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gyrolab: error: "), err
    assert phrase in lines[0], (phrase, lines[0])
    assert "secret" not in lines[0].lower() and "PRIVATE" not in lines[0], lines[0]
    assert files_under(tmp_path) == before


@pytest.mark.parametrize("argv, files, phrase", FILE_CORPUS, ids=[f"{i}-{p[:40]}" for i, (_, _, p) in
                                                                 enumerate(FILE_CORPUS)])
def test_file_corpus_of_bad_inputs(argv, files, phrase, tmp_path, monkeypatch, capsys):
    _one_sentence(argv, files, phrase, tmp_path, monkeypatch, capsys)


@pytest.mark.parametrize("command, name, attrs, phrase", FOREIGN, ids=[f"{c}-{n}-{p[:20]}" for c, n, _, p in FOREIGN])
def test_a_dataset_that_is_not_gyrolabs_is_one_sentence(command, name, attrs, phrase, tmp_path, monkeypatch, capsys):
    import numpy as np
    import xarray as xr

    (tmp_path / "ds").mkdir()
    xr.Dataset({"x": ("t", np.arange(3.0))}, attrs=attrs).to_netcdf(tmp_path / "ds" / name)
    _one_sentence([command, f"ds/{name}"], {}, phrase, tmp_path, monkeypatch, capsys)


#: overrides caught before any directory exists: budgets, magnitudes, degenerate vectors, output names
OVERRIDE_CORPUS = [
    (["time.n_output=abc"], "time.n_output='abc' must be an integer"),
    (["time.n_output=null"], "time.n_output=None must be an integer"),
    (["time.n_output=[1,2]"], "time.n_output"), (["time.n_output=1.5"], "time.n_output"),
    (["initial.r0=1e300"], "too large"), (["initial.r0=-1e300"], "too large"), (["initial.p0=1e200"], "too large"),
    (["body.a=1e300"], "too large"), (["time.end=1e300"], "too large"), (["accuracy=1e300"], "accuracy"),
    (["initial.r0=[1,2,3]"], "initial.r0"), (["initial.r0={x: 1}"], "initial.r0"),
    (["body.com_direction=[0,0,0]"], "force=[] for the torque-free Euler top"),
    (["body.com_direction=[0.0,0.0,0.0]"], "zero vector"),
    (["body=si_gyroscope", "body.com=[0,0,0]"], "body.com=[0, 0, 0] is a zero vector"),
    (["body.com_direction=[1e300,0,0]"], "too large"), (["body.com_direction=[nan,0,1]"], "finite"),
    (["force=[magnetic]", "force.magnetic.direction=[0,0,0]"], "unit vector"),
    (["initial.gamma0=[0,0,0]", "initial.theta0=null", "initial.phi0=null"], "|γ0| = 1"),
    (["integrator=auto", "accuracy=1e-31"], "below what double-double reaches"),
    (["force=[uniform_gravity,magnetic]", "force.magnetic.moment=[0,0,0]"], "leave magnetic out of the forces"),
    (["system=[]"], "no `system` section"), (["~integrator"], "integrator"),
    (["experiment=stability_map", "stability_map.theta0=[0,0]"], "one value"),
    (["experiment=stability_map", "stability_map.theta0=[1e300,1e301]"], "too large"),
    (["experiment=stability_map", "stability_map.file=a b.nc"], "stability_map.file"),
    (["experiment=stability_map", f"stability_map.file={'x' * 300}.nc"], "stability_map.file"),
    (["--batch", "experiment=stability_map", "batch.points=1000000000000", "hydra.sweep.dir=b"], "swept key"),
    (["integrator=auto", "accuracy=1e-17", "integrator.extended_precision=false"],
     "below what double precision reaches"),
    (["experiment=stability_map", "batch.points=0"], "batch.points=0 must be a positive integer"),
    (["experiment=stability_map", "batch.points=-5"], "must be a positive integer"),
    (["experiment=stability_map", "batch.points=1000000000000"], "beyond the budget of 1e+08 points"),
    (["experiment=stability_map", "stability_map.n_theta0=100000", "stability_map.n_r0=100000"], "budget"),
    (["experiment=stability_map", "stability_map.n_theta0=0"], "positive integer"),
    (["experiment=stability_map", "stability_map.file=../elsewhere/x.pth"], "inside the run directory"),
    (["experiment=stability_map", "stability_map.file=/tmp/x.nc"], "inside the run directory"),
    (["experiment=stability_map", "stability_map.file=x.pth"], "ending in .nc"),
    (["experiment=stability_map", "stability_map.file=sub/../../x.nc"], "no '/..'"),
    (["experiment=stability_map", "stability_map.file=~/x.nc"], "stability_map.file"),
    (["experiment=stability_map", "stability_map.file=''"], "stability_map.file"),
    (["experiment=stability_map", "stability_map.file=a\\\\b.nc"], "stability_map.file"),
    (["-m", "initial.r0=range(0,1e12,1)", "hydra.sweep.dir=sw"], "beyond the budget"),
    (["-m", "initial.r0=range(0,10000,1)", "body.a=range(1,100001,1)", "hydra.sweep.dir=sw"], "beyond the budget"),
    (["-m", "initial.r0=range(0,1,0)", "hydra.sweep.dir=sw"], "step must not be 0"),
    (["--batch", "initial.r0=range(0,1e12,1)", "hydra.sweep.dir=b"], "1e+12 points"),
    (["--batch", "initial.r0=range(0,1e9)", "hydra.sweep.dir=b"], "beyond the budget"),
    (["--batch", "initial.r0=range(0,1e6)", "body.a=range(1,1000,1)", "hydra.sweep.dir=b"], "beyond the budget"),
    (["--batch", "initial.r0=range(0,1,0)", "hydra.sweep.dir=b"], "step must not be 0"),
    (["--batch", "time.n_output=abc", "hydra.sweep.dir=b"], "time.n_output"),
    ([f"hydra.run.dir={'x' * 5000}"], "not a usable path"), (["hydra.run.dir=/etc/gyrolab_test_out"], "system directory"),
    (["hydra.run.dir=/proc/self/x"], "system directory"),
    (["hydra.run.dir=venv/lib/python3.11/site-packages/gyrolab_test_out"], "where Python loads code"),
    (["hydra.mode=MULTIRUN"], "disagrees with the command line"),
    (["experiment=stability_map", "stability_map.sections=[[1]]"], "must be [theta0, r0]"),
    (["experiment=stability_map", "stability_map.section_time=-1"], "must be a positive time"),
]


@pytest.mark.parametrize("argv, phrase", OVERRIDE_CORPUS, ids=[" ".join(a)[:60] for a, _ in OVERRIDE_CORPUS])
def test_override_corpus_is_refused_before_any_directory(argv, phrase, tmp_path, monkeypatch, capsys):
    _one_sentence(argv, {}, phrase, tmp_path, monkeypatch, capsys)


def test_a_symlink_loop_as_run_directory_is_one_sentence(tmp_path, monkeypatch, capsys):
    (tmp_path / "loop").symlink_to("loop")
    _one_sentence(["hydra.run.dir=loop/x"], {}, "loop of symbolic links", tmp_path, monkeypatch, capsys)


def test_a_run_directory_linked_into_site_packages_is_refused(tmp_path, monkeypatch, capsys):
    (tmp_path / "innocent").symlink_to(SITE)
    _one_sentence(["hydra.run.dir=innocent/out"], {}, "where Python loads code", tmp_path, monkeypatch, capsys)


def test_a_config_file_linked_to_a_device_is_refused_without_blocking(tmp_path, monkeypatch, capsys):
    (tmp_path / "cd" / "experiment").mkdir(parents=True)
    (tmp_path / "cd" / "experiment" / "zero.yaml").symlink_to("/dev/zero")
    _one_sentence(["--config-dir", "cd", "experiment=zero"], {}, "not a regular file", tmp_path, monkeypatch, capsys)


def test_the_whole_corpus_is_large():
    assert len(CORPUS) + len(CASES) + len(FILE_CORPUS) + len(FOREIGN) + len(OVERRIDE_CORPUS) >= 200


# ---- exit paths (subprocess): no hang, and no lock left behind by a failed run ----------------------------------

def test_an_alias_bomb_in_a_config_dir_does_not_hang(cli, tmp_path):
    (tmp_path / "cd" / "experiment").mkdir(parents=True)
    (tmp_path / "cd" / "experiment" / "bomb.yaml").write_text(BOMB)
    done = cli("--config-dir", "cd", "experiment=bomb", "hydra.run.dir=out")  # the fixture's timeout bounds it
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines() == [next(iter(done.stderr.strip().splitlines()))]
    assert "anchors and aliases" in done.stderr and not (tmp_path / "out").exists()


def test_a_failed_run_leaves_no_lock(cli, tmp_path):
    # a step too long for the spin is found when the integration starts, after the run directory exists; a folder
    # Hydra made for the run goes with it (tests/app/test_cli.py), one the user gave stays, without the lock
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "notes.txt").write_text("the user's")
    done = cli("integrator=rk4", "integrator.step=5", "initial.r0=50", "time.end=2000", "output.figures=false",
               "hydra.run.dir=out")
    assert done.returncode != 0 and done.stderr.strip().splitlines()[-1].startswith("gyrolab: error: ")
    assert (tmp_path / "out" / "notes.txt").exists()
    assert not (tmp_path / "out" / ".gyrolab.lock").exists()
    assert not list((tmp_path / "out").rglob("*.part")) and not (tmp_path / "out" / "run.nc").exists()


def test_an_output_file_through_a_symlink_out_of_the_run_directory_is_refused(tmp_path, monkeypatch, capsys):
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "link").symlink_to(tmp_path / "elsewhere")
    _one_sentence(["experiment=stability_map", "stability_map.file=link/x.nc"], {}, "through a symbolic link",
                  tmp_path, monkeypatch, capsys)


def test_confined_output_path_keeps_a_plain_name_inside(tmp_path):
    from gyrolab.engine.safety import confined_output_path

    assert confined_output_path(tmp_path, "maps/a.nc", "k") == tmp_path.resolve() / "maps" / "a.nc"
    for bad in ("../a.nc", "/abs/a.nc", "a.pth", "", None, "a/../../b.nc", "~/a.nc", "a\\b.nc", 5):
        with pytest.raises(ConfigError):
            confined_output_path(tmp_path, bad, "k")
