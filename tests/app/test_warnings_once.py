"""Warnings are printed once, and expected ones are summarised (issue 25, item 4).

The commands run as a user runs them (``python -m gyrolab``); their output lines are counted on stdout and stderr
together, so the tests hold whichever stream a logging convention sends log lines to.
"""

from __future__ import annotations

import pytest

import re
import subprocess
import sys

import xarray as xr


def _gyrolab(*args: str) -> list[str]:
    done = subprocess.run([sys.executable, "-m", "gyrolab", *args], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return (done.stdout + done.stderr).splitlines()


def test_a_regime_run_prints_each_domain_warning_once(tmp_path):
    """regime=small_parameter at the default θ0 = 1 and r0 = 20 is outside the closed forms' domain
    (Γ = cos θ0 r0/c = 10.8 > 3): the warning saying so, the reseated initial state and the normalised start each
    appear exactly once (the check before Hydra starts used to print them a second time)."""
    lines = _gyrolab("regime=small_parameter", "initial.r0=20", "regime.periods=1", "regime.samples_per_period=40",
                     "output.figures=false", f"hydra.run.dir={tmp_path}")
    for words in ("Γ = cos θ0 · r0/c = 10.8", "the analytic orbit starts from its own", "γ rescaled to unit norm"):
        assert sum(words in line for line in lines) == 1, (words, lines)
    with xr.open_dataset(tmp_path / "regime.nc") as ds:
        assert abs(ds.attrs["analytic_gamma0_norm"] - 1) > 1e-3 and "rescaled" in ds.attrs["regime_warnings"]


def test_a_regime_run_inside_the_domain_has_no_domain_warning(tmp_path):
    """The README's example (θ0 = 1.5, so Γ = 1.4 at r0 = 20): no Γ warning, no rescaling worth a warning."""
    lines = _gyrolab("regime=small_parameter", "initial.r0=20", "initial.theta0=1.5", "regime.periods=1",
                     "regime.samples_per_period=40", "output.figures=false", f"hydra.run.dir={tmp_path}")
    assert not any("Γ = cos θ0" in line or "rescaled" in line for line in lines), lines
    with xr.open_dataset(tmp_path / "regime.nc") as ds:
        assert abs(ds.attrs["analytic_gamma0_norm"] - 1) < 1e-4


@pytest.mark.slow
def test_regime_validity_ends_with_one_line_counting_its_expected_warnings(tmp_path):
    lines = _gyrolab("experiment=regime_validity", "output.figures=false", f"hydra.run.dir={tmp_path}")
    counted = [line for line in lines if re.search(r"\d+ expected domain warnings", line)]
    assert len(counted) == 1, lines
    n = int(re.search(r"(\d+) expected domain warnings", counted[0]).group(1))
    # no point's warning on its own line (resonances, edges of domains, non-physical bodies)
    assert not any("excluded resonance" in line or "non-physical body" in line or "near the edge" in line
                   for line in lines), lines
    assert len(lines) <= 12, lines                                  # the verdicts, the count, the files written
    with xr.open_dataset(tmp_path / "regime_validity.nc") as ds:
        details = ds.attrs["expected_warnings"].splitlines()
        assert ds.attrs["n_expected_warnings"] == n == len(details) > 0
        assert any("excluded resonance" in d for d in details)      # the details are kept in the dataset
    after = lines[lines.index(counted[0]) + 1:]
    assert all("wrote" in line for line in after), after            # the count is the last thing the experiment says
