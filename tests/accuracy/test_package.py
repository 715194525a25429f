"""``gyrolab.accuracy`` owns accuracy: the engine imports no concrete integrator, ``auto`` keeps nothing of a call,
and the calibration constants sit in one table, each naming the benchmark that regenerates it, which reads the table
and reports whether its measurement still supports each value."""

from __future__ import annotations

import re

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.accuracy import calibration as table
from tests.helpers import REPO

BENCHMARKS = {table.PROMISE: "PROMISE", table.PERF: "PERF", table.CALIBRATE: "CALIBRATE", table.CHAOS: "CHAOS",
              table.ROUNDOFF: "ROUNDOFF", table.ONE_PASS: "ONE_PASS", table.HEAD: "HEAD"}


def test_every_constant_names_a_benchmark_that_reports_on_it():
    assert len(table.TABLE) >= 28
    for constant in table.TABLE.values():
        assert constant.benchmark in BENCHMARKS, constant
        source = (REPO / constant.benchmark.split()[0]).read_text()
        assert f"table.report(table.{BENCHMARKS[constant.benchmark]}," in source, constant.benchmark
        assert constant.basis and getattr(table, constant.name) == constant.value


def test_the_one_pass_kernel_runs_with_the_tables_constants():
    # the kernel, a layer below gyrolab.accuracy, holds its own copy: it must be the table's
    from gyrolab.kernels import taylor

    for name in ("EXTRA_ORDERS", "TANGENT_ORDER", "GROWTH_PER_STEP"):
        assert getattr(taylor, name) == table.TABLE[name].value, name


def test_no_accuracy_module_keeps_a_constant_of_the_table_for_itself():
    # one table: a module of gyrolab.accuracy that assigned NAME = ... for a name of the table would be a second copy
    for path in (REPO / "pipeline" / "accuracy").glob("*.py"):
        if path.name != "calibration.py":
            assigned = set(re.findall(r"^([A-Z_]+) = ", path.read_text(), re.MULTILINE))
            assert not assigned & set(table.TABLE), (path.name, assigned & set(table.TABLE))


def test_the_report_says_when_a_measurement_contradicts_a_value(capsys):
    assert table.report(table.ROUNDOFF, {"ROUNDOFF_MARGIN": (True, "a measurement")})
    assert not table.report(table.ROUNDOFF, {"ROUNDOFF_MARGIN": (False, "another")})
    assert f"ROUNDOFF_MARGIN = {table.ROUNDOFF_MARGIN:g}: NOT SUPPORTED by another" in capsys.readouterr().out
    with pytest.raises(KeyError, match="CALIBRATION"):  # a benchmark may not judge another benchmark's constant
        table.report(table.ROUNDOFF, {"CALIBRATION": (True, "")})


def test_the_engine_imports_no_concrete_integrator():
    for path in (REPO / "pipeline" / "engine").glob("*.py"):
        text = path.read_text()
        assert "plugins.integrators" not in text and "accuracy.auto" not in text, path.name


def test_auto_keeps_nothing_of_a_call():
    # what a run chose comes back with its solution (Solution.choice); the integrator is as it was before the call
    scene = compose_scene(["experiment=perf_reference", "time.n_output=2", "accuracy=1e-8"])
    auto = scene.integrator
    before = dict(vars(auto))
    solution = auto.integrate(scene.rhs, scene.times, scene.system.initial_state(), None, scene.compiled)
    assert vars(auto) == before
    assert solution.choice.method.name == "taylor" and solution.choice.promised <= 1e-8
    assert solution.choice.attributes["auto_precision"] == "double"
    again = auto.integrate(scene.rhs, scene.times, scene.system.initial_state(), None, scene.compiled)
    np.testing.assert_array_equal(again.y, solution.y)
