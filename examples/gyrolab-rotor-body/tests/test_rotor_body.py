"""The plugin's own tests: gyrolab's contract kit, the invariants over a run, and the free symmetric top's solution."""

import numpy as np
import pytest

from gyrolab import run
from gyrolab.contracts import Force
from gyrolab.errors import ConfigError
from gyrolab.testing import check_system
from gyrolab_rotor_body import RotorBodySystem
from gyrolab_rotor_body.body import RotorBody

INITIAL = {"p0": 0.3, "q0": -0.2, "r0": 2.0, "theta0": 0.8, "phi0": 0.4, "psi0": 0.0, "gamma0": None}


def test_contract():
    check_system(RotorBodySystem, {"units": "si", "inertia": [2.0, 1.5, 1.0], "rotor_momentum": [0.1, -0.2, 0.5]},
                 INITIAL)


class _Drag(Force):                        # a torque that reads nothing of the body, so it builds on any
    name = "drag"
    preserves_area_integral = False

    def torque(self, omega, axes):
        return -0.1 * omega


def test_forces_are_refused_in_one_sentence():
    body = RotorBody.from_config({"units": "si"})
    with pytest.raises(ConfigError, match=r"takes no force, got force=\[drag\]; valid choice: force=\[\]$"):
        RotorBodySystem(body, [_Drag()], INITIAL, {})
    with pytest.raises(ConfigError, match=r"^force\.uniform_gravity \(UniformGravity\) cannot act on a RotorBody"):
        run(["body=rotor_body", "force=[uniform_gravity]"])   # gravity needs a fixed point: this body has none


def test_invariants_are_conserved_over_a_run():
    ds = run(["body=rotor_body", "force=[]", "body.rotor_momentum=[0.3,-0.4,0.6]", "integrator=dop853",
              "integrator.rtol=1e-12", "integrator.atol=1e-12", "time.end=20", "time.n_output=201"])
    for name in ("kinetic_energy", "momentum_squared", "gamma_norm"):
        values = ds[name].values
        assert np.max(np.abs(values - values[0])) < 1e-10 * max(1.0, abs(values[0])), name
        assert ds[name].attrs["units"] and ds[name].attrs["long_name"]
    assert ds.attrs["monitored_invariants"] == "kinetic_energy momentum_squared gamma_norm"


@pytest.mark.parametrize("h3", [0.0, 0.7])
def test_symmetric_body_with_axial_rotor_precesses_uniformly(h3):
    # A = B, h = (0, 0, h3): I ω̇ = (Iω + h) × ω gives ṙ = 0 and (p, q) turning at λ = ((C − A) r + h3) / A
    # (ṗ = −λ q, q̇ = λ p); h3 = 0 is the free symmetric top.
    A, C, p0, q0, r0 = 2.0, 1.0, 0.3, -0.2, 2.0
    ds = run(["body=rotor_body", "force=[]", f"body.inertia=[{A},{A},{C}]", f"body.rotor_momentum=[0,0,{h3}]",
              f"initial.p0={p0}", f"initial.q0={q0}", f"initial.r0={r0}", "integrator=dop853",
              "integrator.rtol=1e-12", "integrator.atol=1e-12", "time.end=10", "time.n_output=101"])
    t = ds.time.values
    lam = ((C - A) * r0 + h3) / A
    expected = np.stack([p0 * np.cos(lam * t) - q0 * np.sin(lam * t), p0 * np.sin(lam * t) + q0 * np.cos(lam * t),
                         np.full_like(t, r0)], axis=1)
    np.testing.assert_allclose(ds.omega.values, expected, rtol=0, atol=1e-10)
