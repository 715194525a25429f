"""An animation of the motion stored in a ``run.nc``: the body turning about the fixed point.

``animate(path)`` draws, frame by frame, the body's principal axes and its inertia ellipsoid in the fixed
frame (the orbital frame for the orbiting gyrostat), the trace of the apex (the tip of the body z axis) on
the unit sphere up to the frame's time, and the time in the title. It writes a GIF (Pillow, which comes with
matplotlib) or, when ffmpeg is on PATH, an MP4.

The attitude is read, not integrated: the rows of the rotation matrix from body to fixed axes are the fixed
axes seen from the body, α (X), β = γ × α (Y) and γ (Z), which a run stores when it keeps the full
attitude (``output.euler_angles=true``, the default); the orbiting gyrostat stores α, β, γ of its orbital
frame. Frames are output times of the run, evenly picked (no interpolation): a run whose spin is faster than
the frames are dense shows the spin aliased; ``frames`` (at most ``MAX_FRAMES``) or a shorter run helps.

gyrolab's fixed Z points along the weight (down), so for the heavy body Z is drawn pointing down the page,
as in ``body_axis_sphere``. The inertia ellipsoid x·Ix = 1 has semi-axes 1/√I_i, scaled so the longest is
0.8 (inside the unit sphere the apex runs on).
"""

from __future__ import annotations

import logging
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import matplotlib
import numpy as np
import xarray as xr

from gyrolab.errors import ConfigError
from gyrolab.figures.labels import unit
from gyrolab.figures.style import RC, Figure, figure, unit_sphere
from gyrolab.output.atomic import atomic_path
from gyrolab.output.foreign import load_run
from gyrolab.output.trust import check_output_target

log = logging.getLogger(__name__)

FORMATS = ("gif", "mp4")
DEFAULT_FRAMES = 120
#: more frames than this make a slow, large file for no gain a viewer can see
MAX_FRAMES = 600
DEFAULT_FPS = 20
#: GIF frames are small images: 4 in at 100 dpi is 400 pixels wide
GIF_DPI = 100
MP4_DPI = 150
SIZE = 4.0
#: body x, y, z axes; the apex trace has the z axis' colour (it is the z axis' tip)
AXIS_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")
ELLIPSOID_SIZE = 0.8


def attitude(ds: xr.Dataset) -> tuple[np.ndarray, tuple[str, str, str], bool, str]:
    """(R over time, the frame's axis names, whether Z is drawn pointing down, what is shown): ``R[k] @ v_body``
    is v in the fixed frame (the orbital frame for the orbiting gyrostat)."""
    if "alpha" not in ds or "gamma" not in ds:
        raise ConfigError("this run.nc has no full attitude (no alpha, the fixed X axis in body axes) to animate; "
                          "run it again with output.euler_angles=true")
    alpha, gamma = _unit_vectors(ds, "alpha"), _unit_vectors(ds, "gamma")
    beta = _unit_vectors(ds, "beta") if "beta" in ds else np.cross(gamma, alpha)
    rotation = np.stack([alpha, beta, gamma], axis=1)          # rows: the fixed axes in body axes
    if ds.attrs.get("system") == "orbiting_gyrostat":
        return rotation, ("radial", "along-track", "orbit normal"), False, "Gyrostat in the orbital frame"
    return rotation, ("X", "Y", "Z (along the weight)"), True, "Body about the fixed point"


def _unit_vectors(ds: xr.Dataset, name: str) -> np.ndarray:
    """``ds[name]`` as gyrolab writes it, (time, 3) finite numbers, or one sentence naming what is wrong."""
    values = ds[name]
    if values.dims[:1] != ("time",) or values.ndim != 2 or values.shape[1] != 3 or values.dtype.kind not in "fiu":
        raise ConfigError(f"this run.nc's {name} is {values.dtype.name} over {values.dims} {tuple(values.shape)}, "
                          "not the (time, 3) numbers gyrolab writes; the dataset was edited")
    data = np.asarray(values.values, dtype=float)
    if not np.all(np.isfinite(data)):
        raise ConfigError(f"this run.nc's {name} holds NaN or inf at {int((~np.isfinite(data)).any(1).sum())} output "
                          "times; a run gyrolab wrote holds finite values (the dataset was edited)")
    return data


