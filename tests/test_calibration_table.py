"""The calibration constants of ``gyrolab.accuracy`` sit in one table, each naming the benchmark that regenerates it,
and that benchmark reads the table and reports whether its measurement still supports each value."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gyrolab.accuracy import calibration as table

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = {table.PROMISE: "PROMISE", table.PERF: "PERF", table.CALIBRATE: "CALIBRATE", table.CHAOS: "CHAOS",
              table.ROUNDOFF: "ROUNDOFF"}


def test_every_constant_names_a_benchmark_that_reports_on_it():
    assert len(table.TABLE) >= 28
    for constant in table.TABLE.values():
        assert constant.benchmark in BENCHMARKS, constant
        source = (ROOT / constant.benchmark.split()[0]).read_text()
        assert f"table.report(table.{BENCHMARKS[constant.benchmark]}," in source, constant.benchmark
        assert constant.basis and getattr(table, constant.name) == constant.value


def test_no_accuracy_module_keeps_a_constant_of_the_table_for_itself():
    # one table: a module of gyrolab.accuracy that assigned NAME = ... for a name of the table would be a second copy
    for path in (ROOT / "pipeline" / "accuracy").glob("*.py"):
        if path.name != "calibration.py":
            assigned = set(re.findall(r"^([A-Z_]+) = ", path.read_text(), re.MULTILINE))
            assert not assigned & set(table.TABLE), (path.name, assigned & set(table.TABLE))


def test_the_report_says_when_a_measurement_contradicts_a_value(capsys):
    assert table.report(table.ROUNDOFF, {"ROUNDOFF_MARGIN": (True, "a measurement")})
    assert not table.report(table.ROUNDOFF, {"ROUNDOFF_MARGIN": (False, "another")})
    assert "ROUNDOFF_MARGIN = 10: NOT SUPPORTED by another" in capsys.readouterr().out
    with pytest.raises(KeyError, match="CALIBRATION"):  # a benchmark may not judge another benchmark's constant
        table.report(table.ROUNDOFF, {"CALIBRATION": (True, "")})
