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
