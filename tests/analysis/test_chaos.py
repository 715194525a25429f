"""Chaos indicators (gyrolab.analysis.chaos): the variational equations, MEGNO and FLI on scenes whose answer is known.

Known answers, none taken from the kernel under test:
* the generated tangent flow's J u: central finite differences of the compiled right-hand side;
* integrable cases — Euler–Poinsot (no torque), Lagrange (A = B, centre of mass on the symmetry axis),
  Kovalevskaya (A = B = 2C, centre of mass in the equatorial plane) — are regular for every initial
  condition, so MEGNO ⟨Y⟩ → 2 (quasi-periodic) or 0 (periodic) and stops growing (Cincotta & Simó 2000);
* a chaotic heavy-top scene: the separation of two trajectories 1e-9 apart, integrated by scipy's DOP853 at
  rtol 1e-12, grows exponentially at a rate λ; then ⟨Y⟩(t) ≈ λt/2 and FLI(t) ≈ λt (same paper; Froeschlé et al. 1997).
"""

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_arrays
from gyrolab.errors import ConfigError
from gyrolab.analysis.chaos import indicator_outputs, megno_run, poincare_section, section_dataset
from gyrolab.kernels import models, rk4, tangent

BASE = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=1", "time.n_output=11", "output.euler_angles=false"]
#: integrable bodies and torques (docs/stability_map.md cites the sources)
INTEGRABLE = {
    "euler_poinsot": ["force=[]"],
    "lagrange": ["body=lagrange_top", "force=[uniform_gravity]"],
    "kovalevskaya": ["body.a=2", "body.b=2", "body.com_direction=[1,0,0]", "force=[uniform_gravity]"],
}
#: the default body (a = 2, b = 1.5, r_c = (0.3, 0.2, 0.933), Newtonian k = 0.5) at moderate spin
CHAOTIC = ["initial.theta0=1.0", "initial.r0=2.0", "initial.p0=0.3", "initial.q0=-0.2"]


def _scene(*overrides):
    return compose_scene([*BASE, *overrides])


def _states(scene, theta0s, r0s):
    """Initial (ω, γ) rows for (θ0, r0) pairs, φ0 = π/2, the scene's p0 and q0."""
    base = scene.system.initial_state()
    rows = []
    for theta0, r0 in zip(theta0s, r0s):
        y = base.copy()
        y[2] = r0
        y[3:6] = np.sin(theta0), 0.0, np.cos(theta0)
        rows.append(y)
    return np.array(rows)


def test_generated_tangent_flow_matches_finite_differences_of_the_compiled_rhs():
    rng = np.random.default_rng(1)
    for overrides in ([], ["body=lagrange_top"], ["force=[newtonian]"]):
        compiled = _scene(*overrides).system.compiled_model()
        p = compiled.params
        augmented = tangent.compiled_megno(compiled)
        q = tangent.megno_params(augmented, p)[0]

        def f(t, y, params):
            out = np.empty(len(y))
            models.evaluate(t, np.ascontiguousarray(y), params, out)
            return out
        rhs = lambda y: f(0.0, y, p)  # noqa: E731
        for _ in range(4):
            y = np.concatenate([rng.normal(size=3), rng.normal(size=3)])
            y[3:6] /= np.linalg.norm(y[3:6])
            h = 1e-6
            J = np.stack([(rhs(y + h * e) - rhs(y - h * e)) / (2 * h) for e in np.eye(6)], axis=1)
            # the augmented right-hand side (x, u, ℓ, a, b) at t = 2, a = 0.3: f, J u − λ u, λ = u·J u, t λ, 2a/t
            d = rng.normal(size=6)
            d /= np.linalg.norm(d)
            aug = f(2.0, np.concatenate([y, d, [0.0, 0.3, 0.0]]), q)
            lam = d @ J @ d
            np.testing.assert_allclose(aug[:6], rhs(y), rtol=1e-14, atol=1e-14)
            np.testing.assert_allclose(aug[6:], [*(J @ d - lam * d), lam, 2.0 * lam, 0.3], rtol=1e-7, atol=1e-8)
            # the linearised flow keeps γ·δγ: d/dt(γ·δγ) = γ̇·δγ + γ·δγ̇ = 0 for every δ (the constraint |γ| = 1)
            assert abs(rhs(y)[3:6] @ d[3:6] + y[3:6] @ (J @ d)[3:6]) < 1e-8


