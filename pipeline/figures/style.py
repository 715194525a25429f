"""gyrolab's figure style, applied in one place, and the drawing helpers every figure module shares.

``STYLE`` (``gyrolab.mplstyle``) is applied by ``styled`` around every ``draw_*`` function and by
``gyrolab.figures.save.save`` around writing, so a figure looks the same whatever the caller's
matplotlib settings, and the caller's settings are left as they were. Figures are ``Figure`` objects
rendered by Agg (``figure``), not pyplot's: nothing to close, and pyplot is not imported.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

STYLE = Path(__file__).with_name("gyrolab.mplstyle")
#: the style's settings, read once: ``matplotlib.rc_context(RC)`` is ``matplotlib.style.context(STYLE)``
RC = matplotlib.rc_params_from_file(STYLE, use_default_template=False)
#: journal column widths in inches (single column, double column / full page width)
SINGLE = 3.5
DOUBLE = 7.1
#: more visible oscillations than this across a panel and a line becomes a solid band: draw the envelope
MAX_OSCILLATIONS = 40
#: at most this many bins of the min–max envelope
ENVELOPE_BINS = 400

F = TypeVar("F", bound=Callable[..., Any])


def styled(draw: F) -> F:
    """Run a drawing function inside gyrolab's style context; its log axes get readable ticks. ``dpi``: the figure's,
    when it is to be saved at that dpi (what it measures then, e.g. in ``fit``, is what the save draws: measured once)."""
    @functools.wraps(draw)
    def wrapper(*args: Any, dpi: float | None = None, **kwargs: Any) -> Any:
        with matplotlib.rc_context({**RC, **({"figure.dpi": dpi} if dpi else {})}):
            fig = draw(*args, **kwargs)
            for ax in fig.axes:
                if ax.name == "rectilinear":
                    tidy_log(ax)
            return fig
    return wrapper  # type: ignore[return-value]


def tidy_log(ax: Axes) -> None:
    """Log axes: no labels on minor ticks (they collide on narrow panels); an axis spanning less than
    about two decades gets majors at 1, 2, 5 × 10ⁿ instead, so it is never left without a label."""
    for axis, limits in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        if axis.get_scale() != "log":
            continue
        low, high = sorted(abs(v) for v in limits)
        if low > 0 and np.log10(high / low) < 1.8:
            axis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0), numticks=15))
            axis.set_major_formatter(matplotlib.ticker.LogFormatterSciNotation(
                labelOnlyBase=False, minor_thresholds=(np.inf, np.inf)))
        axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def figure(width: float, height: float, layout: str | None = None) -> Figure:
    """A figure of ``width`` × ``height`` inches rendered by Agg; ``layout="none"``: no layout engine at all (margins
    by hand or ``fit``), not matplotlib's placeholder, with which savefig would draw the figure twice."""
    with matplotlib.rc_context({"figure.constrained_layout.use": False} if layout == "none" else {}):
        fig = Figure(figsize=(width, height), layout=None if layout == "none" else layout)
    FigureCanvasAgg(fig)
    return fig


def subplots(nrows: int = 1, ncols: int = 1, *, width: float = SINGLE, height: float | None = None,
             layout: str | None = None, **kwargs: Any) -> tuple[Figure, np.ndarray]:
    """A grid of panels at a journal column width (``SINGLE`` or ``DOUBLE``); axes always 2-D."""
    fig = figure(width, height if height is not None else 1.0 + 1.7 * nrows, layout)
    return fig, fig.subplots(nrows, ncols, squeeze=False, **kwargs)


def fit(fig: Figure, axes: np.ndarray) -> None:
    """Fixed margins for a grid of panels (``subplots(layout="none")``) measured once from the text around them (tick
    and axis labels, notes, legends beside a panel, the figure's title and legend): the constrained layout's room at
    a fraction of its cost (docs/performance.md, "The default run"). Measured with the panels at their largest: at
    their final size they get no more ticks, so no wider labels. Sizes in points."""
    rc, renderer, (width, height) = matplotlib.rcParams, fig.canvas.get_renderer(), fig.get_size_inches() * 72
    scale, pad, (rows, cols) = 72 / fig.dpi, 72 * rc["figure.constrained_layout.w_pad"], axes.shape
    fig.subplots_adjust(0.02, 0.02, 0.98, 0.98, 0.02, 0.02)

    def size(artists: Sequence[Any], i: int, gap: float = 0.0) -> float:  # widest (i=0) or tallest (1) shown, + gap
        extent = max((a.get_window_extent(renderer).size[i] * scale for a in artists if a is not None and a.get_visible()
                      and getattr(a, "get_text", lambda: "drawn")()), default=0.0)
        return extent + gap if extent else 0.0

    sides = np.zeros((rows, cols, 4))  # left, bottom, top, right of each panel
    for (i, j), ax in np.ndenumerate(axes):
        tidy_log(ax)  # the log axes' final ticks are the ones measured
        x, y = ax.xaxis.get_majorticklabels(), ax.yaxis.get_majorticklabels()
        sides[i, j] = (size(y, 0, rc["ytick.major.pad"]) + size([ax.yaxis.label], 0, rc["axes.labelpad"]),
                       size(x, 1, rc["xtick.major.pad"]) + size([ax.xaxis.label], 1, rc["axes.labelpad"]),
                       max(size([ax.title, ax._left_title, ax._right_title], 1, rc["axes.titlepad"])
                           + size([ax.yaxis.offsetText], 1, pad), size(y, 1) / 2),
                       max(size([ax.get_legend()], 0, 0.01 * width / cols), size(x, 0) / 2))
    if fig._suptitle is not None:
        fig._suptitle.set(y=1 - pad / height, va="top")
    top = pad + sides[0, :, 2].max() + size([fig._suptitle], 1, pad)
    bottom = pad + sides[-1, :, 1].max() + max((box.get_window_extent(renderer).y1 * scale for box in fig.legends),
                                               default=0.0)  # a figure legend sits at the bottom edge
    left, right = pad + sides[:, 0, 0].max(), pad + sides[:, -1, 3].max()
    wgap = max((sides[:, j, 3].max() + sides[:, j + 1, 0].max() + 2 * pad for j in range(cols - 1)), default=0.0)
    hgap = max((sides[i, :, 1].max() + sides[i + 1, :, 2].max() + 2 * pad for i in range(rows - 1)), default=0.0)
    fig.subplots_adjust(left / width, bottom / height, 1 - right / width, 1 - top / height,
                        wgap * cols / (width - left - right - wgap * (cols - 1)),
                        hgap * rows / (height - top - bottom - hgap * (rows - 1)))


