"""How long a resumed multirun takes to start its first remaining job (issue 14's target: < 10 s for
1,000 jobs with 600 finished).

    python benchmarks/multirun_resume.py                       # 1,000 jobs, 600 finished (~6 min: it runs them)
    python benchmarks/multirun_resume.py --jobs 100 --finished 60
    python benchmarks/multirun_resume.py --baseline            # also Hydra's basic sweeper (minutes more)
    python benchmarks/multirun_resume.py --sweep-dir DIR       # reuse DIR's finished jobs (kept from a run)

The sweep is a cheap scene on a 2-D grid with a config-group dimension (``integrator=rk4,dop853``, and
``initial.r0`` over jobs/2 values; t ∈ [0, 0.01], 2 output times, no figures). It is run for real with
Hydra's basic launcher and killed (SIGKILL, the whole process group) once ``--finished`` jobs have their
record, as a crash would leave it. Then the same command is run again, and the time from its start to
Hydra's "#K : ..." line for the first job it launches (K = the first unfinished job) is measured; the
resumed sweep is then stopped. For reference, the same time is measured for the sweep started afresh
(its job #0): what any sweep pays before its first job, whatever the sweeper. ``--baseline`` measures the same with ``hydra/sweeper=basic`` (Hydra's own
sweeper: it composes every job to validate the batch, then launches every job, which skips itself).
Times are wall-clock on whatever else the machine is doing: run it on an idle machine for the README.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def command(jobs: int, sweep_dir: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "gyrolab", "-m", "integrator=rk4,dop853", f"initial.r0=range(1,{jobs // 2 + 1})",
            "time.end=0.01", "time.n_output=2", "output.figures=false", f"hydra.sweep.dir={sweep_dir}", *extra]


def stop(process: subprocess.Popen) -> None:
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait()


def run_until_finished(jobs: int, finished: int, sweep_dir: Path) -> int:
    """Run the sweep and kill it once ``finished`` job records exist; the number of records left."""
    process = subprocess.Popen(command(jobs, sweep_dir), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               start_new_session=True)
    try:
        while len(list(sweep_dir.glob("*/job.json"))) < finished:
            if process.poll() is not None:
                raise SystemExit(f"the sweep ended (exit {process.returncode}) before {finished} jobs finished")
            time.sleep(0.2)
    finally:
        stop(process)
    return len(list(sweep_dir.glob("*/job.json")))


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def time_to_first_launch(jobs: int, sweep_dir: Path, *extra: str) -> tuple[float, int, str]:
    """Seconds from the command's start to Hydra's line for the first job it launches (and that job's number)."""
    global last_cpu
    cpu = children_cpu()
    start = time.perf_counter()
    process = subprocess.Popen(command(jobs, sweep_dir, *extra), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, start_new_session=True)
    launched = re.compile(r"\t#(\d+) : ")
    checked = ""
    try:
        for line in process.stdout:
            if "sweep resumed" in line:
                checked = line.split("] ", 1)[-1].strip()
            found = launched.search(line)
            if found:
                return time.perf_counter() - start, int(found.group(1)), checked
        raise SystemExit(f"the resumed sweep launched no job (exit {process.wait()})")
    finally:
        stop(process)
        last_cpu = children_cpu() - cpu


#: CPU seconds (user + system) the last timed command used until it was stopped: on a busy machine, a
#: better guide than the wall time to what the command costs on an idle one (it runs on one core)
last_cpu = 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=1000)
    parser.add_argument("--finished", type=int, default=600)
    parser.add_argument("--baseline", action="store_true", help="also time Hydra's basic sweeper")
    parser.add_argument("--sweep-dir", type=Path, help="keep the sweep here; its finished jobs are reused")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="gyrolab-resume-") as tmp:
        sweep_dir = (args.sweep_dir or Path(tmp) / "sweep").resolve()
        tic = time.perf_counter()
        records = len(list(sweep_dir.glob("*/job.json")))
        if records < args.finished:
            records = run_until_finished(args.jobs, args.finished, sweep_dir)
            print(f"{args.jobs}-job sweep killed after {records} job records ({time.perf_counter() - tic:.0f} s)")
        else:
            print(f"{args.jobs}-job sweep in {sweep_dir} with {records} job records")
        seconds, first, checked = time_to_first_launch(args.jobs, sweep_dir)
        print(f"gyrolab's sweeper: first remaining job (#{first}) launched after {seconds:.2f} s "
              f"({last_cpu:.2f} CPU s)  [{checked}]")
        fresh, _, _ = time_to_first_launch(args.jobs, Path(tmp) / "fresh")
        print(f"for reference, the same sweep started afresh launches its job #0 after {fresh:.2f} s "
              f"({last_cpu:.2f} CPU s; the command's start-up and Hydra's first composition)")
        if args.baseline:
            seconds, first, _ = time_to_first_launch(args.jobs, sweep_dir, "hydra/sweeper=basic")
            print(f"Hydra's basic sweeper: first job launched (#{first}) after {seconds:.2f} s ({last_cpu:.0f} CPU s); its jobs "
                  "then skip themselves one by one")
            base_seconds = _time_basic_to_job(args.jobs, sweep_dir, records)
            print(f"Hydra's basic sweeper: first remaining job (#{records}) launched after {base_seconds:.2f} s")


def _time_basic_to_job(jobs: int, sweep_dir: Path, target: int) -> float:
    start = time.perf_counter()
    process = subprocess.Popen(command(jobs, sweep_dir, "hydra/sweeper=basic"), stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        for line in process.stdout:
            if f"\t#{target} : " in line:
                return time.perf_counter() - start
        raise SystemExit(f"job #{target} was never launched (exit {process.wait()})")
    finally:
        stop(process)


if __name__ == "__main__":
    main()
