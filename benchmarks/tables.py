"""Regenerate the speed tables of README.md and docs/*.md from the benchmarks' results files.

    python benchmarks/tables.py            # rewrite every generated block
    python benchmarks/tables.py --check    # exit 1 when a block differs from its results file

A block is the text between ``<!-- generated: NAME -->`` and ``<!-- /generated -->`` in whichever of
README.md and docs/*.md contains it; NAME is a table of a results file (``benchmarks/results/*.json``,
key ``tables``, written by ``results_file.write_results``). The block says on which CPU, vector width,
core count and load the numbers were measured, when, with which versions, and by which command. A
marker whose table no results file holds is left as it is and reported.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
BLOCK = re.compile(r"(<!-- generated: (?P<name>[\w.-]+) -->\n)(?P<body>.*?)(<!-- /generated -->)", re.S)


#: the table assembled from every results file's ``summary`` rows (the README's)
SUMMARY = "speed_summary"


def load_tables(results: Path) -> dict[str, tuple[dict[str, Any], dict[str, Any]]]:
    """Every table of every results file: name → (table, the file's record); and ``SUMMARY``, assembled from the
    files' summary rows."""
    found: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {}
    records = []
    for path in sorted(results.glob("*.json")):
        record = json.loads(path.read_text())
        records.append(record)
        for name, table in (record.get("tables") or {}).items():
            if name in found or name == SUMMARY:
                raise SystemExit(f"table {name!r} is in two results files")
            found[name] = (table, record)
    summarised = [record for record in records if record.get("summary")]
    if summarised:
        found[SUMMARY] = summary_table(summarised)
    return found


def summary_table(records: list[dict[str, Any]]) -> tuple[dict[str, Any], dict[str, Any]]:
    """One row per summary row of each results file, with the command that measured it; its machine line is the
    records' common CPU (or says they differ), their dates and the largest load among them."""
    rows = [[*row, f"`{record.get('benchmark', '?')}`"] for record in records for row in record["summary"]]
    cpus = sorted({str(record.get("cpu_model", "?")) for record in records})
    dates = sorted(str(record.get("date_utc", "?")) for record in records)
    first = records[0]
    merged = {key: first[key] for key in ("host_vector_doubles", "batch_lanes", "cores") if key in first}
    merged["versions"] = {k: v for k, v in first.get("versions", {}).items() if k != "gyrolab_commit"}
    merged.update({
        "cpu_model": cpus[0] if len(cpus) == 1 else f"several CPUs ({'; '.join(cpus)})",
        "date_utc": dates[0] if dates[0] == dates[-1] else f"{dates[0]} to {dates[-1]}",
        "load_average_start": [max((record.get("load_average_start") or [float("nan")])[0] for record in records)],
        "clock": "each row's benchmark says (docs/performance.md)",
        "regenerate": "Regenerate: run the row's benchmark (last column), then `python benchmarks/tables.py`.",
    })
    merged["load_average_end"] = merged["load_average_start"]
    table = {"caption": "gyrolab's speed targets, each from its benchmark's latest results file (the load is the "
                        "largest at the start of any of them).",
             "header": ["what", "measured", "target", "verdict", "benchmark"], "rows": rows}
    return table, merged


def machine_line(record: dict[str, Any]) -> str:
    """One sentence: where, when and how the numbers were measured."""
    v = record.get("versions", {})
    libs = ", ".join(f"{k} {v[k]}" for k in ("gyrolab", "numba", "numpy", "heyoka") if k in v)
    commit = f" (commit {v['gyrolab_commit']})" if "gyrolab_commit" in v else ""
    load = record.get("load_average_start") or [float("nan")]
    load_end = record.get("load_average_end") or load
    lanes = record.get("batch_lanes")
    width = (f", {record['host_vector_doubles']} doubles per vector register"
             + (f" (batch Taylor kernel compiled for {lanes} lanes)" if lanes else "")) if "host_vector_doubles" in record else ""
    return (f"Measured {record.get('date_utc', '?')} on {record.get('cpu_model', '?')}{width}, "
            f"{record.get('cores', '?')} cores, load average {load[0]:.1f} → {load_end[0]:.1f}; "
            f"{libs}{commit}; clock: {record.get('clock', '?')}. "
            + record.get("regenerate", f"Regenerate: `python {record.get('benchmark', 'benchmarks/?.py')}` then "
                                       f"`python benchmarks/tables.py`."))


def render(table: dict[str, Any], record: dict[str, Any]) -> str:
    """The block's text: the machine line, an optional caption, the markdown table."""
    header = [str(h) for h in table["header"]]
    lines = [machine_line(record), ""]
    if table.get("caption"):
        lines += [str(table["caption"]), ""]
    lines.append("| " + " | ".join(header) + " |")
    lines.append("| " + " | ".join("---" for _ in header) + " |")
    for row in table["rows"]:
        if len(row) != len(header):
            raise SystemExit(f"a row of {len(row)} cells under a header of {len(header)}: {row}")
        lines.append("| " + " | ".join(str(c) for c in row) + " |")
    return "\n".join(lines) + "\n"


def documents(root: Path) -> list[Path]:
    """Where generated blocks may live: README.md and docs/*.md."""
    return [p for p in [root / "README.md", *sorted((root / "docs").glob("*.md"))] if p.is_file()]


def regenerate(root: Path, results: Path, check: bool = False) -> tuple[list[str], list[str], list[Path]]:
    """Rewrite the blocks; returns (markers written, markers without a table, files that changed or differ)."""
    tables = load_tables(results)
    written, missing, changed = [], [], []
    for doc in documents(root):
        text = doc.read_text()

        def replace(m: re.Match) -> str:
            name = m["name"]
            if name not in tables:
                missing.append(name)
                return m[0]
            written.append(name)
            return m[1] + render(*tables[name]) + m[4]

        new = BLOCK.sub(replace, text)
        if new != text:
            changed.append(doc)
            if not check:
                doc.write_text(new)
    return written, missing, changed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="report blocks out of date, write nothing")
    parser.add_argument("--root", type=Path, default=ROOT, help="the repository (README.md, docs/)")
    parser.add_argument("--results", type=Path, default=None, help="the results folder (default benchmarks/results)")
    args = parser.parse_args(argv)
    results = args.results or args.root / "benchmarks" / "results"
    written, missing, changed = regenerate(args.root, results, check=args.check)
    for name in missing:
        print(f"no results file has table {name!r}: block left as it is", file=sys.stderr)
    verb = "out of date" if args.check else "rewritten"
    print(f"{len(written)} blocks ({', '.join(sorted(set(written))) or 'none'}); {verb}: "
          f"{', '.join(str(p.relative_to(args.root)) for p in changed) or 'none'}")
    return 1 if args.check and changed else 0


if __name__ == "__main__":
    sys.exit(main())
