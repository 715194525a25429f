"""The batch Taylor kernel's vector parts against independent scalar code: the step rule, the split form of the
Cauchy sums, the outputs of a step over several output times, and where the split form is admitted."""

import math

import numba
import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_arrays
from gyrolab.kernels import batch_taylor, taylor
from gyrolab.kernels.layout import N_Z

LANES = batch_taylor.LANES


@numba.njit
def _both_rules(T, order, tol, vector, scalar, flags):
    """The vector step sizes of every lane (and their flags) beside the scalar rule ``taylor.step_size``."""
    safety = math.exp(-0.7 / (order - 1))
    K = np.empty((4, LANES))
    K[0], K[1], K[2], K[3] = tol, safety, 1.0 / (order - 1), 1.0 / order
    S = np.zeros((2, LANES))
    batch_taylor._step_sizes(T, order, K, S)
    for lane in range(LANES):
        vector[lane], flags[lane] = S[0, lane], S[1, lane]
        scale, n1, n2 = 1.0, 0.0, 0.0
        for c in range(6):
            scale = max(scale, abs(T[0, c, lane]))
            n1 = max(n1, abs(T[order - 1, c, lane]))
            n2 = max(n2, abs(T[order, c, lane]))
        scalar[lane] = taylor.step_size(tol, scale, n1, n2, order, safety)


def test_vector_step_sizes_are_the_scalar_rule_to_rounding():
    """Random series over 60 decades of magnitude, orders 4–30, tolerances 1e-16…1e-3: every lane the vector
    path keeps has the scalar rule's step (powers by libm) within 1e-13 relative, and the lanes it hands back to
    the scalar rule are exactly those it cannot take (a non-finite coefficient, both last coefficients zero)."""
    rng = np.random.default_rng(1)
    for trial in range(3000):
        order = int(rng.integers(4, 31))
        T = rng.normal(size=(order + 1, 6, LANES)) * 10.0 ** rng.uniform(-30, 30, size=(order + 1, 1, LANES))
        special = np.zeros(LANES, dtype=bool)
        if trial % 5 == 0:
            T[order - 1, :, rng.integers(LANES)] = 0.0  # one vanishing term: the other decides
        if trial % 7 == 0:
            lane = rng.integers(LANES)
            T[order - 1:, :, lane] = 0.0  # both vanish: the step goes to the end
            special[lane] = True
        if trial % 11 == 0:
            lane = rng.integers(LANES)
            T[rng.choice([0, order - 1, order]), rng.integers(6), lane] = rng.choice([np.nan, np.inf])  # a row the rule reads
            special[lane] = True
        vector, scalar, flags = np.zeros(LANES), np.zeros(LANES), np.zeros(LANES)
        _both_rules(np.ascontiguousarray(T), order, 10.0 ** rng.uniform(-16, -3), vector, scalar, flags)
        kept = flags == 0.0
        assert not (kept & special).any()
        np.testing.assert_allclose(vector[kept], scalar[kept], rtol=1e-13, atol=0)


def _scene(extra=()):
    return compose_scene(["experiment=perf_reference", "time.end=2", "time.n_output=11", "integrator=taylor",
                          *extra])


def _starts(scene, count, seed, scale=0.1):
    rng = np.random.default_rng(seed)
    y0s = np.tile(scene.system.initial_state(), (count, 1))
    y0s[:, 0:3] += rng.normal(scale=scale, size=(count, 3))
    return y0s


def _run(P, order, tol, times, y0s, split):
    out = np.empty((len(y0s), len(times), 6))
    out[:, 0] = y0s
    steps, status = np.zeros(len(y0s), dtype=np.int64), np.zeros(len(y0s), dtype=np.int64)
    batch_taylor.run_blocks(P, order, tol, times, y0s, out, steps, status, batch_taylor.task_size(len(y0s)), split)
    assert not status.any()
    return out, steps


def test_split_form_agrees_with_the_direct_form():
    """The split form (six sums of ω ± √N₂ γ from order SPLIT on) against the direct form (twelve sums of ω and
    γ) at tol 1e-15, order 18, t ∈ [0, 2], with spins up to four times the reference and N₂ from 0.05 to 2:
    the same steps, and states within 1e-13 (rounding, a hundred times below the tolerance of any setting
    the benchmark asks for)."""
    scene = _scene()
    y0s = _starts(scene, 3 * LANES, seed=11)
    y0s[::3, 0:3] *= 4.0
    P = np.tile(scene.compiled.params, (len(y0s), 1))
    P[:, N_Z] = np.linspace(0.05, 2.0, len(y0s))
    assert batch_taylor.split_ready(P, y0s).all()
    direct, direct_steps = _run(P, 18, 1e-15, scene.times, y0s, 18)
    split, split_steps = _run(P, 18, 1e-15, scene.times, y0s, batch_taylor.SPLIT)
    np.testing.assert_array_equal(split_steps, direct_steps)
    np.testing.assert_allclose(split, direct, rtol=0, atol=1e-13)


