"""A small real stability map (40 × 40) of the default body, computed with the chaos kernel; draws the gallery figure.

    python examples/stability_map_40x40.py [OUT_DIR]      # writes OUT_DIR/stability_map.nc and figures/

The grid: θ0 ∈ [0.05, π − 0.05] (40 values), r0/c ∈ [0.05, 10] (40 values, geometric), p0 = 0.1, q0 = −0.05,
φ0 = π/2 (the reference scene's), t ∈ [0, 300] (units of 1/c), RK4 step 0.01. Poincaré sections of three points.
``experiment=stability_map`` (gyrolab.batch) runs the same indicator at any size, chunked and resumable.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr

from gyrolab import compose_scene
from gyrolab.figures.stability_map import draw
from gyrolab.output.atomic import atomic_path
from gyrolab.physics.attitude import gamma_from_angles
from gyrolab.analysis.chaos import indicator_outputs, section_dataset

T_END, STEP = 300.0, 0.01
SECTIONS = ((0.6, 3.0), (1.0, 1.5), (0.4, 0.5))  # (θ0, r0/c): regular fast spin, chaotic, regular slow spin


def initial_states(theta0: np.ndarray, r0: np.ndarray, p0: float = 0.1, q0: float = -0.05) -> np.ndarray:
    th, rr = np.meshgrid(theta0, r0, indexing="ij")
    y0 = np.empty(th.shape + (6,))
    y0[..., 0], y0[..., 1], y0[..., 2] = p0, q0, rr
    y0[..., 3:6] = np.moveaxis(gamma_from_angles(th, np.pi / 2), 0, -1)
    return y0.reshape(-1, 6)


def main(out: Path) -> None:
    scene = compose_scene(["integrator=rk4_numba", f"integrator.step={STEP}", "output.euler_angles=false"])
    compiled = scene.system.compiled_model()
    theta0 = np.linspace(0.05, np.pi - 0.05, 40)
    r0 = np.geomspace(0.05, 10.0, 40)
    tic = time.perf_counter()
    outputs = indicator_outputs(compiled, scene.integrator, np.linspace(0.0, T_END, 2), initial_states(theta0, r0))
    print(f"{theta0.size * r0.size} trajectories in {time.perf_counter() - tic:.1f} s")
    ds = xr.Dataset({name: (("theta0", "r0"), values.reshape(theta0.size, r0.size), attrs)
                     for name, (values, attrs) in outputs.items()},
                    coords={"theta0": ("theta0", theta0, {"units": "rad", "long_name": "initial nutation angle"}),
                            "r0": ("r0", r0, {"units": "1", "long_name": "initial spin r0 (units of c)"})},
                    attrs={**scene.system.attributes(), "t_end": T_END, "integrator_step": STEP})
    ds.attrs = {k: v for k, v in ds.attrs.items() if not isinstance(v, (bool, np.bool_))}
    points = np.array(SECTIONS)
    y0s = np.concatenate([initial_states(np.array([t]), np.array([r])) for t, r in points])
    ds = ds.merge(section_dataset(compiled, y0s, points[:, 0], points[:, 1], 2000.0, STEP), combine_attrs="override")
    out.mkdir(parents=True, exist_ok=True)
    with atomic_path(out / "stability_map.nc") as tmp:
        ds.to_netcdf(tmp)
    print(draw(ds, out / "figures"))


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "outputs/stability_map_40x40"))