def test_initial_tangent_is_unit_and_tangent_to_the_sphere():
    y0 = _states(_scene(), [0.3, 1.5, 3.0], [1.0, 2.0, 3.0])
    d = tangent.direction(y0, slice(3, 6))
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.sum(d[:, 3:6] * y0[:, 3:6], axis=1), 0.0, rtol=0, atol=1e-15)
    z0 = tangent.initial_augmented(y0, d)
    np.testing.assert_array_equal(z0[:, :6], y0)
    np.testing.assert_array_equal(z0[:, 12:], 0.0)  # ℓ = ln|δ| = 0 and the MEGNO quadratures start at 0


@pytest.mark.parametrize("case", sorted(INTEGRABLE))
def test_integrable_cases_are_regular(case):
    scene = _scene(*INTEGRABLE[case])
    y0 = _states(scene, [0.1, 0.4, 1.0, 1.5, 2.5, 3.0], [0.1, 0.5, 1.0, 2.0, 3.0, 0.2])
    times = np.array([0.0, 100.0, 300.0, 1000.0])
    megno = megno_run(scene.system.compiled_model(), scene.integrator, times, y0)["megno"]
    # regular quasi-periodic: ⟨Y⟩ → 2 from below, the deviation decaying like ln²t / t; never above 2 (+ rounding).
    # A chaotic orbit with λ ≥ 0.01 would be at ⟨Y⟩ ≈ λt/2 ≥ 5 by t = 1000. How fast it nears 2 depends on the initial
    # tangent vector: the slowest here, the Lagrange top's θ0 = 0.1, r0 = 0.1 swing (a long period near the sleeping
    # top's separatrix), is at 1.44 at t = 1000 and 1.75 at t = 4000, still rising.
    assert np.all(megno <= 2.05), megno
    np.testing.assert_allclose(megno[:, -1], 2.0, rtol=0, atol=0.6)
    assert np.all((megno[:, -1] > megno[:, -2]) | (megno[:, -1] > 1.9)), megno  # the slow ones still approach 2


def _euler_poisson(inertia, com, k):
    """The Euler–Poisson equations written out for scipy (independent of gyrolab's kernels), in the model units
    of body.py: I ω̇ = Iω × ω + r_c × γ + k γ × Iγ, γ̇ = γ × ω; any number of stacked 6-D states."""
    A, B, C = inertia
    x, y, z = com

    def f(t, s):
        p, q, r, g1, g2, g3 = s.reshape(-1, 6).T
        return np.stack([
            ((B - C) * q * r + y * g3 - z * g2 + k * (C - B) * g2 * g3) / A,
            ((C - A) * r * p + z * g1 - x * g3 + k * (A - C) * g3 * g1) / B,
            ((A - B) * p * q + x * g2 - y * g1 + k * (B - A) * g1 * g2) / C,
            g2 * r - g3 * q, g3 * p - g1 * r, g1 * q - g2 * p], axis=1).ravel()
    return f


def test_chaotic_heavy_top_megno_grows_at_the_independent_lyapunov_rate():
    scene = _scene(*CHAOTIC)
    y0 = scene.system.initial_state()
    # independent: two nearby trajectories by scipy DOP853 (rtol 1e-12), the default body's parameters as in the config
    f = _euler_poisson(np.array([2.0, 1.5, 1.0]), np.array([0.3, 0.2, 0.9327379053088815]), 0.5)
    offset = np.array([1.0, -1.0, 1.0, 0.0, 0.0, 0.0]) * 1e-9 / np.sqrt(3)
    t_fit = np.linspace(0.0, 130.0, 27)
    both = solve_ivp(f, (0.0, 130.0), np.concatenate([y0, y0 + offset]), method="DOP853", rtol=1e-12, atol=1e-12,
                     t_eval=t_fit)
    separation = np.linalg.norm(both.y[:6] - both.y[6:], axis=0)
    assert separation[-1] < 1e-2  # still in the linear regime: the fit measures growth, not saturation
    assert separation[-1] / separation[0] > 1e4  # a regular orbit separates at most linearly in t (~ 100×)
    lyapunov = np.polyfit(t_fit, np.log(separation), 1)[0]
    assert lyapunov > 0.05  # a lower bound: the unrenormalised pair still carries its alignment transient
    T = 200.0
    run = megno_run(scene.system.compiled_model(), scene.integrator, np.linspace(0.0, T, 5), y0[None])
    megno = run["megno"][0]
    assert megno[-1] > 4.0 and megno[-1] > 0.25 * lyapunov * T  # ⟨Y⟩ ≈ λt/2, with room for the transient
    assert megno[-1] > megno[2] + 0.1 * lyapunov * T / 2  # and still growing
    assert 0.5 * lyapunov < run["fli"][0] / T < 2.0 * lyapunov  # FLI ≈ λt


