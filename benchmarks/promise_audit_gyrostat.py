"""A randomized audit of gyrolab's accuracy promises on orbiting satellite-gyrostat scenes, against heyoka real128.

The gyrostat counterpart of benchmarks/promise_audit.py (whose run and estimate checks it reuses):

1. ``integrator=auto accuracy=ε`` either refuses in one sentence (a ConfigError) or its error against the
   reference — every component of the state (ω, α, γ) — is ≤ ε at the final time AND at every output time
   (the stricter reading; promise_audit.py judges the final state). Whether the error is also below the run's
   ``auto_predicted_error`` is recorded beside it.
2. The stored error estimate (``error_estimate_max_omega`` / ``error_estimate_max_attitude``, and the per-time
   series) is at most a factor 2 below the actual error (estimate / actual ≥ 0.5), above round-off; checked for
   auto and, on every ``--integrators-every``-th scene, for taylor, dop853_numba and rk4_numba with
   ``output.error_estimate=true``.

Scenes (seeded): body=gyrostat_asymmetric with random principal moments (asymmetric or with two equal, the triangle
inequality kept), random rotor momentum k (|k_i| ≲ 1), orbit rate Ω in [0.5, 1.5] with the gravity gradient
N = 3Ω², a magnetic dipole μ (random) in a field of log-uniform strength 0.05–2 along a random direction of the
orbital frame (a third of them in the radial–normal plane, the paper's h2 = 0), orbital Euler angles with
θ0 in (0.2, π − 0.2) (away from θ = 0), random ψ0, φ0, Euler rates (ψ̇0, θ̇0, φ̇0) with a spin φ̇0 log-uniform in
[0.1, 10], a span log-uniform in [3, 25] and three accuracies out of 1e-4 … 1e-12. The reference is
benchmarks/gyrostat_reference.py (equations written from the model's vector form and checked against gyrolab's
numpy right-hand side at random states for every scene; heyoka, real128, tol 1e-30) at every output time.

    nice -n 5 python benchmarks/promise_audit_gyrostat.py --n 40      # ~3 min (2 of them compiling) on 2 loaded cores
    python benchmarks/promise_audit_gyrostat.py --n 3 --no-write      # a quick look
    python benchmarks/promise_audit_gyrostat.py --n 100 --seed 5 --t-max 200 --spin-max 30 \
        --name promise_audit_gyrostat_long                            # harsher: longer spans, faster spins
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numpy as np

from gyrolab import compose_scene
from gyrolab.errors import GyrolabError

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gyrostat_reference as gr  # noqa: E402  (benchmarks/ is not a package)
from promise_audit import (ACCURACIES, BEST_TOL, ESTIMATE_FACTOR, ROUNDOFF, Scene, _command, _g, needless,  # noqa: E402
                           audit_auto, compact, estimate_check, estimates_by_integrator,
                           print_estimate_table, r_eps)
from results_file import write_results  # noqa: E402

#: (integrator, settings) audited with output.error_estimate=true on every k-th scene
INTEGRATORS = [("taylor", ["integrator.tol=1e-8"]), ("taylor", ["integrator.tol=1e-13"]),
               ("dop853_numba", ["integrator.rtol=1e-7", "integrator.atol=1e-7"]),
               ("dop853_numba", ["integrator.rtol=1e-11", "integrator.atol=1e-11"]),
               ("rk4_numba", ["integrator.step=0.01"]), ("rk4_numba", ["integrator.step=0.002"])]
#: ω, γ, α: the column order promise_audit's checks expect (the gyrostat's state is ω, α, γ)
FIXED_POINT_ORDER = [0, 1, 2, 6, 7, 8, 3, 4, 5]


def _unit(rng: np.random.Generator) -> list[float]:
    v = rng.normal(size=3)
    return (v / np.linalg.norm(v)).tolist()


def _vector(v) -> str:
    return "[" + ",".join(repr(float(x)) for x in v) + "]"


def random_scene(rng: np.random.Generator, index: int, t_max: float = 25.0, spin_max: float = 10.0) -> Scene:
    kind = str(rng.choice(["asymmetric", "asymmetric", "asymmetric", "A=B", "B=C"]))
    while True:
        A, B, C = np.round(np.exp(rng.uniform(np.log(0.5), np.log(2.5), size=3)), 4)
        if kind == "A=B":
            B = A
        elif kind == "B=C":
            C = B
        if A + B >= C and B + C >= A and C + A >= B and (kind != "asymmetric" or
                                                         min(abs(A - B), abs(B - C), abs(C - A)) > 0.05):
            break
    k = np.round(rng.normal(scale=0.5, size=3), 4)
    Omega = round(float(rng.uniform(0.5, 1.5)), 4)
    field = float(np.exp(rng.uniform(np.log(0.05), np.log(2.0))))
    if rng.random() < 1 / 3:  # in the radial–normal plane (the paper's h2 = 0)
        angle = rng.uniform(0, 2 * math.pi)
        direction = [math.cos(angle), 0.0, math.sin(angle)]
        kind += ", field ⟂ β"
    else:
        direction = _unit(rng)
    moment = np.round(rng.normal(size=3), 4)
    theta0 = float(rng.uniform(0.2, math.pi - 0.2))
    spin = math.exp(rng.uniform(math.log(0.1), math.log(spin_max))) * rng.choice([-1.0, 1.0])
    rates = [float(rng.uniform(-1, 1)), float(rng.uniform(-0.5, 0.5)), spin]
    t_end = math.exp(rng.uniform(math.log(3.0), math.log(t_max)))
    overrides = ["experiment=gyrostat", "body=gyrostat_asymmetric", f"body.inertia={_vector([A, B, C])}",
                 f"body.gyrostatic_momentum={_vector(k)}", f"body.orbit_rate={Omega}", "force=[newtonian,magnetic]",
                 "force.newtonian.k=null", f"force.magnetic.field={field:.6g}",
                 f"force.magnetic.direction={_vector(direction)}", f"force.magnetic.moment={_vector(moment)}",
                 f"initial.psi0={rng.uniform(0, 2 * math.pi):.6g}", f"initial.theta0={theta0:.6g}",
                 f"initial.phi0={rng.uniform(0, 2 * math.pi):.6g}",
                 "initial.euler_rates0=[" + ",".join(f"{x:.6g}" for x in rates) + "]", f"time.end={t_end:.5g}"]
    accuracies = sorted(rng.choice(ACCURACIES, size=3, replace=False).tolist(), reverse=True)
    return Scene(index, overrides, kind, t_end * (1.0 + abs(spin)), accuracies)


def judge(row: dict) -> dict:
    """The gyrostat audit's verdict on an auto run: refused, or ≤ ε at the final time and at every output time."""
    if "actual" not in row:
        return {**row, "promise": row["verdict"]}  # refused, or an error other than a refusal (BROKEN)
    final_ok = row["actual"] <= row["eps"]
    all_ok = row["actual_max_over_time"] <= row["eps"]
    promise = "kept" if final_ok and all_ok else "BROKEN"
    return {**row, "promise": promise, "final_ok": final_ok, "all_times_ok": all_ok,
            "below_predicted": row["actual"] <= row["predicted"]}