def principal_moments(ds: xr.Dataset) -> np.ndarray:
    """(A, B, C) of the body: SI or gyrostat inertia as stored, else the papers' (a, b, 1) in units of C; a sphere
    when the dataset does not say, or says something else than three positive finite numbers."""
    try:
        if "body_inertia" in ds.attrs:
            moments = np.asarray(ds.attrs["body_inertia"], dtype=float).reshape(3)
        else:
            a = ds.attrs.get("body_nondim_a", ds.attrs.get("body_a"))
            b = ds.attrs.get("body_nondim_b", ds.attrs.get("body_b"))
            moments = np.array([float(a), float(b), 1.0])
    except (TypeError, ValueError):
        return np.ones(3)   # unknown: a sphere (the principal axes still show the attitude)
    return moments if np.all(np.isfinite(moments)) and np.all(moments > 0) else np.ones(3)


def ellipsoid_curves(moments: np.ndarray, n: int = 48) -> list[np.ndarray]:
    """Curves (each (n, 3), body axes) outlining the inertia ellipsoid: its three principal sections and two
    parallels at ±half height, enough to see it turn and cheap to redraw."""
    semi = 1.0 / np.sqrt(np.asarray(moments, dtype=float))
    semi = ELLIPSOID_SIZE * semi / semi.max()
    s = np.linspace(0.0, 2.0 * np.pi, n)
    c, sn, zero = np.cos(s), np.sin(s), np.zeros(n)
    unit_curves = [np.stack([c, sn, zero], 1), np.stack([c, zero, sn], 1), np.stack([zero, c, sn], 1)]
    unit_curves += [np.stack([np.sqrt(1 - z * z) * c, np.sqrt(1 - z * z) * sn, np.full(n, z)], 1) for z in (-0.5, 0.5)]
    return [curve * semi for curve in unit_curves]


def frame_indices(n_times: int, frames: int) -> np.ndarray:
    """``frames`` output indices evenly spread over the run, first and last included (all of them if fewer)."""
    if n_times < 2:
        raise ConfigError(f"this run.nc has {n_times} output time(s); an animation needs at least 2")
    return np.unique(np.linspace(0, n_times - 1, min(frames, n_times)).round().astype(int))


def motion_figure(ds: xr.Dataset, indices: np.ndarray) -> tuple[Figure, Callable[[int], None]]:
    """The figure and ``update(k)``, which draws frame ``k`` (output index ``indices[k]``) and titles it with its
    time."""
    with matplotlib.rc_context(RC):
        rotation, names, down, what = attitude(ds)
        t = ds["time"].values
        units = unit(ds, ds["time"].attrs.get("units"), "time")
        apex = rotation[:, :, 2]                                   # body z axis in the fixed frame
        fig = figure(SIZE, SIZE + 0.4, layout="none")
        fig.subplots_adjust(left=0.02, right=0.92, top=0.95, bottom=0.1)
        ax = fig.add_subplot(projection="3d")
        unit_sphere(ax, n=19)
        ax.set_xlim(-1, 1), ax.set_ylim(-1, 1), ax.set_zlim(-1, 1)
        ax.set_xlabel(names[0], labelpad=-6), ax.set_ylabel(names[1], labelpad=-6), ax.set_zlabel(names[2], labelpad=-6)
        if down:
            ax.invert_zaxis()                                      # Z along the weight: drawn pointing down
        ax.plot(*apex[indices].T, color="0.6", lw=0.4, ls=":")     # the whole apex trace, faint
        trace, = ax.plot([], [], [], color=AXIS_COLOURS[2], lw=0.9, alpha=0.8, label="apex trace (tip of body z)")
        curves = ellipsoid_curves(principal_moments(ds))
        shells = [ax.plot([], [], [], color="0.45", lw=0.6)[0] for _ in curves]
        shells[0].set_label("inertia ellipsoid")
        axes = [ax.plot([], [], [], color=colour, lw=2.0, label=f"body {name} axis")[0]
                for colour, name in zip(AXIS_COLOURS, "xyz")]
        fig.legend(handles=[*axes, shells[0], trace], loc="lower center", ncols=3, fontsize=7, frameon=False)
        title = fig.suptitle("")

        def update(k: int) -> None:
            i = int(indices[k])
            R = rotation[i]
            for line, shell in zip(shells, curves):
                line.set_data_3d(*(shell @ R.T).T)
            for j, line in enumerate(axes):
                line.set_data_3d([0.0, R[0, j]], [0.0, R[1, j]], [0.0, R[2, j]])
            path = apex[indices[: k + 1]]
            trace.set_data_3d(path[:, 0], path[:, 1], path[:, 2])
            title.set_text(f"{what}, t = {float(t[i]):.3f}" + (f" ({units})" if units else ""))

        update(0)
        return fig, update