def _benettin(f, y0, T, tau=1.0, d0=1e-8):
    """Largest Lyapunov exponent by Benettin et al. (1980): a companion trajectory d0 away, renormalised every tau,
    the mean log stretch; integrated by scipy's DOP853 at rtol 1e-12 on the equations written in this file."""
    x = np.array(y0, dtype=float)
    v = np.array([1.0, -1.0, 1.0, 0.0, 0.0, 0.0])
    v[3:] -= (v[3:] @ x[3:]) * x[3:]  # tangent to |γ| = 1
    v /= np.linalg.norm(v)
    total = 0.0
    for _ in range(int(T / tau)):
        both = solve_ivp(f, (0.0, tau), np.concatenate([x, x + d0 * v]), method="DOP853", rtol=1e-12, atol=1e-12)
        x, stretched = both.y[:6, -1], both.y[6:, -1] - both.y[:6, -1]
        total += np.log(np.linalg.norm(stretched) / d0)
        v = stretched / np.linalg.norm(stretched)
    return total / T


@pytest.mark.slow
def test_megno_and_fli_rates_equal_the_independent_largest_lyapunov_exponent():
    # docs/stability_map.md gave λ = 0.081 for this top: the slope of an unrenormalised pair over [0, 130], which
    # still carries its alignment transient. The exponent is the long-time rate (Benettin): 0.127 at T = 1000 and
    # 0.128 at 2000 here; MEGNO grows like λt/2 and FLI like λt
    scene = _scene(*CHAOTIC)
    y0 = scene.system.initial_state()
    f = _euler_poisson(np.array([2.0, 1.5, 1.0]), np.array([0.3, 0.2, 0.9327379053088815]), 0.5)
    T = 1000.0
    lyapunov = _benettin(f, y0, T)
    assert 0.10 < lyapunov < 0.16
    t = np.linspace(0.0, T, 21)
    run = megno_run(scene.system.compiled_model(), scene.integrator, t, y0[None])
    late = t > T / 2
    megno_rate = 2 * np.polyfit(t[late], run["megno"][0][late], 1)[0]
    assert megno_rate == pytest.approx(lyapunov, rel=0.2)
    assert run["fli"][0] / T == pytest.approx(lyapunov, rel=0.2)


def test_indicator_outputs_interface_and_nutation_deviation_against_the_batch_kernel():
    scene = _scene(*CHAOTIC)
    y0 = _states(scene, [0.5, 1.0, 2.0], [3.0, 2.0, 0.5])
    times = np.linspace(0.0, 5.0, 501)  # every RK4 step is an output: the same steps as the indicator kernel
    out = indicator_outputs(scene.system.compiled_model(), scene.integrator, times[[0, -1]], y0)
    assert set(out) == {"indicator", "fli", "max_nutation_deviation"}
    for values, attrs in out.values():
        assert values.shape == (3,) and np.all(np.isfinite(values))
        assert attrs["units"] and attrs["long_name"]
    assert out["indicator"][1]["indicator_name"] == "MEGNO" and "Cincotta" in out["indicator"][1]["definition"]
    assert out["max_nutation_deviation"][1]["units"] == "rad"
    states = integrate_arrays(scene.system.compiled_model(), scene.integrator, times, y0).y
    theta = np.arccos(np.clip(states[:, :, 5], -1, 1))
    np.testing.assert_allclose(out["max_nutation_deviation"][0], np.max(np.abs(theta - theta[:, :1]), axis=1),
                               rtol=0, atol=1e-12)


def test_trajectories_are_independent_across_blocks_and_a_failure_stays_local():
    scene = _scene(*CHAOTIC)
    n = rk4.BLOCK + 5  # two blocks of the batch kernel, the second partial
    y0 = _states(scene, np.linspace(0.2, 2.8, n), np.linspace(0.2, 4.0, n))
    y0[3, 2] = 1e6  # ω h = 1e4: RK4 blows up
    compiled, times = scene.system.compiled_model(), np.array([0.0, 2.0, 4.0])
    batch = megno_run(compiled, scene.integrator, times, y0)
    assert batch["failed"].tolist() == [j == 3 for j in range(n)]
    assert np.isnan(batch["fli"][3]) and np.isnan(batch["final_state"][3]).all()
    for j in (0, 4, n - 1):  # alone = in the batch, bit for bit
        alone = megno_run(compiled, scene.integrator, times, y0[j:j + 1])
        for key in ("megno", "fli", "max_nutation_deviation", "final_state"):
            np.testing.assert_array_equal(alone[key][0], batch[key][j])


