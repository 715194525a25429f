"""The fixed point's hand-written kernels against its traced equations (issue 31: which hand-written form still earns its place).

    python benchmarks/built_in_vs_traced.py            # about a minute
    python benchmarks/built_in_vs_traced.py --rounds 3

On the reference scene (``experiment=perf_reference``: t ∈ [0, 300], 3,001 output times), with the state (ω, γ)
and with α carried (``output.euler_angles=true``): the same equations run by the hand-written form
(``models.FIXED_POINT``, ``fixed_point.pack``'s parameters) and by the form traced from the system's numpy
``euler_poisson`` (``plugins/systems/fixed_point.traced_model``), under ``taylor`` (double), ``dop853_numba`` and
double-double ``taylor``. CPU time (``time.process_time``), the two forms interleaved, minimum over the rounds. A
form with α is no longer hand-written: its "hand" column is gone from the kernels, and this prints only the traced
one for it (the numbers that retired it are in docs/performance.md).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gyrolab import compose_scene
from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor
from gyrolab.plugins.systems.fixed_point import traced_model

SETTINGS = [("taylor", lambda: Taylor(tol=1e-9)), ("taylor", lambda: Taylor(tol=1e-15)),
            ("dop853_numba", lambda: DOP853Numba(rtol=1e-9, atol=1e-12)),
            ("dop853_numba", lambda: DOP853Numba(rtol=1e-12, atol=1e-15)),
            ("double-double", lambda: Taylor(tol=1e-20, precision="double-double"))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()
    print("| state | integrator | setting | hand-written (ms) | traced (ms) | traced / hand |")
    print("| --- | --- | --- | --- | --- | --- |")
    for alpha in (False, True):
        scene = compose_scene(["experiment=perf_reference", f"output.euler_angles={str(alpha).lower()}"])
        system = scene.system
        t_out, y0 = scene.times, system.initial_state()
        forms = {"traced": traced_model(system.inertia, system.forces, system.carries_alpha)}
        if scene.compiled.model == 0:  # models.FIXED_POINT: the hand-written form
            forms["hand"] = scene.compiled
        for name, make in SETTINGS:
            integrator = make()
            best = {key: np.inf for key in forms}
            ends = {}
            for key, compiled in forms.items():  # compile and warm up
                ends[key] = integrator.integrate(None, t_out, y0, None, compiled).y[-1]
            for _ in range(args.rounds):
                for key, compiled in forms.items():
                    start = time.process_time()
                    integrator.integrate(None, t_out, y0, None, compiled)
                    best[key] = min(best[key], time.process_time() - start)
            if "hand" in ends:  # the same equations: the same trajectory to the method's accuracy
                assert np.max(np.abs(ends["hand"] - ends["traced"])) < 1e-6, (name, ends)
            setting = ", ".join(f"{k}={v:g}" for k, v in integrator.attributes().items()
                                if k in ("integrator_tol", "rtol", "integrator_rtol"))
            hand = best.get("hand")
            ratio = f"{best['traced'] / hand:.2f}" if hand else "(no hand-written form)"
            hand_cell = f"{hand * 1e3:.2f}" if hand else "—"
            print(f"| {'(ω, γ, α)' if alpha else '(ω, γ)'} | {name} | {setting} | {hand_cell} | "
                  f"{best['traced'] * 1e3:.2f} | {ratio} |")


if __name__ == "__main__":
    main()