def _check(fmt: str, frames: int, fps: float) -> str:
    fmt = str(fmt).lower().lstrip(".")
    if fmt not in FORMATS:
        raise ConfigError(f"animation format {fmt!r} is not one of {', '.join(FORMATS)}")
    if fmt == "mp4" and shutil.which("ffmpeg") is None:
        raise ConfigError("animation format 'mp4' needs ffmpeg on PATH (not found); use format gif")
    if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or not 2 <= frames <= MAX_FRAMES:
        raise ConfigError(f"animation frames={frames!r} must be a whole number from 2 to {MAX_FRAMES}")
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.number)) or not 0 < fps <= 60:
        raise ConfigError(f"animation fps={fps!r} must be a number of frames per second in (0, 60]")
    return fmt


def animate(path: str | os.PathLike[str], output: str | os.PathLike[str] | None = None, fmt: str = "gif",
            frames: int = DEFAULT_FRAMES, fps: float = DEFAULT_FPS) -> Path:
    """Animate the run stored at ``path`` (a ``run.nc`` or its run directory); returns the file written.

    ``output`` defaults to ``figures/animation.<fmt>`` beside the run.nc; ``fmt`` is ``gif`` (Pillow) or
    ``mp4`` (ffmpeg on PATH); ``frames`` output times (at most ``MAX_FRAMES``) are shown at ``fps`` frames per
    second. The file appears whole or not at all.
    """
    fmt = _check(fmt, frames, fps)
    if output is not None:
        check_output_target(output, "-o")
    path = Path(path)
    file = path / "run.nc" if path.is_dir() else path
    if not file.is_file():
        raise ConfigError(f"--animate: {str(path)!r} is neither a run.nc nor a run directory holding one")
    ds = load_run(file)  # the loader every reader uses
    if "time" not in ds.dims or ds["time"].ndim != 1 or not np.all(np.isfinite(ds["time"].values)):
        raise ConfigError(f"{str(file)!r} has no time axis of finite times to animate; the dataset was edited")
    indices = frame_indices(ds.sizes["time"], int(frames))
    target = Path(output) if output is not None else file.parent / "figures" / f"animation.{fmt}"
    fig, update = motion_figure(ds, indices)
    # written beside the target under a temporary name, renamed when complete (the format is named)
    with atomic_path(target) as tmp, matplotlib.rc_context(RC):
        (_write_gif if fmt == "gif" else _write_mp4)(fig, update, len(indices), fps, tmp)
    log.info("wrote %s (%d frames)", target, len(indices))
    return target


def _write_gif(fig: Figure, update: Callable[[int], None], n: int, fps: float, path: Path) -> None:
    from PIL import Image  # start-up: PIL only for a GIF

    fig.set_dpi(GIF_DPI)
    images = []
    for k in range(n):
        update(k)
        fig.canvas.draw()
        rgba = np.asarray(fig.canvas.buffer_rgba())
        images.append(Image.fromarray(rgba[..., :3].copy()).convert("P", palette=Image.Palette.ADAPTIVE, colors=255))
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:], duration=round(1000 / fps), loop=0)


def _write_mp4(fig: Figure, update: Callable[[int], None], n: int, fps: float, path: Path) -> None:
    from matplotlib.animation import FFMpegWriter  # start-up: only for an MP4

    writer = FFMpegWriter(fps=fps, codec="libx264", extra_args=["-pix_fmt", "yuv420p", "-f", "mp4"])
    with writer.saving(fig, str(path), MP4_DPI):
        for k in range(n):
            update(k)
            writer.grab_frame()
