"""The derivation scripts of docs/derivations/scripts run to the end (they are records of how the papers'
formulas were checked; a script that no longer runs has rotted).

Each script prints its comparison tables; most assert nothing themselves, so this is a smoke test: exit
status 0, no traceback, something printed. sympy comes with the test extra (through ``derivations``).
Scripts that took more than about 5 s on a loaded 2-core machine are marked ``slow``.
"""
import subprocess
import sys

import pytest

from tests.helpers import REPO

SCRIPTS = REPO / "docs" / "derivations" / "scripts"
# measured run times on the shared 2-core CI machine: 6.5 s … 25 s; the others take 0.2 … 4.7 s
SLOW = {"seed000/lindstedt.py", "seed000/derive_f3_phi3.py", "seed000/lindstedt_resonances.py",
        "seed000/resonance_band.py", "seed001/case_i_convergence.py", "seed001/case_iii_amplitude.py",
        "seed001/check_printed_vs_lp.py", "seed001/euler_angles.py", "seed002/check_cases.py",
        "seed002/check_vector_model.py", "seed002/derive_euler_lagrange.py", "seed002/precession_conditions.py"}
ALL = sorted(str(p.relative_to(SCRIPTS)) for p in SCRIPTS.glob("*/*.py"))


def test_the_scripts_are_found():
    assert len(ALL) == 25 and set(SLOW) <= set(ALL)


@pytest.mark.parametrize("script", [pytest.param(s, marks=pytest.mark.slow) if s in SLOW else s for s in ALL])
def test_derivation_script_runs(script):
    path = SCRIPTS / script
    done = subprocess.run([sys.executable, path.name], cwd=path.parent, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, f"{script} failed:\n{done.stderr[-3000:]}"
    assert "Traceback" not in done.stderr
    if path.stem not in {"formulas", "model", "printed", "fullmodel"}:   # libraries the others import
        assert done.stdout.strip(), f"{script} printed nothing"
