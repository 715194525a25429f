"""Every benchmark's results file: its numbers with the machine they were measured on.

``write_results(name, numbers, tables)`` writes ``benchmarks/results/<name>.json`` with the CPU model,
its vector width (doubles per register, as LLVM targets it) and the batch kernels' lane width, the core
count, the load average at the start and at the end, the library versions (gyrolab and its commit,
numba, numpy, heyoka) and the benchmark's numbers. ``tables`` maps a marker name to a table
(``{"caption": ..., "header": [...], "rows": [[...], ...]}``) that ``python benchmarks/tables.py``
writes between ``<!-- generated: NAME -->`` and ``<!-- /generated -->`` in README.md or docs/*.md.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import subprocess
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"
LOAD_AT_IMPORT = os.getloadavg()  # the load when the benchmark started


def _lanes_at_import() -> dict[str, int]:
    # read when the benchmark imports this module, with the kernels it runs (not when it writes, minutes later)
    from gyrolab.kernels.vector_width import lane_attributes

    return lane_attributes()


LANES_AT_IMPORT = _lanes_at_import()


def cpu_model() -> str:
    """The CPU's model name (/proc/cpuinfo; the platform's processor string elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).resolve().parent,
                             capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=Path(__file__).resolve().parent, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return out.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "") if out.returncode == 0 else "unknown"


COMMIT_AT_IMPORT = _commit()  # the code the benchmark runs, not what the worktree holds when it writes


def versions() -> dict[str, str]:
    """Library versions of this process (a library not installed is left out)."""
    from importlib.metadata import PackageNotFoundError, version

    found = {"python": platform.python_version(), "gyrolab_commit": COMMIT_AT_IMPORT}
    for name in ("gyrolab", "numpy", "numba", "llvmlite", "scipy", "heyoka"):
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            pass
    return found


def machine() -> dict[str, Any]:
    """What a timing depends on: CPU, vector and lane widths, cores, threads, load, versions."""
    record = {"cpu_model": cpu_model(), "machine": platform.machine(), "cores": os.cpu_count(),
              **LANES_AT_IMPORT, "load_average_start": list(LOAD_AT_IMPORT),
              "load_average_end": list(os.getloadavg()), "versions": versions()}
    try:
        import numba

        record["numba_threads"] = numba.get_num_threads()
    except ImportError:
        pass
    return record


def write_results(name: str, numbers: dict[str, Any], tables: dict[str, dict[str, Any]] | None = None,
                  clock: str = "time.process_time (CPU time of the process, all its threads)",
                  command: str | None = None, summary: list[list[str]] | None = None) -> Path:
    """Write ``benchmarks/results/<name>.json``; returns its path. ``command``: how the numbers were made, when
    not ``benchmarks/<name>.py`` without options (a benchmark with several modes names each mode's file).
    ``summary``: rows [what, measured, target, verdict] for the README's ``speed_summary`` table, which
    ``tables.py`` assembles from every results file's rows."""
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    record = {"benchmark": command or f"benchmarks/{name}.py",
              "date_utc": f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%dT%H:%MZ}",
              **machine(), "clock": clock, "numbers": numbers, "tables": tables or {}}
    if summary:
        record["summary"] = summary
    path.write_text(json.dumps(record, indent=2, default=float) + "\n")
    print(f"written {path}")
    return path