def test_reading_every_step_in_windows_or_the_trajectories_in_groups_changes_nothing(monkeypatch):
    """A fixed-step run goes on from its last step in windows of time, an adaptive run takes the trajectories in
    groups, both when the samples would exceed chaos.MEMORY: bit for bit the results of one call."""
    from gyrolab.analysis import chaos

    scene = _scene(*CHAOTIC)
    y0 = _states(scene, np.linspace(0.2, 2.8, 300), np.linspace(0.2, 4.0, 300))
    compiled, times = scene.system.compiled_model(), np.array([0.0, 1.0, 3.0])
    dop = compose_scene(["integrator=dop853_numba", "integrator.rtol=1e-8", "integrator.atol=1e-8"]).integrator
    whole = [megno_run(compiled, integrator, times, y0) for integrator in (scene.integrator, dop)]
    monkeypatch.setattr(chaos, "MEMORY", 1)  # windows of 64 steps (300 steps: 5), groups of 256 trajectories (2)
    for integrator, expected in zip((scene.integrator, dop), whole):
        parts = megno_run(compiled, integrator, times, y0)
        for key in ("megno", "fli", "max_nutation_deviation", "final_state", "steps"):
            np.testing.assert_array_equal(parts[key], expected[key])


def test_a_state_carrying_alpha_gives_the_same_indicators():
    with_alpha = _scene(*CHAOTIC[:2], "output.euler_angles=true")
    without = _scene(*CHAOTIC[:2])
    times = np.array([0.0, 20.0])
    a = indicator_outputs(with_alpha.system.compiled_model(), with_alpha.integrator, times,
                          with_alpha.system.initial_state()[None])
    b = indicator_outputs(without.system.compiled_model(), without.integrator, times, without.system.initial_state()[None])
    assert with_alpha.system.state_size == 9
    for key in a:
        np.testing.assert_array_equal(a[key][0], b[key][0])


def test_bad_input_is_refused_in_one_sentence():
    scene = _scene()
    compiled, y0 = scene.system.compiled_model(), scene.system.initial_state()[None]
    with pytest.raises(ConfigError, match="rk4"):
        indicator_outputs(compiled, compose_scene(["integrator=radau"]).integrator, [0.0, 1.0], y0)
    with pytest.raises(ConfigError, match="norm"):
        indicator_outputs(compiled, scene.integrator, [0.0, 1.0], y0 * 2)
    with pytest.raises(ConfigError, match="finite"):
        indicator_outputs(compiled, scene.integrator, [0.0, 1.0], y0 * np.nan)
    with pytest.raises(ConfigError, match="increasing"):
        indicator_outputs(compiled, scene.integrator, [1.0, 0.0], y0)
    magnetic = compose_scene([*BASE, "force=[uniform_gravity,magnetic]", "force.magnetic.direction=[1,0,0]"])
    with pytest.raises(ConfigError, match="vertical"):
        indicator_outputs(magnetic.system.compiled_model(), magnetic.integrator, [0.0, 1.0],
                          magnetic.system.initial_state()[None])


