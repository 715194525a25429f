"""The speed tables' generator (benchmarks/tables.py) on a fixture results file, and the results file's machine record."""

from __future__ import annotations

import importlib.util
import json
import sys

import pytest

from tests.helpers import REPO

BENCHMARKS = REPO / "benchmarks"


def _module(name: str):
    spec = importlib.util.spec_from_file_location(f"_bench_{name}", BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


RECORD = {
    "benchmark": "benchmarks/batch_heyoka.py", "date_utc": "2026-11-26T22:00Z", "cpu_model": "Fixture CPU 9000",
    "cores": 2, "host_vector_doubles": 8, "batch_lanes": 4, "load_average_start": [3.25, 3, 3],
    "load_average_end": [4.5, 4, 4], "clock": "time.process_time",
    "versions": {"gyrolab": "0.1.0", "gyrolab_commit": "abc1234", "numba": "0.68.1", "numpy": "2.4.6", "heyoka": "7.13.2"},
    "tables": {"batch_heyoka": {"caption": "CPU s at max error 1e-10.", "header": ["contestant", "CPU s"],
                                "rows": [["heyoka, batch 8", "1.00"], ["gyrolab taylor", "0.45"]]}},
}


@pytest.fixture
def tree(tmp_path):
    (tmp_path / "docs").mkdir()
    results = tmp_path / "benchmarks" / "results"
    results.mkdir(parents=True)
    (results / "batch_heyoka.json").write_text(json.dumps(RECORD))
    (tmp_path / "README.md").write_text("# front page\n\nno blocks here\n")
    (tmp_path / "docs" / "performance.md").write_text(
        "intro\n<!-- generated: batch_heyoka -->\nold table\n<!-- /generated -->\nbetween\n"
        "<!-- generated: nobody_has_this -->\nkept\n<!-- /generated -->\nend\n")
    return tmp_path


def test_blocks_are_rewritten_from_the_results_file_wherever_they_are(tree):
    tables = _module("tables")
    written, missing, changed = tables.regenerate(tree, tree / "benchmarks" / "results")
    assert written == ["batch_heyoka"] and missing == ["nobody_has_this"]
    assert changed == [tree / "docs" / "performance.md"]
    text = (tree / "docs" / "performance.md").read_text()
    assert "old table" not in text and "\nkept\n" in text and text.startswith("intro\n") and text.endswith("end\n")
    block = text.split("<!-- generated: batch_heyoka -->\n")[1].split("<!-- /generated -->")[0]
    assert "Fixture CPU 9000" in block and "8 doubles per vector register" in block and "4 lanes" in block
    assert "2 cores" in block and "load average 3.2" in block and "commit abc1234" in block and "heyoka 7.13.2" in block
    assert "| contestant | CPU s |\n| --- | --- |\n| heyoka, batch 8 | 1.00 |\n| gyrolab taylor | 0.45 |\n" in block
    # a second run changes nothing, and --check agrees
    assert tables.regenerate(tree, tree / "benchmarks" / "results")[2] == []
    assert tables.main(["--root", str(tree), "--check"]) == 0


def test_check_reports_a_stale_block_without_writing(tree):
    tables = _module("tables")
    before = (tree / "docs" / "performance.md").read_text()
    assert tables.main(["--root", str(tree), "--check"]) == 1
    assert (tree / "docs" / "performance.md").read_text() == before


def test_a_table_moved_to_the_readme_is_found_there(tree):
    tables = _module("tables")
    (tree / "docs" / "performance.md").write_text("nothing\n")
    (tree / "README.md").write_text("top\n<!-- generated: batch_heyoka -->\n<!-- /generated -->\n")
    written, _, changed = tables.regenerate(tree, tree / "benchmarks" / "results")
    assert written == ["batch_heyoka"] and changed == [tree / "README.md"]
    assert "| gyrolab taylor | 0.45 |" in (tree / "README.md").read_text()


def test_a_ragged_row_is_refused(tree):
    tables = _module("tables")
    record = dict(RECORD, tables={"batch_heyoka": {"header": ["a", "b"], "rows": [["1"]]}})
    (tree / "benchmarks" / "results" / "batch_heyoka.json").write_text(json.dumps(record))
    with pytest.raises(SystemExit):
        tables.regenerate(tree, tree / "benchmarks" / "results")


def test_results_file_records_the_machine(tmp_path, monkeypatch):
    results_file = _module("results_file")
    monkeypatch.setattr(results_file, "RESULTS", tmp_path)
    path = results_file.write_results("fixture", {"x": 1.5}, {"t": {"header": ["a"], "rows": [["1"]]}})
    record = json.loads(path.read_text())
    for key in ("cpu_model", "cores", "host_vector_doubles", "batch_lanes", "load_average_start",
                "load_average_end", "clock", "date_utc"):
        assert key in record
    assert record["numbers"] == {"x": 1.5} and record["benchmark"] == "benchmarks/fixture.py"
    for lib in ("gyrolab", "numpy", "numba", "gyrolab_commit"):
        assert lib in record["versions"]


def test_the_repositorys_speed_tables_are_the_results_files():
    # issue 24: the README's and docs' speed tables come from the results files (one command regenerates them):
    # every generated block of this repository has a results file, and none differs from what it would render
    tables = _module("tables")
    root = BENCHMARKS.parent
    written, missing, changed = tables.regenerate(root, BENCHMARKS / "results", check=True)
    assert not missing, f"generated blocks with no results file: {sorted(set(missing))}"
    assert not changed, f"run `python benchmarks/tables.py`: out of date in {[str(p) for p in changed]}"
    assert "scene_run_verdict" in written and "batch_heyoka" in written  # the README's and the batch's


def test_the_summary_table_gathers_every_results_files_rows_with_its_benchmark(tree):
    tables = _module("tables")
    results = tree / "benchmarks" / "results"
    (results / "batch_heyoka.json").write_text(json.dumps({**RECORD, "summary": [["batch / heyoka", "0.45×", "≤ 0.5×",
                                                                                  "PASS"]]}))
    (results / "sweep_overhead.json").write_text(json.dumps({
        **RECORD, "benchmark": "benchmarks/sweep_overhead.py", "date_utc": "2026-11-27T01:00Z", "tables": {},
        "load_average_start": [0.5, 0, 0], "summary": [["overhead per job", "0.15 s", "≤ 0.2 s", "PASS"]]}))
    (tree / "README.md").write_text("<!-- generated: speed_summary -->\n<!-- /generated -->\n")
    tables.main(["--root", str(tree)])
    text = (tree / "README.md").read_text()
    assert "| batch / heyoka | 0.45× | ≤ 0.5× | PASS | `benchmarks/batch_heyoka.py` |" in text
    assert "| overhead per job | 0.15 s | ≤ 0.2 s | PASS | `benchmarks/sweep_overhead.py` |" in text
    assert "Fixture CPU 9000" in text and "2026-11-26T22:00Z to 2026-11-27T01:00Z" in text
    assert "load average 3.2" in text  # the largest start load of the files, not the first file's
