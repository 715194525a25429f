"""The regime tasks: regime run dataset/figure, Tables 1-2 of seed 000, ω = 3 Euler angles, validity verdict."""

import numpy as np
import pytest
import xarray as xr

from gyrolab.engine.config import compose_config
from gyrolab.errors import ConfigError
from gyrolab.experiments import run_task
from gyrolab.experiments.regime_run import angles_from_states
from tests.helpers.regimes import B1, overrides_000, overrides_001, run_case


def test_regime_run_writes_a_self_describing_dataset_and_figure(tmp_path):
    written = run_task("regime", compose_config([*overrides_000(20.0), "regime.periods=2"]), tmp_path)
    assert {p.name for p in written} == {"regime.nc", "regime_comparison.png"}
    ds = xr.open_dataset(tmp_path / "regime.nc")
    for name, var in {**ds.data_vars, **ds.coords}.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert "analytic orbit starts from its own p0" in ds.attrs["regime_warnings"]
    assert ds.newton_residual.values[-1] < 1e-13
    # ε = 0.05: analytic vs exact orbit errors of order ε³..ε⁴ (relative to c and r0)
    assert ds.max_error_vs_orbit.values[:2].max() < 1e-3
    # the reduced system (000 eq. 14 through μ⁻³, integrated numerically) against the exact orbit over two
    # periods at μ = r0/c = 20, started at the analytic τ = 0 state, not on the orbit (measured 9.2e-5 and 1.2e-5)
    assert ds.omega_reduced.shape == ds.omega_orbit.shape
    assert np.allclose(ds.omega_reduced.values[0], ds.omega_analytic.values[0], atol=1e-12)  # same τ = 0 state
    err = ds.max_error_reduced_vs_orbit.values
    assert 1e-5 < err[:2].max() < 4 * 20.0**-3
    assert err[3:].max() < 4 * 20.0**-4
    assert "regime_comparison.png" in {p.name for p in written}
    # the reduced system's Euler angles (ψ by quadrature of eq. 29): O(μ⁻²)-close to the exact orbit's
    for name in ("psi", "theta", "phi"):
        assert np.abs(ds[f"{name}_reduced"].values - ds[f"{name}_orbit"].values).max() < 1e-3


def test_euler_angles_by_quadrature_match_the_fixed_axis():
    # ψ from ψ̇ = (pγ + qγ')/(1 − γ''²) on the samples against ψ from the integrated fixed axis α (full model)
    scene, regime, t, result = run_case(overrides_001(B1, 0.05), samples=200, full=True)
    for source in ("orbit", "full"):
        angles = angles_from_states(t, result["states"][source], float(result["angles"][source]["psi"][0]))
        for name, values in angles.items():
            assert np.abs(values - result["angles"][source][name]).max() < 1e-9, (source, name)


def test_reduced_system_is_integrated_by_the_scenes_integrator(tmp_path):
    # seed 001's eq. (1) is an exact linear rescaling of the full model and RK4 is invariant under linear changes
    # of variables: integrated by the scene's rk4 with the same step, reduced and full agree to round-off
    # (measured 1e-15); a different method differs from the full model's RK4 by RK4's truncation error (2e-9)
    rk4 = run_task("regime", compose_config([*overrides_001(B1, 0.05), "integrator=rk4", "integrator.step=0.002"]),
                   tmp_path / "rk4")
    ds = xr.open_dataset(rk4[0])
    assert ds.attrs["reduced_system_integrator"] == "rk4"
    scale = np.abs(ds.omega_full.values).max()
    assert np.abs(ds.omega_reduced.values - ds.omega_full.values).max() < 1e-11 * scale
    compiled = run_task("regime", compose_config([*overrides_001(B1, 0.05), "integrator=rk4_numba",
                                                  "integrator.step=0.002"]), tmp_path / "numba")
    ds = xr.open_dataset(compiled[0])
    assert ds.attrs["reduced_system_integrator"].startswith("dop853")  # compiled-only: DOP853 stands in, recorded
    assert "rk4_numba" in ds.attrs["reduced_system_integrator"]
    assert np.abs(ds.omega_reduced.values - ds.omega_full.values).max() > 1e-10 * scale


def test_printed_branch_ii_run_records_what_the_orbit_search_found(tmp_path):
    B3 = dict(a=0.4, b=1 / 7, rc=(0.48, 0.36, -0.8), k=2.0, theta0=np.pi / 3)
    cfg = compose_config([*overrides_001(B3, 0.02, "printed"), "regime.branch=ii", "force.newtonian.R=null"])
    ds = xr.open_dataset(run_task("regime", cfg, tmp_path)[0])
    assert "branch ii as printed: not a periodic solution" in ds.attrs["regime_warnings"]
    assert ds.attrs["regime_branch"] == "ii"
    if ds.attrs["exact_orbit"] == "found":  # it is a branch (iii) orbit: O(1) away from (ii) in p, q
        assert ds.max_error_vs_orbit.values[:2].max() > 1.0
    else:
        assert ds.attrs["exact_orbit"].startswith("not found: Newton shooting did not converge")
        assert "omega_orbit" not in ds


