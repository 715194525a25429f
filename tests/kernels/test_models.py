"""Kernels compiled per model form (``models.Form``): a built-in scene compiles no plugin code.

Issue 12, item 6 (first compile). The expected values are the run-time dispatch's (an int model), which
the forms must reproduce bit for bit, and which code numba did or did not compile.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numba
import numpy as np

from gyrolab.contracts.integrator import CompiledModel
from gyrolab.kernels import fixed_point, models

INERTIA = np.array([2.0, 1.5, 1.0])


def _params() -> np.ndarray:
    p = fixed_point.pack(INERTIA, [], False)
    p[9:12] = [0.3, 0.2, 0.9]  # U_2
    p[14] = 0.5  # N_2
    return p


def test_form_of_each_compiled_model():
    assert models.form(CompiledModel(models.FIXED_POINT, _params())).id == models.FIXED_POINT
    assert models.form(CompiledModel(models.TRACED, np.zeros(30))).id == models.TRACED
    assert numba.typeof(models.FORMS[models.FIXED_POINT]) != numba.typeof(models.FORMS[models.TRACED])


def test_form_matches_run_time_dispatch_bit_for_bit():
    p = _params()
    y = np.array([0.3, -1.1, 2.2, 0.48, 0.6, 0.64])
    by_int, by_form = np.empty(6), np.empty(6)
    models.evaluate(models.FIXED_POINT, 0.0, y, p, by_int)
    models.evaluate(models.form(CompiledModel(models.FIXED_POINT, p)), 0.0, y, p, by_form)
    assert np.array_equal(by_int, by_form)
    assert np.all(by_form != 0.0)  # every component computed


@numba.njit
def _probe(model, y, p, out):
    models.rhs(model, 0.0, y, p, out)


def _compiled_ir(model) -> str:
    """The LLVM IR of ``_probe`` for one model argument, with every function it calls linked in."""
    y = np.ones(6)
    _probe(model, y, _params(), np.empty_like(y))
    return _probe.inspect_llvm(_probe.signatures[-1])


def test_builtin_form_compiles_no_plugin_code():
    """The run-time dispatch contains the traced models' indirect call (``inttoptr``); the built-in form does not."""
    dispatch = _compiled_ir(models.FIXED_POINT)
    built_in = _compiled_ir(models.FORMS[models.FIXED_POINT])
    assert "inttoptr" in dispatch
    assert "inttoptr" not in built_in
    assert built_in.count("fmul") <= dispatch.count("fmul")


_CHILD = r'''
import json, sys
import numpy as np
from numba.core import event
from gyrolab.kernels import fixed_point, models, taylor_series, rk4
import numba

p = fixed_point.pack(np.array([2.0, 1.5, 1.0]), [], False)
p[9:12] = [0.3, 0.2, 0.9]
form = models.FORMS[models.FIXED_POINT]
y0 = np.array([0.3, -1.1, 2.2, 0.48, 0.6, 0.64])
with event.install_recorder("numba:compile") as rec:
    y, Y, f = y0.copy(), np.zeros((3, 6)), np.empty(6)
    rk4.run(form, p, np.array([0.0, 0.1, 0.2]), np.array([5, 5]), y, Y, 1, 3)
    models.evaluate(form, 0.0, y0, p, f)
    if sys.argv[1] == "first":
        @numba.njit
        def series(model, p, T, order, work):
            models.taylor_coefficients(model, p, T, order, work)
        T = np.zeros((9, 6))
        T[0] = y0
        series(form, p, T, 8, np.zeros((9, 3)))
compiled = sorted({ev.data["dispatcher"].py_func.__qualname__ for _, ev in rec.buffer if "dispatcher" in ev.data})
print(json.dumps({"compiled": compiled, "Y": Y.tolist(),
                  "unused": [len(taylor_series.coefficients.signatures)],
                  "gamma": len(fixed_point.taylor_coefficients.signatures)}))
'''


def test_fresh_cache_compiles_the_form_only_and_a_second_process_loads_it(tmp_path):
    """In a fresh kernel cache the (ω, γ) form does not compile the traced models' Taylor code; a second process on that cache compiles nothing (numba loads every kernel from disk)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def child(which: str) -> dict:
        out = subprocess.run([sys.executable, "-c", _CHILD, which], env=env, capture_output=True, text=True,
                             check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    first = child("first")
    assert "run" in first["compiled"] and first["gamma"] == 1
    assert first["unused"] == [0]
    second = child("second")
    assert second["compiled"] == []
    assert second["Y"] == first["Y"]
