"""A third-party force plugin against the built-ins: compiled speed of a traced torque (issue 12, item 1).

    python benchmarks/plugin_speed.py            # tolerances 1e-8 .. 1e-12, 10 repeats
    python benchmarks/plugin_speed.py --quick    # two tolerances, 3 repeats

The reference problem (``experiment=perf_reference``: uniform gravity + Newtonian centre, k = 0.5,
t ∈ [0, 300], 3,001 output times) is run twice: with the built-in forces (their packed compiled
form), and with the same two torques written as a third-party plugin in plain Python
(``cross(r, γ)`` and ``N γ × Iγ``: the same arithmetic), which gyrolab traces and compiles. Both
under ``dop853_numba``, interleaved, integration time only (best of the repeats); the plugin also
under scipy's DOP853 (gyrolab's ``dop853``: the Python right-hand side), at equal error.
Error = max-norm of the final state's error against the extended-precision reference.
Targets (issue 12): plugin ≤ 1.3× the built-in's time; ≥ 150× faster than scipy DOP853. Then both
under ``taylor`` (the plugin's series from the generated kernel of ``taylor_series``); target (issue 24,
item 2): plugin ≤ 2× the built-in's time. Last (full run only), the compile time of the plugin's Taylor
kernel: generated and compiled in a process with an empty kernel cache, then loaded by a second process.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_file import write_results  # noqa: E402  (benchmarks/ is not a package)

PLUGIN = textwrap.dedent('''
    from gyrolab.contracts import Force
    from gyrolab.physics.vectors import cross


    class PlainGravity(Force):
        name = "plain_gravity"
        required_axes = frozenset({2})
        preserves_area_integral = True

        def __init__(self, body):
            self.w = body.weight_moment

        def torque(self, omega, axes):
            return cross(self.w, axes[2])


    class PlainNewtonian(Force):
        name = "plain_newtonian"
        required_axes = frozenset({2})
        preserves_area_integral = True

        def __init__(self, body, *, k=0.5):
            self.N, self.inertia = float(k), body.inertia  # nondimensional body: c² = 1, N = k

        def torque(self, omega, axes):
            e = axes[2]
            return self.N * cross(e, self.inertia * e)
''')


def _install(site: Path) -> None:
    (site / "plain_forces.py").write_text(PLUGIN)
    info = site / "plain_forces-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: plain-forces\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[gyrolab.forces]\nplain_gravity = plain_forces:PlainGravity\n"
                                           "plain_newtonian = plain_forces:PlainNewtonian\n")
    sys.path.insert(0, str(site))


def rhs_cost(base: list[str], plugin: list[str], compose_scene) -> None:
    """One right-hand-side evaluation, built-in form against the traced plugin (ns; best of 20 loops of 10⁵)."""
    import numba

    from gyrolab.kernels import models

    @numba.njit
    def loop(p, y, out, n):
        for i in range(n):
            models.rhs(1e-9 * i, y, p, out)
            y[0] += 1e-300 * out[0]  # a dependency, so that no evaluation is optimised away
        return out[0]

    costs = []
    for overrides in (base, plugin):
        compiled = compose_scene(overrides).compiled
        y = compose_scene(overrides).system.initial_state()
        out = np.empty_like(y)
        loop(compiled.params, y, out, 10)
        best = np.inf
        for _ in range(20):
            start = time.perf_counter()
            loop(compiled.params, y, out, 100_000)
            best = min(best, time.perf_counter() - start)
        costs.append(best / 100_000 * 1e9)
    print(f"right-hand side: built-in {costs[0]:.1f} ns, plugin {costs[1]:.1f} ns per evaluation "
          f"(ratio {costs[1] / costs[0]:.2f})\n")


_KERNEL_TIME = textwrap.dedent('''
    import sys
    import time

    sys.path.insert(0, sys.argv[1])
    from plain_forces import PlainGravity, PlainNewtonian
    from gyrolab import compose_scene
    from gyrolab.kernels import taylor_series, expression

    body = compose_scene(["experiment=perf_reference"]).system.body
    trace = expression.trace([PlainGravity(body), PlainNewtonian(body, k=0.5)])
    expression.compile_trace(trace, ["plain_gravity", "plain_newtonian"])  # (the right-hand side's, as a run does)
    start = time.perf_counter()
    taylor_series.compile_taylor(trace, ["plain_gravity", "plain_newtonian"])
    print(time.perf_counter() - start)
''')


def taylor_kernel_times(site: Path) -> tuple[float, float]:
    """Seconds to generate and compile the plugin's Taylor kernel in a process with an empty kernel cache, and to
    load it in a second process on that cache (after the torque's right-hand-side kernel, as in a run: numba's
    start-up and gyrolab's own kernels are not timed)."""
    import os
    import subprocess

    times = []
    with tempfile.TemporaryDirectory() as cache:
        for _ in range(2):
            done = subprocess.run([sys.executable, "-c", _KERNEL_TIME, str(site)], capture_output=True, text=True,
                                  env=dict(os.environ, NUMBA_CACHE_DIR=cache), check=True)
            times.append(float(done.stdout.split()[-1]))
    return times[0], times[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    tols = (1e-8, 1e-11) if args.quick else (1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
    repeats = 3 if args.quick else 10
    site = Path(tempfile.mkdtemp())
    _install(site)

    from gyrolab import compose_scene
    from gyrolab.physics.reference import fixed_point_reference

    scene = ["body=asymmetric_top", "initial=fast_spin", "initial.gamma0=[0.8414709848078965,0.0,0.5403023058681398]",
             "initial.theta0=null", "initial.phi0=null", "time.end=300", "time.n_output=3001",
             "output.euler_angles=false"]  # experiment=perf_reference, spelled out so that the forces can change
    base = [*scene, "force=[uniform_gravity,newtonian]", "force.newtonian.k=0.5"]
    plugin = [*scene, "force=[plain_gravity,plain_newtonian]", "force.plain_newtonian.k=0.5"]
    first = compose_scene([*base, "integrator=dop853_numba"])
    y0 = first.system.initial_state()
    truth = fixed_point_reference(first.system.inertia, first.system.body.weight_moment, 0.5, y0,
                                  [0.0, 300.0])[-1].astype(float)

    def timed(overrides: list[str], tol: float, n: int) -> tuple[float, float]:
        scene = compose_scene([*overrides, f"integrator.rtol={tol}", f"integrator.atol={tol}"])
        compiled = scene.compiled
        best, error = np.inf, np.nan
        for _ in range(n):
            solution = scene.integrator.integrate(scene.system.rhs, scene.times, y0, None, compiled)
            best = min(best, solution.stats.wall_time)
            error = float(np.max(np.abs(solution.y[-1] - truth)))
        return best, error

    for overrides in ([*base, "integrator=dop853_numba"], [*plugin, "integrator=dop853_numba"]):
        timed(overrides, 1e-6, 1)  # compile (or load) the kernels outside the timing
    rhs_cost([*base, "integrator=dop853_numba"], [*plugin, "integrator=dop853_numba"], compose_scene)
    print(f"{'tol':>7} {'built-in s':>11} {'error':>9} {'plugin s':>9} {'error':>9} {'ratio':>6}")
    rows, dop_rows, taylor_rows = [], [], []
    for tol in tols:
        b_time = p_time = np.inf
        for _ in range(repeats):  # interleaved: the machine's load hits both alike
            bt, b_err = timed([*base, "integrator=dop853_numba"], tol, 1)
            pt, p_err = timed([*plugin, "integrator=dop853_numba"], tol, 1)
            b_time, p_time = min(b_time, bt), min(p_time, pt)
        rows.append((tol, p_time, p_err))
        dop_rows.append([f"{tol:.0e}", f"{b_time * 1e3:.2f}", f"{b_err:.1e}", f"{p_time * 1e3:.2f}", f"{p_err:.1e}",
                         f"{p_time / b_time:.2f}×"])
        print(f"{tol:7.0e} {b_time:11.5f} {b_err:9.2e} {p_time:9.5f} {p_err:9.2e} {p_time / b_time:6.2f}")

    print("\nscipy DOP853 (gyrolab dop853, Python right-hand side) on the plugin scene, at equal error:")
    print(f"{'tol':>7} {'scipy s':>9} {'error':>9}   {'compiled plugin s':>17} (its error) {'speed-up':>9}")
    for tol in ((1e-8, 1e-10) if args.quick else (1e-8, 1e-9, 1e-10, 1e-11)):
        s_time, s_err = timed([*plugin, "integrator=dop853"], tol, 1)
        # the cheapest compiled run whose error is at most scipy's
        candidates = [(t, e) for _, t, e in rows if e <= s_err]
        if not candidates:
            print(f"{tol:7.0e} {s_time:9.3f} {s_err:9.2e}   (no compiled run as accurate)")
            continue
        c_time, c_err = min(candidates)
        print(f"{tol:7.0e} {s_time:9.3f} {s_err:9.2e}   {c_time:17.5f} ({c_err:8.2e}) {s_time / c_time:8.0f}×")

    print("\ntaylor (the plugin's series from its generated kernel, taylor_series) against the built-in's series:")
    print(f"{'tol':>7} {'built-in s':>11} {'error':>9} {'plugin s':>9} {'error':>9} {'ratio':>6}")
    for tol in ((1e-9, 1e-13) if args.quick else (1e-8, 1e-10, 1e-12, 1e-13)):
        runs = {}
        for _ in range(repeats):  # interleaved
            for name, overrides in (("built-in", base), ("plugin", plugin)):
                scene = compose_scene([*overrides, "integrator=taylor", f"integrator.tol={tol}"])
                solution = scene.integrator.integrate(scene.system.rhs, scene.times, y0, None, scene.compiled)
                best = min(runs.get(name, (np.inf,))[0], solution.stats.wall_time)
                runs[name] = (best, float(np.max(np.abs(solution.y[-1] - truth))))
        (b_time, b_err), (p_time, p_err) = runs["built-in"], runs["plugin"]
        print(f"{tol:7.0e} {b_time:11.5f} {b_err:9.2e} {p_time:9.5f} {p_err:9.2e} {p_time / b_time:6.2f}")
        taylor_rows.append([f"{tol:.0e}", f"{b_time * 1e3:.2f}", f"{b_err:.1e}", f"{p_time * 1e3:.2f}", f"{p_err:.1e}",
                            f"{p_time / b_time:.2f}×"])
    if args.quick:
        return
    compile_s, load_s = taylor_kernel_times(site)
    print(f"\nthe plugin's Taylor kernel: compiled in {compile_s:.3f} s (a fresh kernel cache), loaded from the cache "
          f"in {load_s:.3f} s (a second process)")
    worst_taylor = max(float(row[-1].rstrip("×")) for row in taylor_rows)
    header = ["tol", "built-in ms", "error", "plugin ms", "error", "plugin / built-in"]
    caption = ("`experiment=perf_reference` (t ∈ [0, 300], 3,001 outputs), gravity + Newtonian as built-ins and as "
               "a plain-Python plugin with the same arithmetic; integration time (the solution's wall_time), "
               f"minimum of {repeats} interleaved repeats; error against the extended-precision reference.")
    write_results("plugin_speed", {"repeats": repeats, "dop853_numba": dop_rows, "taylor": taylor_rows,
                                   "taylor_kernel_compile_s": compile_s, "taylor_kernel_load_s": load_s},
                  {"plugin_speed_dop853": {"caption": "`dop853_numba`: " + caption, "header": header, "rows": dop_rows},
                   "plugin_speed_taylor": {"caption": "`taylor`: " + caption, "header": header, "rows": taylor_rows}},
                  clock="the integrator's wall_time (time.perf_counter), minimum of interleaved repeats",
                  summary=[["force plugin (gravity + Newtonian in plain Python) under `taylor` / the built-in, worst "
                            "over tol 1e-8 … 1e-13", f"{worst_taylor:.2f}×", "≤ 2×",
                            "PASS" if worst_taylor <= 2.0 else "FAIL"]])


if __name__ == "__main__":
    start = time.perf_counter()
    main()
    print(f"\n(total {time.perf_counter() - start:.0f} s; timings are noisy on a shared machine)")
