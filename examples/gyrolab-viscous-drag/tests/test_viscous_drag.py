"""The plugin's own tests: gyrolab's contract kit, and the drag's exact solution."""

import numpy as np
import pytest

from gyrolab import run
from gyrolab.errors import ConfigError
from gyrolab.testing import check_force
from gyrolab_viscous_drag import ViscousDrag


def test_contract():
    check_force(ViscousDrag, coefficient=0.3)


def test_bad_coefficient_is_one_sentence():
    with pytest.raises(ConfigError, match="coefficient"):
        ViscousDrag(None, coefficient="abc")


@pytest.mark.parametrize("integrator", ["dop853", "dop853_numba"])
def test_spherical_body_decays_exponentially(integrator):
    # A = B = C = 1: ω̇ = −c ω, so ω(t) = ω0 exp(−c t) in every component (the installed plugin, compiled or not).
    ds = run(["force=[viscous_drag]", "force.viscous_drag.coefficient=0.3", "body.a=1", "body.b=1",
              f"integrator={integrator}", "integrator.rtol=1e-12", "integrator.atol=1e-12",
              "time.end=5", "time.n_output=51"])
    expected = np.array([0.1, -0.05, 5.0]) * np.exp(-0.3 * ds.time.values)[:, None]
    np.testing.assert_allclose(ds.omega.values, expected, rtol=1e-9, atol=1e-12)
    assert "area_integral" not in ds.attrs["monitored_invariants"].split()
