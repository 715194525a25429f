"""large_parameter (seed 000 read as printed, μ = c/r0 ≫ 1): refused, and the evidence for the refusal."""

import numpy as np
import pytest

from gyrolab.engine.config import compose_config
from gyrolab.errors import ConfigError
from gyrolab.experiments.regime_run import prepare
from gyrolab.engine.scene import Scene
from gyrolab.plugins.regimes import ismail2021 as paper
from gyrolab.plugins.regimes.base import nondimensional_scene
from gyrolab.plugins.regimes.large_parameter import printed_reading_state
from tests.test_regime_helpers import BODY_000, GAMMA_000


def test_large_parameter_is_refused_with_one_sentence():
    with pytest.raises(ConfigError) as info:
        prepare(compose_config(["regime=large_parameter", "initial.r0=0.05"]))
    message = str(info.value)
    assert "no consistent expansion" in message and "regime=small_parameter" in message
    import re

    assert not re.search(r"\. [A-Z]", message) and "\n" not in message  # one sentence


@pytest.mark.parametrize("mu", [16.0, 64.0])
def test_printed_reading_fails_at_order_one(mu):
    """Erratum 000 eq. (4): μ = c/r0 as printed gives γ'' errors ~1; μ = r0/c gives small ones (report §3)."""
    errors = {}
    for reading, r0 in (("printed", 1 / mu), ("consistent", mu)):
        theta0 = float(np.arccos(GAMMA_000 / mu))
        scene = Scene.from_config(compose_config([*BODY_000, f"initial.r0={r0!r}", f"initial.theta0={theta0!r}",
                                                  "integrator=taylor", "output.euler_angles=false"]))
        s = nondimensional_scene(scene.system, "test")
        t = np.linspace(0, 2 * np.pi / r0, 201)  # one period of τ = r0 t
        if reading == "printed":
            approx = printed_reading_state(t, s)
        else:
            P = paper.Params(s.a, s.b, s.x0, s.y0, s.z0, s.k, mu, GAMMA_000 / mu)
            approx = paper.scaled_to_model(paper.printed_scaled(r0 * t, P), P)
        y0 = approx[0].copy()
        y0[3:6] /= np.linalg.norm(y0[3:6])
        exact = scene.integrator.integrate(scene.system.rhs, t, y0, None, scene.system.compiled_model()).y
        errors[reading] = np.abs(approx[:, 5] - exact[:, 5]).max()
    assert errors["printed"] > 0.5  # report: 0.97 (μ = 16), 0.99 (μ = 64)
    assert errors["consistent"] < 1e-4  # report: 3.5e-5, 1.4e-7