def test_split_form_at_its_admission_bound_is_as_accurate_as_the_direct_form():
    """At |ω| / (√N₂ |γ|) ≈ 0.9 × SPLIT_RATIO, the edge of what ``split_ready`` admits, both forms against an
    extended-precision reference (``physics.reference``: the equations summed in long double, not these kernels):
    the same steps, and the split form's γ error within 1 % (+ a few ulps) of the direct form's. (Measured on
    2026-11-27: equal to three digits at 0.9, 9 and 90 × the bound; both errors are the fast spin's, the
    tolerance being relative to |ω|.)"""
    from gyrolab.physics.reference import fixed_point_reference
    from gyrolab.kernels.layout import INERTIA, U_Z

    scene = _scene(["time.end=0.2"])
    y0s = _starts(scene, LANES, seed=3)
    P = np.tile(scene.compiled.params, (LANES, 1))
    P[:, N_Z] = 0.5
    gamma = np.linalg.norm(y0s[:, 3:6], axis=1)
    direction = y0s[:, 0:3] / np.linalg.norm(y0s[:, 0:3], axis=1)[:, None]
    y0s[:, 0:3] = direction * (0.9 * batch_taylor.SPLIT_RATIO * np.sqrt(0.5) * gamma)[:, None]
    assert batch_taylor.split_ready(P, y0s).all()
    direct, direct_steps = _run(P, 18, 1e-15, scene.times, y0s, 18)
    split, split_steps = _run(P, 18, 1e-15, scene.times, y0s, batch_taylor.SPLIT)
    np.testing.assert_array_equal(split_steps, direct_steps)
    for j in range(2):
        reference = fixed_point_reference(P[j, INERTIA:INERTIA + 3], P[j, U_Z:U_Z + 3], P[j, N_Z], y0s[j],
                                          scene.times).astype(float)
        direct_error = np.max(np.abs(direct[j, :, 3:6] - reference[:, 3:6]))
        split_error = np.max(np.abs(split[j, :, 3:6] - reference[:, 3:6]))
        assert split_error <= 1.01 * direct_error + 4 * np.finfo(float).eps


def test_split_form_is_admitted_only_where_its_rounding_stays_small():
    scene = _scene()
    y0s = _starts(scene, 4, seed=12)
    P = np.tile(scene.compiled.params, (4, 1))
    assert batch_taylor.split_ready(P, y0s).all()  # the reference body: |ω| ≈ 5, √N₂ |γ| ≈ 0.7
    P[1, N_Z] = 0.0  # no Newtonian centre: a = 0
    P[2, N_Z] = -0.5  # a repelling one: no real a
    y0s[3, 0:3] = (0.0, 0.0, 2000.0)  # |ω| / (√N₂ |γ|) ≈ 2800 > 1024
    assert batch_taylor.split_ready(P, y0s).tolist() == [True, False, False, False]
    released = y0s[:1].copy()
    released[0, 0:3] = 0.0  # released at rest: energy bounds |ω| by the potential's range
    assert batch_taylor.split_ready(P[:1], released).all()


def test_a_trajectory_in_a_mixed_batch_is_computed_as_alone():
    """A batch mixing trajectories with and without the split form (N₂ = 0 for some): each result, bit for bit,
    the one it has alone (its form follows from its own parameters and state, never from its neighbours)."""
    scene = _scene()
    y0s = _starts(scene, 2 * LANES + 3, seed=13)
    P = np.tile(scene.compiled.params, (len(y0s), 1))
    P[::3, N_Z] = 0.0
    mixed = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s, P)
    for j in (0, 1, 3, len(y0s) - 1):
        alone = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s[j:j + 1], P[j:j + 1])
        np.testing.assert_array_equal(mixed.y[j], alone.y[0])
        assert mixed.steps[j] == alone.steps[0]


@pytest.mark.parametrize("n_output", [201, 2001])  # steps of ~0.17 over outputs 0.01 and 0.001 apart
def test_steps_over_several_output_times_agree_with_the_single_kernel(n_output):
    """Output times closer than a step (several outputs per step: the separate output path) against the
    single-trajectory kernel (``run_each``, scalar Horner per output): the same steps, outputs within 1e-13."""
    scene = _scene([f"time.n_output={n_output}", "integrator.tol=1e-12"])
    y0s = _starts(scene, LANES + 3, seed=14)
    P = np.tile(scene.compiled.params, (len(y0s), 1))
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s, P)
    out = np.empty_like(batch.y)
    out[:, 0] = y0s
    steps, status = np.zeros(len(y0s), dtype=np.int64), np.zeros(len(y0s), dtype=np.int64)
    batch_taylor.run_each(scene.compiled.model, P, scene.integrator.order, scene.integrator.tol, scene.times, y0s,
                          out, steps, status)
    assert not status.any() and batch.steps.max() < n_output / 2
    np.testing.assert_array_equal(batch.steps, steps)
    np.testing.assert_allclose(batch.y, out, rtol=0, atol=1e-13)


@numba.njit
def _row_addresses(order):
    T = batch_taylor._rows(order + 1, 6)
    Q = batch_taylor._rows(1, batch_taylor.CONSTANTS)[0]
    return T.ctypes.data % 64, Q.ctypes.data % 64


def test_work_arrays_are_aligned_to_whole_vectors():
    assert _row_addresses(17) == (0, 0)