def audit_integrator(scene: Scene, name: str, settings: list[str], truth: np.ndarray, common: list[str],
                     floor: float) -> dict:
    overrides = [*scene.overrides, f"integrator={name}", *settings, "output.error_estimate=true", *common]
    start = time.process_time()
    try:
        ds = compose_scene(overrides).run()
    except GyrolabError as error:
        return {"integrator": name, "verdict": "refused", "why": str(error), "overrides": overrides,
                "cpu": time.process_time() - start}
    found = estimate_check(ds, truth, floor)
    verdict = ("n/a" if not found["available"] else "round-off" if math.isnan(found["ratio"]) else
               "saturated" if found["saturated"] else "UNDER" if found["under"] else "ok")
    return {"integrator": name, "verdict": verdict, "estimate": found, "overrides": overrides,
            "cpu": time.process_time() - start}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=40, help="random scenes (default 40)")
    parser.add_argument("--seed", type=int, default=31, help="seed of the scene generator")
    parser.add_argument("--integrators-every", type=int, default=4,
                        help="audit taylor / dop853_numba / rk4_numba estimates on every k-th scene (0: never)")
    parser.add_argument("--n-output", type=int, default=101, help="output times per run (time.n_output)")
    parser.add_argument("--t-max", type=float, default=25.0, help="longest span drawn (default 25)")
    parser.add_argument("--spin-max", type=float, default=10.0, help="fastest spin φ̇0 drawn (default 10)")
    parser.add_argument("--no-write", action="store_true",
                        help="do not write benchmarks/results/promise_audit_gyrostat.json")
    parser.add_argument("--name", default="promise_audit_gyrostat",
                        help="results file (benchmarks/results/NAME.json) and its table's name")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    common = [f"time.n_output={args.n_output}", "output.figures=false"]
    reference = gr.Real128Gyrostat()
    scenes = [random_scene(rng, i, args.t_max, args.spin_max) for i in range(args.n)]
    auto_rows, other_rows, checks = [], [], []
    wall = time.perf_counter()
    print("| # | scene | ε | verdict | method | final error | max over times | predicted | final/ε | max/ε | "
          "est/actual | CPU s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for scene in scenes:
        base = compose_scene([*scene.overrides, "integrator=taylor", *common])
        checks.append(gr.check_against_python_rhs(base, samples=5, seed=scene.index))
        if checks[-1] > 1e-13:
            raise SystemExit(f"scene {scene.index}: the reference's equations disagree with gyrolab's rhs "
                             f"({checks[-1]:.1e})")
        truth = reference.states(base)[:, FIXED_POINT_ORDER]
        floor = ROUNDOFF * max(1.0, float(np.max(np.abs(base.system.initial_state()))))
        label = f"{scene.kind} t={base.times[-1]:.3g}"
        for eps in scene.accuracies:
            row = judge(audit_auto(scene, eps, truth, common, floor))
            row.update(scene=scene.index, kind=scene.kind)
            auto_rows.append(row)
            if "actual" in row:
                est = row["estimate"].get("ratio", math.nan) if row["estimate"]["available"] else math.nan
                print(f"| {scene.index} | {label} | {eps:g} | {row['promise']} | {row['method']} tol "
                      f"{row['tolerance']:.2g} | {_g(row['actual'])} | {_g(row['actual_max_over_time'])} | "
                      f"{_g(row['predicted'])} | {_g(row['actual'] / eps)} | {_g(row['actual_max_over_time'] / eps)} | "
                      f"{_g(est)} | {row['cpu']:.2f} |", flush=True)
            else:
                best = (f" (taylor tol {BEST_TOL:g} ends {row['best_double']:.2g} away)" if "best_double" in row
                        else "")
                print(f"| {scene.index} | {label} | {eps:g} | {row['promise']}: {row['why'][:100]}…{best} | | | | | | | "
                      f"| {row['cpu']:.2f} |", flush=True)
        if args.integrators_every and scene.index % args.integrators_every == 0:
            for name, settings in INTEGRATORS:
                other_rows.append({**audit_integrator(scene, name, settings, truth, common, floor),
                                   "scene": scene.index, "settings": " ".join(settings)})
    wall = time.perf_counter() - wall

    print_estimate_table(other_rows)

    counts = {v: sum(r["promise"] == v for r in auto_rows) for v in ("kept", "refused", "BROKEN")}
    measured = [r for r in auto_rows if "actual" in r]
    worst_final = max((r["actual"] / r["eps"] for r in measured), default=math.nan)
    worst_all = max((r["actual_max_over_time"] / r["eps"] for r in measured), default=math.nan)
    worst_pred = max((r["actual"] / r["predicted"] for r in measured), default=math.nan)
    above_predicted = sum(not r["below_predicted"] for r in measured)
    per_integrator = estimates_by_integrator([*({**r, "integrator": "auto"} for r in measured), *other_rows])
    under = sum(v["under"] for v in per_integrator.values())
    print(f"\n{len(scenes)} gyrostat scenes (seed {args.seed}), {len(auto_rows)} auto runs: {counts['kept']} kept, "
          f"{counts['refused']} refused, {counts['BROKEN']} BROKEN (final and every output time ≤ ε); worst final/ε "
          f"{_g(worst_final)}, worst max-over-times/ε {_g(worst_all)}, worst actual/predicted {_g(worst_pred)} "
          f"({above_predicted} runs above their prediction); {len(other_rows)} other-integrator runs; {under} "
          f"estimates more than {ESTIMATE_FACTOR:g}× below the actual error; reference equations vs gyrolab's rhs: "
          f"max {max(checks):.1e}; {wall:.0f} s")
    print("\n| integrator | runs | judged (above round-off) | saturated | no estimate | estimate/actual min | max | "
          "worst per-time | under 1/2 (max) | under 1/2 (per time) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    table_rows = []
    for name, v in per_integrator.items():
        cells = [name, str(v["runs"]), str(v["judged"]), str(v["saturated"]), str(v["unavailable"]),
                 _g(v["min_ratio"] if v["judged"] else math.nan), _g(v["max_ratio"] if v["judged"] else math.nan),
                 _g(v["min_ratio_per_time"] if math.isfinite(v["min_ratio_per_time"]) else math.nan),
                 str(v["under"]), str(v["under_per_time"])]
        table_rows.append(cells)
        print("| " + " | ".join(cells) + " |")
    print()
    needless_counts = needless(auto_rows, r_eps)
    broken = [r for r in auto_rows if r["promise"] == "BROKEN"]
    underestimates = [r for r in [*({**r, "integrator": "auto"} for r in measured), *other_rows]
                      if (r.get("estimate") or {}).get("under")]
    for r in broken:
        detail = (f"final error {r['actual']:.3g}, max over the output times {r['actual_max_over_time']:.3g}, "
                  f"ε {r['eps']:g}, predicted {r['predicted']:.3g}, {r['method']} tol {r['tolerance']:.3g}"
                  if "actual" in r else r["why"])
        print(f"\nBROKEN (scene {r['scene']}): {detail}\n  reproduce: {_command(r['overrides'])}")
    for r in underestimates:
        e = r["estimate"]
        print(f"\nUNDERESTIMATE ({r['integrator']}, scene {r['scene']}): estimate/actual {e['ratio']:.3g} "
              f"(ω {e['omega']['estimate_max']:.3g} vs {e['omega']['actual_max']:.3g}, attitude "
              f"{e['attitude']['estimate_max']:.3g} vs {e['attitude']['actual_max']:.3g})\n"
              f"  reproduce: {_command(r['overrides'])}")
    if not args.no_write:
        def record(r):
            out = compact(r)
            for key in ("promise", "final_ok", "all_times_ok", "below_predicted"):
                if key in r:
                    out[key] = r[key]
            if r.get("promise") == "BROKEN" or (r.get("estimate") or {}).get("under"):
                out["reproduce"] = _command(r["overrides"])
            return out
        numbers = {"seed": args.seed, "n": args.n, "n_output": args.n_output, "t_max": args.t_max,
                   "spin_max": args.spin_max, "auto_runs": len(auto_rows),
                   **{f"auto_{k}": v for k, v in counts.items()}, "worst_final_over_eps": worst_final,
                   "worst_max_over_time_over_eps": worst_all, "worst_actual_over_predicted": worst_pred,
                   "runs_above_prediction": above_predicted,
                   **needless_counts, "reference_rhs_check_max": max(checks),
                   "estimates": {k: {**v, "min_ratio": v["min_ratio"] if v["judged"] else None,
                                     "min_ratio_per_time": v["min_ratio_per_time"]
                                     if math.isfinite(v["min_ratio_per_time"]) else None}
                                 for k, v in per_integrator.items()},
                   "wall_seconds": wall, "scene_overrides": {s.index: s.overrides for s in scenes},
                   "auto": [record(r) for r in auto_rows], "integrators": [record(r) for r in other_rows]}
        options = ("" if (args.t_max, args.spin_max) == (25.0, 10.0) else
                   f" --t-max {args.t_max:g} --spin-max {args.spin_max:g}")
        caption = (f"Randomized audit on orbiting-gyrostat scenes (`benchmarks/promise_audit_gyrostat.py --n {args.n} "
                   f"--seed {args.seed}{options}`, spans up to {args.t_max:g}, spins up to {args.spin_max:g}): "
                   f"{len(scenes)} scenes, {len(auto_rows)} auto runs, {counts['kept']} kept, "
                   f"{counts['refused']} refused, {counts['BROKEN']} broken (final and every output time ≤ ε; worst "
                   f"final/ε {_g(worst_final)}, max over times/ε {_g(worst_all)}). The error estimates against "
                   f"the real128 reference:")
        write_results(args.name, numbers, {args.name: {
            "caption": caption, "header": ["integrator", "runs", "judged (above round-off)", "saturated",
                                           "no estimate", "estimate/actual min", "max", "worst per-time",
                                           "under 1/2 (max)", "under 1/2 (per time)"],
            "rows": table_rows}}, command=f"benchmarks/promise_audit_gyrostat.py --n {args.n} --seed {args.seed}{options}"
                      + ("" if args.name == "promise_audit_gyrostat" else f" --name {args.name}"))
    return 1 if broken or underestimates else 0


if __name__ == "__main__":
    sys.exit(main())
