"""experiment=orbit_family on a short stretch of the pendulum body's family, and the continuation's labels.

Evidence independent of the continuation code: each point's initial state returns to itself after its period under
scipy's DOP853 on the Euler–Poisson equations written out here; at r0/c = 0.01 the period is the pendulum's (exact
quadrature, elliptic integrals) to O((r0/c)²); the labels follow their definitions on constructed monodromy traces."""

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import solve_ivp

import gyrolab.experiments as experiments
from gyrolab.engine.config import compose_config
from gyrolab.errors import ConfigError
from gyrolab.physics import pendulum
from gyrolab.analysis.continuation import FamilyPoint, bifurcations

FAMILY = ["experiment=orbit_family", "~orbit_family.families.default_body", "~orbit_family.families.ismail2021_body_I",
          "orbit_family.families.pendulum_body.r0_end=0.1", "orbit_family.families.pendulum_body.max_points=12"]


def euler_poisson(t, y, a=2.0, b=1.5, k=0.3):
    """I ω̇ = Iω × ω + e_z × γ + k γ × Iγ, γ̇ = γ × ω, I = diag(a, b, 1), centre of mass on +z."""
    w, g = y[:3], y[3:]
    inertia = np.array([a, b, 1.0])
    torque = np.cross(inertia * w, w) + np.cross([0.0, 0.0, 1.0], g) + k * np.cross(g, inertia * g)
    return np.concatenate([torque / inertia, np.cross(g, w)])


def test_short_family_from_the_pendulum(tmp_path):
    written = experiments.run_task("orbit_family", compose_config(FAMILY), tmp_path)
    assert {p.name for p in written} == {"orbit_family.nc", "orbit_family.png"}
    with xr.open_dataset(tmp_path / "orbit_family.nc") as ds:
        for name in ("r0_over_c", "period", "initial_state", "floquet_multiplier_real", "floquet_multiplier_imag",
                     "stable", "error_slow_spin_series"):
            assert name in ds and ds[name].attrs["units"] and ds[name].attrs["long_name"], name
        assert ds.initial_state.dims == ("point", "component") and ds.floquet_multiplier_real.dims == ("point", "multiplier")
        r0, period, y0 = ds.r0_over_c.values, ds.period.values, ds.initial_state.values
        assert r0[0] == 0.01 and r0[-1] >= 0.1 and np.all(np.diff(r0) > 0)
        T0 = pendulum.period(1.5, pendulum.kappa(2.0, 0.3), 1.0)
        assert abs(period[0] - T0) < 10 * 0.01 ** 2      # T − T0 = O(ε²): measured −5.5e-4
        for i in (0, len(r0) // 2, len(r0) - 1):
            sol = solve_ivp(euler_poisson, (0, period[i]), y0[i], method="DOP853", rtol=1e-12, atol=1e-12)
            assert np.max(np.abs(sol.y[:, -1] - y0[i])) < 1e-8
        s = ds.stability_index.values
        assert np.array_equal(ds.stable.values, (np.abs(s) <= 2 + 1e-6).astype(int))
        assert s[0] > 2   # the swing about the intermediate axis is unstable out of plane
        assert np.nanmax(ds.error_slow_spin_series.values[r0 <= 0.05]) < 1e-6


def _point(r0, index, direction):
    monodromy = np.diag([1.0, 1.0, 1.0, 1.0, 0.0, 0.0])
    monodromy[4, 4] = monodromy[5, 5] = index / 2  # trace − 4 = index
    return FamilyPoint(r0, 1.0, np.zeros(6), monodromy, 0.0, np.array([0, 0, 0, direction]))


def test_bifurcation_labels_follow_their_definitions():
    points = [_point(1.0, 1.0, 1), _point(1.1, 3.0, 1), _point(1.2, 3.5, -1), _point(1.1, 1.0, -1),
              _point(1.0, -3.0, -1)]
    assert bifurcations(points) == [(1, "branch point"), (2, "fold"), (3, "branch point"), (4, "period doubling")]
    assert [p.stable for p in points] == [True, False, False, True, False]


def test_a_family_needs_its_settings():
    with pytest.raises(ConfigError, match="theta0"):
        experiments.run_task("orbit_family", compose_config([*FAMILY, "orbit_family.families.pendulum_body.theta0=x"]),
                             "unused")


def _monodromy_by_scipy(y0, period, h=1e-6):
    """Φ(T) by central differences of the flow of the Euler–Poisson equations written above (scipy's DOP853)."""
    columns = []
    for j in range(6):
        ends = []
        for sign in (1, -1):
            y = np.array(y0, dtype=float)
            y[j] += sign * h
            ends.append(solve_ivp(euler_poisson, (0, period), y, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1])
        columns.append((ends[0] - ends[1]) / (2 * h))
    return np.column_stack(columns)


@pytest.mark.slow
def test_branch_points_are_located_where_the_multipliers_cross_one(tmp_path):
    # issue 22: the labels sat on the next family point (0.380, 1.139, 1.579); an independent review found the
    # multipliers crossing +1 at r0/c = 0.266, 0.973, 1.237 on the pendulum body's family
    family = ["experiment=orbit_family", "~orbit_family.families.default_body",
              "~orbit_family.families.ismail2021_body_I", "orbit_family.families.pendulum_body.r0_end=1.6"]
    experiments.run_task("orbit_family", compose_config(family), tmp_path)
    with xr.open_dataset(tmp_path / "orbit_family.nc") as ds:
        branch = ds.event_kind.values == "branch point"
        np.testing.assert_allclose(ds.event_r0_over_c.values[branch], [0.266, 0.973, 1.237], rtol=2e-3)
        np.testing.assert_allclose(ds.event_stability_index.values[branch], 2.0, atol=1e-4)
        # at the located orbit, the monodromy matrix computed independently has tr Φ − 4 = ρ + 1/ρ = 2
        y0, period = ds.event_initial_state.values[branch][0], float(ds.event_period.values[branch][0])
        assert np.trace(_monodromy_by_scipy(y0, period)) - 4 == pytest.approx(2.0, abs=1e-4)