def test_poincare_section_crossings_against_scipy_events_and_the_lagrange_integral():
    scene = _scene("body=lagrange_top", "force=[uniform_gravity]", "initial.theta0=1.0", "initial.r0=3.0",
                   "initial.p0=0.4", "initial.q0=0.1")
    y0 = scene.system.initial_state()
    section = poincare_section(scene.system.compiled_model(), y0, 30.0, 0.005)
    assert len(section["t"]) >= 3
    np.testing.assert_allclose(section["state"][:, 5], np.cos(1.0), rtol=0, atol=1e-9)  # on the section
    np.testing.assert_allclose(section["r"], 3.0, rtol=0, atol=1e-9)  # Lagrange top: ω3 is a first integral

    def gamma3(t, y):
        return y[5] - np.cos(1.0)
    gamma3.direction = 1.0
    f = _euler_poisson(np.array([0.8, 0.8, 1.0]), np.array([0.0, 0.0, 1.0]), 0.0)
    ref = solve_ivp(f, (0.0, 30.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, events=gamma3)
    expected = ref.t_events[0][ref.t_events[0] > 1e-9]
    np.testing.assert_allclose(section["t"], expected[:len(section["t"])], rtol=0, atol=1e-7)
    assert len(expected) == len(section["t"])


def test_stability_map_figure_from_a_small_real_map(tmp_path):
    from gyrolab.figures import redraw

    scene = _scene()
    theta0, r0 = np.array([0.5, 1.0, 2.0]), np.array([0.1, 1.0, 5.0, 8.0])
    th, rr = np.meshgrid(theta0, r0, indexing="ij")
    y0 = _states(scene, th.ravel(), rr.ravel())
    out = indicator_outputs(scene.system.compiled_model(), scene.integrator, [0.0, 20.0], y0)
    ds = xr.Dataset({k: (("theta0", "r0"), v.reshape(th.shape), a) for k, (v, a) in out.items()},
                    coords={"theta0": ("theta0", theta0, {"units": "rad"}), "r0": ("r0", r0, {"units": "1"})},
                    attrs={"body_nondim_a": 2.0, "body_nondim_b": 1.5})
    ds["indicator"][0, 0] = np.nan  # a failed point is drawn grey, not dropped
    ds = ds.merge(section_dataset(scene.system.compiled_model(), y0[:2], th.ravel()[:2], rr.ravel()[:2], 20.0, 0.01))
    ds.to_netcdf(tmp_path / "stability_map.nc")
    paths = redraw.draw_dataset(tmp_path / "stability_map.nc", dpi=60)  # what gyrolab --plot does
    assert [p.name for p in paths] == ["stability_map.png"] and paths[0].stat().st_size > 10_000


def test_adaptive_dop853_indicators_agree_with_fine_step_rk4():
    """Two integrations of the same variational system by different methods: DOP853 at rtol 1e-10 and RK4 at
    step 0.002 (error ~ h⁴ ≈ 1e-11 per unit time) give the same ⟨Y⟩ and final state, on regular and chaotic points."""
    scene = _scene(*CHAOTIC)
    y0 = _states(scene, [0.4, 1.0, 2.5], [0.5, 1.0, 3.0])  # ⟨Y⟩(100) = 1.32, 4.34, 1.69
    times = np.array([0.0, 50.0, 100.0])
    fine = megno_run(scene.system.compiled_model(), _scene("integrator.step=0.002").integrator, times, y0)
    dop = compose_scene(["integrator=dop853_numba", "integrator.rtol=1e-10", "integrator.atol=1e-12"]).integrator
    adaptive = megno_run(scene.system.compiled_model(), dop, times, y0)
    assert np.all(adaptive["steps"] < 0.05 * fine["steps"])  # adaptive: far fewer steps
    np.testing.assert_allclose(adaptive["megno"], fine["megno"], rtol=0, atol=1e-8)
    np.testing.assert_allclose(adaptive["final_state"], fine["final_state"], rtol=0, atol=1e-6)


@pytest.mark.parametrize("com, hatched", [([0.0, 0.0, 1.0], True), ([0.3, 0.2, 0.9327379053088815], False)])
def test_stability_map_marks_the_slow_spin_regime_only_for_a_body_it_applies_to(com, hatched):
    """The large-parameter regime is derived for a centre of mass on the body z axis (its refusal says so): the
    map hatches r0/c ≤ 0.2 for such a body only, and notes why it does not for the others."""
    import matplotlib.pyplot as plt

    from gyrolab.figures.stability_map import draw_stability_map

    theta0, r0 = np.array([0.5, 1.0]), np.array([0.05, 1.0, 8.0])
    ds = xr.Dataset({"indicator": (("theta0", "r0"), np.full((2, 3), 2.0), {"indicator_name": "MEGNO", "units": "1"})},
                    coords={"theta0": ("theta0", theta0, {"units": "rad"}), "r0": ("r0", r0, {"units": "1"})},
                    attrs={"body_nondim_a": 2.0, "body_nondim_b": 1.5, "body_nondim_com_direction": np.array(com)})
    fig = draw_stability_map(ds)
    try:
        texts = [label for ax in fig.axes for label in ax.get_legend_handles_labels()[1]]
        titles = " ".join(ax.get_title(loc="left") for ax in fig.axes)
        assert any(label.startswith("large parameter") for label in texts) == hatched
        assert ("centre of mass is off the z axis" in titles) != hatched
    finally:
        plt.close(fig)