def legend_outside(fig: Figure, axes: Sequence[Axes] | None = None, *, ncols: int | None = None,
                   where: str = "lower center") -> None:
    """One legend for the figure, outside every panel (it never covers data); duplicates merged."""
    handles = {}  # label -> handle, in the order first met
    for ax in (axes if axes is not None else fig.axes):
        for handle, label in zip(*ax.get_legend_handles_labels()):
            if label not in handles and not label.startswith("_"):
                handles[label] = handle
    if handles:  # without a layout engine (3-D figures, margins set by hand) the caller leaves room for it
        loc = f"outside {where}" if fig.get_layout_engine() is not None else where
        fig.legend(list(handles.values()), list(handles), loc=loc, ncols=ncols or min(len(handles), 4))


def panel_note(ax: Axes, text: str) -> None:
    """A short note above the panel's upper left corner (outside the data); notes accumulate, one per line."""
    before = ax.get_title(loc="left")
    ax.set_title(f"{before}\n{text}" if before else text, loc="left", fontsize=6.5, color="0.3")


def oscillations(y: np.ndarray) -> int:
    """How many times a series crosses its mean: a measure of how dense its line is on a panel."""
    y = np.asarray(y, dtype=float)
    y = y[np.isfinite(y)]
    if y.size < 3:
        return 0
    sign = np.sign(y - y.mean())
    return int(np.count_nonzero(sign[1:] * sign[:-1] < 0) // 2)


def trace(ax: Axes, t: np.ndarray, y: np.ndarray, *, label: str | None = None, **style: Any) -> bool:
    """A line, or the min–max envelope of the series over ``ENVELOPE_BINS`` bins when the line would
    be a solid band (more than ``MAX_OSCILLATIONS`` oscillations); True when the envelope was drawn.
    Each bin spans about two oscillations, so the band is the envelope, not the oscillation itself."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    n = oscillations(y)
    bins = min(ENVELOPE_BINS, n // 2)
    if n <= MAX_OSCILLATIONS or len(t) < 4 * bins:
        ax.plot(t, y, label=label, **style)
        return False
    edges = np.linspace(0, len(t), bins + 1).astype(int)  # bins of at least 4 samples
    low, high = np.fmin.reduceat(y, edges[:-1]), np.fmax.reduceat(y, edges[:-1])  # NaN only where all are
    centres = np.add.reduceat(t, edges[:-1]) / np.diff(edges)
    color = style.get("color")
    band = ax.fill_between(centres, low, high, alpha=0.45, lw=0, color=color, label=label)
    ax.plot(centres, low, lw=0.4, color=band.get_facecolor()[0][:3])
    ax.plot(centres, high, lw=0.4, color=band.get_facecolor()[0][:3])
    return True


def fast_window(t: np.ndarray, series: Sequence[np.ndarray], periods: float = 6.0) -> slice:
    """The leading part of the time span that shows about ``periods`` oscillations of the fastest series;
    the whole span (``slice(None)``) when no series is dense (at most ``MAX_OSCILLATIONS / 2`` oscillations)."""
    n = max((oscillations(y) for y in series), default=0)
    if n <= MAX_OSCILLATIONS / 2:
        return slice(None)
    end = t[0] + (t[-1] - t[0]) * periods / n
    stop = int(np.searchsorted(t, end, side="right"))
    return slice(0, max(stop, 3))


def unit_sphere(ax: Any, n: int = 25) -> None:
    """A light wireframe of the unit sphere on a 3-D axes."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, n), np.linspace(0, np.pi, (n + 1) // 2))
    ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", lw=0.3)
    ax.set_box_aspect((1, 1, 1))
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(matplotlib.ticker.FixedLocator([-1, 0, 1]))
        axis.label.set_size(7)
    ax.tick_params(labelsize=6, pad=0)


def log_positive(values: np.ndarray) -> np.ndarray:
    """Values for a log axis: zeros and negatives become NaN (gaps, never a fake floor)."""
    values = np.asarray(values, dtype=float)
    return np.where(values > 0, values, np.nan)
