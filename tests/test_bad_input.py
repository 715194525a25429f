"""Bad input: one sentence naming the bad value and what is valid, a non-zero exit, no run.nc."""

import sys

import pytest

from gyrolab import app

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

def run_main(argv, monkeypatch, capsys):
    """``gyrolab ARGV`` in this process: (exit code, stderr)."""
    from gyrolab.engine.config import ConfigSource, use_source

    monkeypatch.setattr(sys, "argv", ["gyrolab", *argv])
    try:
        app.main()
        code = 0
    except SystemExit as stop:
        code = stop.code
    finally:
        use_source(ConfigSource())
    return code, capsys.readouterr().err


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
