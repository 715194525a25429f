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


# ---- the error estimate (``gyrolab.accuracy.estimate``) -------------------------------------------------------------
TIGHTER = _constant("TIGHTER", 100.0, PERF, (
    "the companion is this many times more accurate than the run: within ~1 % of the truth; on the reference scene "
    "(auto at 1e-6) the companion at 100× takes 0.55 ms and ends 176× more accurate, at 1000× 0.68 ms and 1660×"))
DOUBLE_DOUBLE_BELOW = _constant("DOUBLE_DOUBLE_BELOW", 1e-14, PROMISE, (
    "a double Taylor run whose companion would run below this tol is measured in double-double: with a double "
    "companion the smallest estimate / actual error was 0.0047 at tol 3e-14, 0.94 at 1e-12; double-double 0.98"))
ROUNDOFF_MARGIN = _constant("ROUNDOFF_MARGIN", 10.0, ROUNDOFF, (
    "a double companion near the floor is trusted when two double companions disagree by this many times less than "
    "the error it measures: at 10 no trusted estimate below 1/2 of the actual error in 606 runs (seed 5)"))
# ---- the growth of perturbations (``gyrolab.accuracy.amplification``) ------------------------------------------------
TANGENT_TOLERANCE = _constant("TANGENT_TOLERANCE", 1e-5, CHAOS, (
    "tolerance of the tangent run: slow_spin over t = 300 grows e^19.3 at 1e-5, e^17.4 at 1e-4, e^23.3 at 1e-3"))
SHADOW_OFFSET = _constant("SHADOW_OFFSET", 1e-7, CHAOS, "the shadow pair's separation relative to the state's size")
SHADOW_CHUNKS = _constant("SHADOW_CHUNKS", 64, CHAOS, "the shadow pair's renormalisations over the span")
TANGENT_SAMPLES = _constant("TANGENT_SAMPLES", 64, CHAOS, "times a generated tangent run reads max ln|δ| at")
CHAOS_MARGIN = _constant("CHAOS_MARGIN", 10.0, CHAOS, (
    "a chaotic scene's amplification is taken this many times larger: one tangent run's growth scatters by up to "
    "e^2 between nearby tolerances; with no margin slow_spin at t = 300 was accepted at 1e-6 and ended at 1.4e-6"))
SHADOW_TOLERANCE = _constant("SHADOW_TOLERANCE", 1e-9, CHAOS, "tolerance of the shadow pair's runs")
# ---- auto's pilot and choice (``gyrolab.accuracy.auto``) -------------------------------------------------------------
PILOT_POINTS = _constant("PILOT_POINTS", 65, CALIBRATE, "samples of the pilot's error growth")
MIN_GROWTH = _constant("MIN_GROWTH", 2.0, CALIBRATE, (
    "the pilot's power law t^q is at least quadratic: a non-symplectic method's phase error on a near-integrable "
    "motion; Taylor at tol 1e-10 on the reference scene grows ×100 from t = 30 to t = 300"))
MAX_GROWTH = _constant("MAX_GROWTH", 4.0, CALIBRATE, (
    "the largest power law the pilot fits; an amplification beyond (1/pilot_fraction)^MAX_GROWTH is chaos"))
FIRST_RATIO = _constant("FIRST_RATIO", 1e-3, CALIBRATE, (
    "first pilot tolerance relative to the accuracy (final error / tolerance is 24–470 on the reference scene)"))
MIN_TOLERANCE = _constant("MIN_TOLERANCE", 1e-13, CALIBRATE, "the first pilot's tightest tolerance")
MAX_TOLERANCE = _constant("MAX_TOLERANCE", 1e-5, CALIBRATE, (
    "looser per-step tolerances take steps near the Taylor series' radius of convergence"))
TIGHT_RATIO = _constant("TIGHT_RATIO", 3000.0, CALIBRATE, (
    "the pilot's tight run is at most accuracy/TIGHT_RATIO (final tolerances are accuracy/420 … accuracy/1300)"))
MIN_PILOT_STEPS = _constant("MIN_PILOT_STEPS", 8, PROMISE, (
    "a pilot whose loose run took fewer steps measured nothing (r0 = 32 over t = 0.25 at 1e-9 ended 5.7e-5 away)"))
UNMEASURED_PER_TOL = _constant("UNMEASURED_PER_TOL", 1e3, CALIBRATE, (
    "the error per unit tolerance taken when the pilot measured nothing: above the 24–470 measured"))
RECENTRE = _constant("RECENTRE", 20.0, CALIBRATE, (
    "a first prediction this many times looser than the pilot's τ is measured again: the largest actual / raw "
    "prediction is 1.09 at every threshold from 10 to 100; at 20 the pilot re-measures in 267 of 369 runs"))
CALIBRATION = _constant("CALIBRATION", 3.0, CALIBRATE, (
    "the recorded prediction is the raw one times this: the largest actual / raw predicted final error on the "
    "extremes matrix and the reference scene at 1e-3 … 1e-13 is 0.94"))
MISS_MARGIN = _constant("MISS_MARGIN", 1000.0, PERF, "a series' predicted error is trusted to this factor")
SCREEN_POINTS = _constant("SCREEN_POINTS", 512, PERF, "grid of the screen before the series check (~0.25 ms)")
SCREEN_TOLERANCE = _constant("SCREEN_TOLERANCE", 1e-9, PERF, "tolerance of the screen's Taylor run")
FLOOR = _constant("FLOOR", 1e-15, PROMISE, "relative to the state's size: no double run reaches below")
DOUBLE_DOUBLE_FLOOR = _constant("DOUBLE_DOUBLE_FLOOR", 1e-16, PROMISE, (
    "the same for double-double: it integrates to ~1e-31 but stores its states as doubles, each rounded by up to half "
    "an ulp (≤ 1.1e-16 × the state's size); asked 5e-29 at time.end=1, the error estimate measured 1.1e-16"))
AUTO_SAMPLE = _constant("AUTO_SAMPLE", 3, PROMISE, "trajectories of a batch on which auto runs its pilot")
# ---- the recheck (``gyrolab.accuracy.promise``) ----------------------------------------------------------------------
RECHECK_MARGIN = _constant("RECHECK_MARGIN", 3.0, PROMISE, (
    "a run that broke its promise runs again aimed this many times below what would have met it; over the extremes "
    "matrix and the reference scene the measured error is at most 0.47× the prediction"))
MAX_RECHECKS = _constant("MAX_RECHECKS", 2, PROMISE, "runs made more accurate before the recheck refuses")


def report(benchmark: str, measured: dict[str, tuple[bool, str]]) -> bool:
    """Print, for every constant of the table that ``benchmark`` regenerates, whether this run's measurement
    (``measured[name]``: (supports the value, what was measured)) supports it; return False if one is contradicted.
    A constant the run did not measure is printed as unchecked."""
    mine = [c for c in TABLE.values() if c.benchmark == benchmark or c.benchmark.startswith(benchmark + " ")]
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