def test_bad_regime_input_writes_nothing(tmp_path):
    with pytest.raises(ConfigError):
        run_task("regime", compose_config(["regime=resonant_omega3"]), tmp_path)
    assert not list(tmp_path.iterdir())


def test_tables_within_published_print_precision(tmp_path):
    run_task("ismail2021_tables", compose_config(["experiment=ismail2021_tables"]), tmp_path)
    for n in (1, 2):
        header = (tmp_path / f"table{n}.csv").read_text().splitlines()[0]
        assert header == "t,p2,gamma2,dp2,dgamma2"
        table = np.loadtxt(tmp_path / f"table{n}.csv", delimiter=",", skiprows=1)
        assert np.array_equal(table[:, 0], np.arange(0, 301, 10))
    ds = xr.open_dataset(tmp_path / "ismail2021_tables.nc")
    # Table 1 and the p2 columns of Table 2 within one unit of the last printed digit; Table 2's γ2 columns
    # within 1.2 units (report §7: RK4 with ω_γ = 1 reproduces them to 1.2e-6; the paper's float32 noise)
    assert ds.max_deviation_print_units1.values.max() <= 1.02
    assert ds.max_deviation_print_units2.values[[0, 2]].max() <= 1.0
    assert ds.max_deviation_print_units2.values[[1, 3]].max() <= 1.25


def test_shaker_omega3_euler_angles_match_the_report(tmp_path):
    run_task("shaker_omega3", compose_config(["experiment=shaker_omega3"]), tmp_path)
    ds = xr.open_dataset(tmp_path / "shaker_omega3.nc")
    # report §9: series vs full model over [0, 20]: θ 3.9e-4, ψ 1.1e-2, φ 2.4e-2 rad; exact period 0.70318806
    assert ds.attrs["max_error_theta"] == pytest.approx(3.9e-4, rel=0.1)
    assert ds.attrs["max_error_psi"] == pytest.approx(1.1e-2, rel=0.1)
    assert ds.attrs["max_error_phi"] == pytest.approx(2.4e-2, rel=0.1)
    assert ds.attrs["period_exact"] == pytest.approx(0.70318806, abs=1e-8)


@pytest.mark.slow
def test_regime_validity_verdict(tmp_path):
    cfg = compose_config(["experiment=regime_validity",
                          "regime_validity.small_parameter.values=[2.0,0.0625,0.03125,0.015625]",
                          "regime_validity.resonant_omega3.values=[0.05,0.035,0.025]",
                          "regime_validity.resonant_omega3_iii.values=[0.4,0.01,0.005,0.0025]",
                          "regime_validity.large_parameter.values=[16.0]",
                          "regime_validity.resonance_sweep.distances=[0.1,0.05,0.025,0.01]"])
    run_task("regime_validity", cfg, tmp_path)
    ds = xr.open_dataset(tmp_path / "regime_validity.nc")
    verdict = ds.attrs["verdict"]
    assert "small_parameter" in verdict and "NOT consistent" not in verdict
    # seed 001's branch (iii): orders 1 (p, q) and 2 against exact orbits; far out (μ = 0.4) no orbit near the series
    assert "resonant_omega3_iii" in verdict
    assert ds.resonant_omega3_iii_status.values[0].startswith("failed: Newton shooting did not converge")
    assert ds.resonant_omega3_iii_order_pq.item() == pytest.approx(1.0, abs=0.2)
    assert ds.resonant_omega3_iii_order_gamma.item() == pytest.approx(2.0, abs=0.2)
    assert ds.small_parameter_status.values[0].startswith("refused")
    assert ds.small_parameter_order_pq.values == pytest.approx(3, abs=0.2)
    assert ds.large_parameter_error_gamma3_vs_orbit.values[0] > 0.5  # report §3: 0.97 at μ = 16
    assert (tmp_path / "figures" / "regime_validity.png").exists()
    # ω swept across the resonances 1, 2: |ω − n| = 0.01 refused (not crashed), the rest computed, error growing
    assert "near the resonance ω = 1" in verdict and "near the resonance ω = 2" in verdict
    status = ds.resonance_status.values
    assert all(s.startswith("refused") for s in status[:, :, 3].ravel())
    assert all(s == "ok" for s in status[:, :, :3].ravel())
    e = ds.resonance_error_max_vs_orbit.values[:, :, :3]
    assert np.all(np.diff(e, axis=-1) > 0)
    assert ds.resonance_exponent_max.sel(resonance=2.0).item() == pytest.approx(1.0, abs=0.15)
    assert ds.resonance_omega.attrs["units"] == "1"


def test_reproduce_reruns_the_task_that_wrote_a_regime_nc(tmp_path, monkeypatch, capsys):
    import sys

    from gyrolab import app

    run_task("regime", compose_config([*overrides_000(20.0), "regime.periods=1", "output.figures=false"]), tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", "reproduce", str(tmp_path / "regime.nc")])
    with pytest.raises(SystemExit) as stop:
        app.main()
    out = capsys.readouterr().out
    assert stop.value.code == 0, out
    assert "task regime run again" in out and "identical:" in out and "NOT" not in out   # not one scene's variables
