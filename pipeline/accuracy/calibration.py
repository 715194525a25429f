"""Every tuned number behind ``auto``'s choice, the error estimate and the recheck, in one table.

Each entry names the benchmark that regenerates it (``TABLE[name].benchmark``). That benchmark reads the table and
reports, for each entry naming it, whether its measurement still supports the value (``report``); an entry it did
not measure in that run is listed as unchecked, never as supported. Measurements quoted below were made on an AMD
EPYC with AVX-512 (2026-11-24 … 27) unless a benchmark's results file says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

PROMISE = "benchmarks/promise_audit.py"
PERF = "benchmarks/perf_reference.py"
CALIBRATE = "benchmarks/perf_reference.py --calibration"
CHAOS = "benchmarks/chaos_promise.py"
ROUNDOFF = "benchmarks/roundoff_margin.py"
ONE_PASS = "benchmarks/one_pass_estimate.py"
HEAD = "benchmarks/companion_head.py"


@dataclass(frozen=True)
class Constant:
    name: str
    value: float
    benchmark: str
    #: what the benchmark measured that the value rests on
    basis: str


#: name -> Constant, in the order below
TABLE: dict[str, Constant] = {}


def _constant(name: str, value: float, benchmark: str, basis: str) -> float:
    TABLE[name] = Constant(name, value, benchmark, basis)
    return value


_c = _constant
# the error estimate (``estimate``)
TIGHTER = _c("TIGHTER", 100.0, PERF, "companion this many times more accurate: reference scene at 1e-6, 0.55 ms and "
             "176× more accurate (1000×: 0.68 ms, 1660×)")
DOUBLE_DOUBLE_BELOW = _c("DOUBLE_DOUBLE_BELOW", 3e-15, ROUNDOFF, "a double Taylor run whose companion tol is below "
                         "this is measured by two double companions: one alone measured every run at tol 3e-13 within "
                         "0.68–1.92× of the actual error (227 runs, seeds 5 and 11), at 1e-13 0.20–4.2×")
HEAD_ORDERS = _c("HEAD_ORDERS", 4, HEAD, "orders of a double-double head (the state's update too, the rest in double) "
                 "where one runs: the floor companion, and auto's first run on a chaotic scene whose round-off would "
                 "climb. At tol 1e-18 (order 25) on four scenes: within an ulp of a double-double run (reference "
                 "scene: heads 2, 3 ended 8.9 and 4.1 ulps off), or 40x closer than double (a fast top, 112 against "
                 "4,490 ulps), in 15-20 % of double-double's time (AMD EPYC, 2026-11-30)")
HEAD_COMPANION_GROWTH = _c("HEAD_COMPANION_GROWTH", 1e3, HEAD, "the head companion measures runs whose perturbations "
                           "grew at most this much (its round-off, ~u·2.5e-4 of the state a step at tol 1e-18, "
                           "grows with them: the scenes above grow <= 97x; on the chaotic top over t = 200, ~3e10, it "
                           "ended ~1e7 ulps off), double-double beyond")
HEAD_WALK = _c("HEAD_WALK", 4.0, HEAD, "a head run's round-off is at most this many times the ulps of its steps' terms "
               "computed in double, added up and amplified by the growth of perturbations (the terms beyond the head "
               "are also evaluated at the state's high part: an error k times theirs for order k): a head run's "
               "distance from the same steps with an 8-order head, four scenes at tol 1e-13 … 2e-16, heads 1 … 4: "
               "at most 3.4 (the fast top at 2e-16, head 3)")
ROUNDOFF_MARGIN = _c("ROUNDOFF_MARGIN", 6.0, ROUNDOFF, "a double companion near the floor is trusted when two disagree "
                     "this many times below what it measures: seeds 5 and 11, one of 448 trusted below 1/2 of the "
                     "error, as at 10 (354 trusted); at 4, two of 550. The one pass, where a twin run (rounded numbers "
                     "moved) and the walk are this many times below it: 240 of 1,227 runs trusted, 0.57-2.8x the "
                     "error at every output time (AMD EPYC, 2026-11-30)")
# the one-pass estimate of the Taylor kernel (``kernels.taylor.run_measured``; the kernel, a lower layer, holds the same
# values, which the benchmark and tests/accuracy/test_package.py check against these)
EXTRA_ORDERS = _c("EXTRA_ORDERS", 4, ONE_PASS, "the series' orders beyond the step's that estimate its truncation "
                  "error: 2 underestimated 2.3× on a slow top (r0 = 0.1, tol 1e-8), 4 held 0.97–1.04× on four scenes")
TANGENT_ORDER = _c("TANGENT_ORDER", 10, ONE_PASS, "the highest order of the tangent series: the error's at a fixed 6 "
                   "overestimated 36× on a fast top (r0 = 30, tol 1e-6), at 8 and 10 held within 0.82–1.06×")
GROWTH_PER_STEP = _c("GROWTH_PER_STEP", 1e-5, ONE_PASS, "the tangent vector's series is as short as this relative "
                     "error a step allows: 1e-4 moved ln|δ| by 0.54 on the reference scene at tol 1e-12, 1e-5 by 0.06 "
                     "(the first neglected term counted with its factor ~k: without it a fast top over t = 185 moved "
                     "by 0.26, audit seed 5, scene 93); the error's series at that order drifted on that top (0.6× at "
                     "tol 1e-10), so it stays at TANGENT_ORDER")
# the growth of perturbations (``amplification``)
TANGENT_TOLERANCE = _c("TANGENT_TOLERANCE", 1e-5, CHAOS, "tangent run's tolerance: slow_spin over t = 300 grows e^19.3 "
                       "at 1e-5, e^17.4 at 1e-4, e^23.3 at 1e-3")
SHADOW_OFFSET = _c("SHADOW_OFFSET", 1e-7, CHAOS, "the shadow pair's separation relative to the state's size")
SHADOW_CHUNKS = _c("SHADOW_CHUNKS", 64, CHAOS, "the shadow pair's renormalisations over the span")
TANGENT_SAMPLES = _c("TANGENT_SAMPLES", 64, CHAOS, "times a generated tangent run reads max ln|δ| at")
CHAOS_MARGIN = _c("CHAOS_MARGIN", 10.0, CHAOS, "a chaotic scene's amplification taken this many times larger (one "
                  "tangent run scatters by e^2); with none slow_spin at t = 300 was accepted at 1e-6, ended at 1.4e-6")
SHADOW_TOLERANCE = _c("SHADOW_TOLERANCE", 1e-9, CHAOS, "tolerance of the shadow pair's runs")
# auto's pilot and choice (``auto``)
PILOT_POINTS = _c("PILOT_POINTS", 65, CALIBRATE, "samples of the pilot's error growth")
MIN_GROWTH = _c("MIN_GROWTH", 2.0, CALIBRATE, "the pilot's power law t^q is at least quadratic (phase drift): Taylor "
                "at tol 1e-10 on the reference scene grows ×100 from t = 30 to t = 300")
MAX_GROWTH = _c("MAX_GROWTH", 4.0, CALIBRATE, "the pilot's largest power law; growth beyond (1/pilot_fraction)^4 is chaos")
FIRST_RATIO = _c("FIRST_RATIO", 1e-3, CALIBRATE, "first pilot tolerance / accuracy (final error / tol: 24–470)")
MIN_TOLERANCE = _c("MIN_TOLERANCE", 1e-13, CALIBRATE, "the first pilot's tightest tolerance")
MAX_TOLERANCE = _c("MAX_TOLERANCE", 1e-5, CALIBRATE, "looser tolerances step near the Taylor series' radius")
TIGHT_RATIO = _c("TIGHT_RATIO", 3000.0, CALIBRATE, "pilot's tight run ≤ accuracy / this (final tols: accuracy/420 … /1300)")
MIN_PILOT_STEPS = _c("MIN_PILOT_STEPS", 8, PROMISE, "a pilot of fewer steps measured nothing (r0 = 32 over t = 0.25 at "
                     "1e-9 ended 5.7e-5 away)")
UNMEASURED_PER_TOL = _c("UNMEASURED_PER_TOL", 1e3, CALIBRATE, "error per unit tol taken when the pilot measured nothing "
                        "(measured: 24–470)")
RECENTRE = _c("RECENTRE", 20.0, CALIBRATE, "a first prediction this many times looser than τ is measured again: actual "
              "/ raw prediction ≤ 1.09 at every threshold 10–100; at 20, 267 of 369 runs re-measure")
CALIBRATION = _c("CALIBRATION", 3.0, CALIBRATE, "recorded prediction = raw × this: the largest actual / raw final error "
                 "on the extremes matrix and the reference scene at 1e-3 … 1e-13 is 0.94")
MISS_MARGIN = _c("MISS_MARGIN", 1000.0, PERF, "a series' predicted error is trusted to this factor")
SCREEN_POINTS = _c("SCREEN_POINTS", 512, PERF, "grid of the screen before the series check (~0.25 ms)")
SCREEN_TOLERANCE = _c("SCREEN_TOLERANCE", 1e-9, PERF, "tolerance of the screen's Taylor run")
FLOOR = _c("FLOOR", 1e-15, PROMISE, "relative to the state's size: no double run reaches below")
DOUBLE_DOUBLE_FLOOR = _c("DOUBLE_DOUBLE_FLOOR", 1e-16, PROMISE, "double-double stores its states as doubles, rounded "
                         "by ≤ 1.1e-16 × their size: asked 5e-29 at time.end=1, the estimate measured 1.1e-16")
AUTO_SAMPLE = _c("AUTO_SAMPLE", 3, PROMISE, "trajectories of a batch on which auto runs its pilot")
# the recheck (``promise``)
RECHECK_MARGIN = _c("RECHECK_MARGIN", 3.0, PROMISE, "a broken promise reruns aimed this many times below what would "
                    "have met it; extremes matrix and reference scene: measured ≤ 0.47× the prediction")
MAX_RECHECKS = _c("MAX_RECHECKS", 2, PROMISE, "runs made more accurate before the recheck refuses")
ESTIMATE_SLACK = _c("ESTIMATE_SLACK", 2.0, PROMISE, "a run is kept when its measured error is this many times below "
                    "the target, the estimate's own accuracy: audit seed 2026, scene 61 measured 0.98e-11 of 1e-11, "
                    "ended 1.0e-11 away")
FLOOR_COMPANION_MARGIN = _c("FLOOR_COMPANION_MARGIN", 20.0, PROMISE, "a fixed-step run is measured against the "
                            "compiled Taylor method at its floor where that run's own error bound is this many times "
                            "below the difference (at an output time a tenth of the largest error, its error is then "
                            "at most half of that time's), else by Richardson's half step: audit seeds 7 and 11, "
                            "Richardson 0.3× at one time on a fast top (rk4, step 0.01, pre-asymptotic), 0.39× where "
                            "lie_poisson's round-off rivals its error (step 0.002)")


def report(benchmark: str, measured: dict[str, tuple[bool, str]]) -> bool:
    """Print, for every constant of the table that ``benchmark`` regenerates, whether this run's measurement
    (``measured[name]``: (supports the value, what was measured)) supports it; return False if one is contradicted.
    A constant the run did not measure is printed as unchecked."""
    mine = [c for c in TABLE.values() if c.benchmark == benchmark]
    print(f"\ncalibration constants regenerated by {benchmark} (gyrolab.accuracy.calibration):")
    ok = True
    for c in mine:
        if c.name in measured:
            supported, what = measured[c.name]
            ok &= supported
            print(f"  {c.name} = {c.value:g}: {'supported' if supported else 'NOT SUPPORTED'} by {what}")
        else:
            print(f"  {c.name} = {c.value:g}: unchecked by this run")
    unknown = sorted(set(measured) - {c.name for c in mine})
    if unknown:
        raise KeyError(f"{benchmark} measured constants the table does not attribute to it: {', '.join(unknown)}")
    return ok
