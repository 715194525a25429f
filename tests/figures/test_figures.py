"""Figures are functions of datasets: `gyrolab --plot` redraws them, in the configured formats and dpi,
with the dataset's provenance in the file metadata; the defects of the old figures stay fixed."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from PIL import Image

from gyrolab.app import preflight, run_subcommand
from gyrolab.app.parser import parse_command_line
from gyrolab.engine.config import compose_config
from gyrolab.engine.scene import Scene
from gyrolab.errors import ConfigError
from gyrolab.figures.options import figure_options
from gyrolab.figures.redraw import draw_figures
from gyrolab.figures.style import SINGLE
from gyrolab.output.dataset import write_dataset

TINY = ["time.end=2", "time.n_output=41"]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A run directory as `gyrolab` leaves it: run.nc and figures/ drawn at the run."""
    directory = tmp_path_factory.mktemp("run")
    cfg = compose_config(TINY)
    ds = Scene.from_config(cfg).run()
    write_dataset(ds, directory / "run.nc")
    draw_figures("run.nc", ds, directory, cfg.output)
    return directory


def _names(directory):
    return sorted(p.name for p in (directory / "figures").iterdir())


def test_plot_redraws_the_same_figures_in_the_formats_and_dpi_asked_with_provenance(run_dir):
    drawn = _names(run_dir)
    assert drawn == ["body_axis_sphere.png", "euler_angles.png", "invariant_drift.png", "state.png"]
    for path in (run_dir / "figures").iterdir():
        path.unlink()
    assert run_subcommand(*parse_command_line(["--plot", str(run_dir), "output.figure_formats=[png,pdf,svg]",
                                                "output.dpi=50"])) == 0
    figures = run_dir / "figures"
    stems = {p.removesuffix(".png") for p in drawn}
    for fmt in ("png", "pdf", "svg"):
        assert {p.stem for p in figures.glob(f"*.{fmt}")} == stems
    assert len(list(figures.iterdir())) == 3 * len(stems)
    ds = xr.load_dataset(run_dir / "run.nc")
    with Image.open(figures / "invariant_drift.png") as png:
        # a single-column figure: 3.5 in wide at 50 dpi (the style's width, not matplotlib's default)
        assert png.size[0] == round(SINGLE * 50)
        assert png.text["gyrolab:git_commit"] == ds.attrs["git_commit"]
        assert png.text["gyrolab:config"] == ds.attrs["config"]
    pdf = (figures / "state.pdf").read_bytes()
    assert f"git_commit={ds.attrs['git_commit']}".encode() in pdf
    svg = (figures / "state.svg").read_text()
    assert ds.attrs["git_commit"] in svg and "<dc:description>" in svg


@pytest.mark.parametrize("output, words", [
    ({"figure_formats": ["png", "jpg"]}, "'jpg'"),
    ({"figure_formats": []}, "empty"),
    ({"dpi": 0}, "output.dpi=0"),
    ({"dpi": "high"}, "output.dpi='high'"),
])
def test_bad_figure_settings_are_one_sentence(output, words):
    with pytest.raises(ConfigError, match=words) as error:
        figure_options(output)
    assert "\n" not in str(error.value)


def test_bad_format_is_refused_before_anything_runs(tmp_path):
    with pytest.raises(ConfigError, match="valid: pdf, png, svg"):
        preflight(parse_command_line(["output.figure_formats=[png,eps]", f"hydra.run.dir={tmp_path / 'out'}"])[1])
    assert not (tmp_path / "out").exists()


def test_plot_of_a_path_without_datasets_is_one_sentence(tmp_path):
    with pytest.raises(ConfigError, match="no gyrolab dataset"):
        run_subcommand(*parse_command_line(["--plot", str(tmp_path)]))


def test_body_axis_sphere_draws_z_along_the_weight(run_dir):
    from gyrolab.figures.run import draw_body_axis

    fig = draw_body_axis(xr.load_dataset(run_dir / "run.nc"))
    ax = fig.axes[0]
    assert ax.zaxis_inverted() and "weight" in ax.get_zlabel()


def test_initial_upright_stands_and_hanging_hangs():
    # Z points along the weight: with the centre of mass on +z, θ0 = π is the sleeping (upright) top,
    # an equilibrium that a Lagrange top keeps exactly (r0² = 25 > 4a = 3.2: stable); θ0 = 0 hangs.
    for initial, theta in (("upright", np.pi), ("hanging", 0.0)):
        ds = Scene.from_config(compose_config(["body=lagrange_top", f"initial={initial}", "time.end=2",
                                               "time.n_output=21"])).run()
        np.testing.assert_allclose(ds.theta.values, theta, atol=1e-12)
        np.testing.assert_allclose(ds.gamma.values[:, 2], np.cos(theta), atol=1e-12)


def _sweep(values):
    return xr.Dataset({"integrator_nfev": (("integrator", "r0"), values, {"units": "1"})},
                      coords={"integrator": ["rk4", "taylor"], "r0": ("r0", [2.0, 5.0, 10.0])},
                      attrs={"sweep_dims": "integrator r0", "n_finished": 6, "n_failed": 0})


def test_sweep_points_are_markers_and_evaluation_kinds_are_named():
    from gyrolab.figures.sweep import draw_cost

    fig = draw_cost(_sweep(np.array([[100.0, 200, 400], [10, 20, 40]])))
    lines = [line for ax in fig.axes for line in ax.get_lines() if len(line.get_xdata()) == 3]
    assert lines and all(line.get_linestyle() == "None" for line in lines)  # discrete values: never joined
    assert all(ax.get_ylabel() for ax in fig.axes)
    assert "taylor: Taylor series evaluations" in fig.axes[0].get_title(loc="left")


def _work_precision():
    # dop853 and dop853_numba take the same steps at equal tolerances (identical points)
    methods = ["dop853"] * 2 + ["dop853_numba"] * 3 + ["taylor"] * 2 + ["auto"]
    nfev = [1e4, 2e4, 1e4, 2e4, 4e4, 500, 800, 900]
    error = [1e-6, 1e-8, 1e-6, 1e-8, 1e-10, 1e-9, 0.0, 1e-9]
    return xr.Dataset({"method": ("run", methods), "nfev": ("run", nfev), "error": ("run", error),
                       "wall_time": ("run", np.linspace(0.1, 0.8, 8))})


def test_work_precision_counts_only_right_hand_side_calls_and_hides_no_method():
    from gyrolab.figures.work_precision import draw_error_vs_nfev, draw_error_vs_wall_time

    ds = _work_precision()
    fig = draw_error_vs_nfev(ds)
    labels = fig.legends[0].get_texts()
    assert [t.get_text() for t in labels] == ["dop853", "dop853_numba (points coincide with dop853)"]
    assert "not shown: taylor, auto" in fig.axes[0].get_title(loc="left")
    fig = draw_error_vs_wall_time(ds)
    assert {t.get_text().split(" ")[0] for t in fig.legends[0].get_texts()} == {"dop853", "dop853_numba", "taylor",
                                                                              "auto"}
    note = fig.axes[0].get_title(loc="left")
    assert "pilot runs included" in note and "exactly 0 (not drawn): taylor" in note


def test_exact_zeros_are_gaps_not_a_floor(tmp_path):
    """Ismail's Tables 1 and 2 agree exactly at t = 0: that zero is marked on the axis edge, never drawn at a
    made-up floor value."""
    from omegaconf import OmegaConf

    from gyrolab.experiments import ismail2021_tables
    from gyrolab.figures.tables import draw_tables

    ismail2021_tables.run(OmegaConf.create({"output": {"figures": False}}), tmp_path)
    fig = draw_tables(xr.load_dataset(tmp_path / "ismail2021_tables.nc"))
    right = fig.axes[1]
    drawn = np.concatenate([np.asarray(line.get_ydata(), dtype=float) for line in right.get_lines()
                            if line.get_transform() == right.transData])
    finite = drawn[np.isfinite(drawn)]
    assert finite.min() > 1e-12 and np.isnan(drawn).any()
    assert any("exactly 0" in t.get_text() for t in fig.legends[0].get_texts())


def _drift_sweep():
    """A sweep over r0 × integrator with the heavy body's four invariants (nondimensional: units of C c for Iω·γ)."""
    r0, integrators = [2.0, 5.0, 10.0], ["rk4", "dop853"]
    drift = np.array([[1e-10, 1e-7, 1e-5], [1e-9, 1e-9, 1e-9]])
    variables = {f"{name}_max_abs_drift": (("integrator", "r0"), drift, {"units": "1"})
                 for name in ("energy", "area_integral", "gamma_norm", "frame_error")}
    return xr.Dataset(variables, coords={"integrator": integrators, "r0": ("r0", r0, {"override_key": "initial.r0"})},
                      attrs={"sweep_dims": "integrator r0", "n_finished": 6, "n_failed": 0, "rate_unit": "c",
                             "energy_unit": "C c2", "time_unit": "1/c"})


def _overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_sweep_labels_stay_inside_their_panels_and_clear_of_the_title():
    """The area-integral y label overran its panel and the figure title: every y label now fits the height of its
    panel, touches no other panel and no title; the quantity names the panel."""
    from gyrolab.figures.sweep import draw_invariant_drift

    fig = draw_invariant_drift(_drift_sweep())
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    axes = [ax for ax in fig.axes if ax.get_visible()]
    title = fig._suptitle.get_window_extent(renderer)
    titles = {ax.get_title(loc="left") for ax in axes}
    assert {"energy E", "area integral Iω·γ", "norm |γ|", "frame orthonormality error"} <= titles
    for ax in axes:
        ylabel = ax.yaxis.label.get_window_extent(renderer)
        box = ax.get_window_extent(renderer)
        assert ylabel.height <= box.height, f"{ax.get_ylabel()!r} is taller than its panel"
        assert not _overlap(ylabel, title), f"{ax.get_ylabel()!r} runs into the title"
        for other in axes:
            if other is not ax:
                assert not _overlap(ylabel, other.get_window_extent(renderer)), f"{ax.get_ylabel()!r} runs into a panel"
                assert not _overlap(ylabel, other._left_title.get_window_extent(renderer)), \
                    f"{ax.get_ylabel()!r} runs into another panel's title"
    area = next(ax for ax in axes if ax.get_title(loc="left") == "area integral Iω·γ")
    assert "units of C c" in area.get_ylabel()


def _orbit_family(crowded: bool):
    """Two families; crowded: the second turns back (a fold) and has a fold, a branch point and a period doubling
    within 0.01 of r0/c, two of them at the same orbit, as near a homoclinic end; else no fold, events far apart."""
    r0 = [100.0, 10.0, 2.0, 1.0, 0.5, 100.0, 10.0, 3.0, 1.7, 1.75, 1.72, 1.74]
    family = ["slow"] * 5 + ["turning"] * 7
    n = len(r0)
    amplitude = [0.01, 0.05, 0.2, 0.5, 0.9, 0.01, 0.05, 0.3, 0.8, 1.2, 1.5, 1.7]
    events = {"event_family": ("event", ["slow", "turning", "turning", "turning", "turning"]),
              "event_kind": ("event", ["branch point", "fold", "fold", "period doubling", "branch point"] if crowded
                             else ["branch point", "period doubling", "branch point", "period doubling", "branch point"]),
              "event_r0_over_c": ("event", [1.5, 1.69, 1.745, 1.745, 1.735] if crowded else [1.5, 1.69, 5, 6, 7]),
              "event_point": ("event", [3, 9, 10, 10, 11] if crowded else [3, 9, 7, 7, 7])}
    return xr.Dataset({"family": ("point", family), "family_label": ("point", family),
                       "r0_over_c": ("point", r0), "period": ("point", np.linspace(0.1, 20, n)),
                       "amplitude": ("point", amplitude), "stable": ("point", [1, 0] * (n // 2)), **events})


def test_orbit_family_events_are_legend_markers_and_crowded_ones_get_an_inset():
    from gyrolab.figures.orbit_family import draw_orbit_family

    fig = draw_orbit_family(_orbit_family(crowded=True))
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert not {"F", "BP", "PD"} & set(texts)                      # no overprinting text labels
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    for kind in ("fold", "branch point", "period doubling"):
        assert f"{kind} (located)" in legend                        # every marker is explained
    assert len(fig.axes[1].child_axes) == 1                         # an inset of the amplitude panel
    zoom = fig.axes[1].child_axes[0]
    low, high = zoom.get_xlim()
    assert zoom.get_xscale() == "linear" and low <= 1.69 and high >= 1.75 and high - low < 0.2
    markers = [line for line in zoom.get_lines() if line.get_marker() in ("s", "D", "v") and len(line.get_xdata()) == 1]
    assert len(markers) == 4                                        # the turning family's four events, each once
    sizes = {line.get_marker(): line.get_markersize() for line in markers}
    assert sizes["s"] > sizes["D"] > sizes["v"]                     # nested: co-located events stay visible

    fig = draw_orbit_family(_orbit_family(crowded=False))
    assert not fig.axes[1].child_axes                               # no family turns back: no inset
    drawn = [line for ax in fig.axes for line in ax.get_lines() if line.get_marker() in ("D", "v")
             and len(line.get_xdata()) == 1]
    assert len(drawn) == 2 * 5                                      # every event in the period and amplitude panels


def _regime(norm):
    t = np.linspace(0, 1, 11)
    wave = np.stack([np.sin(t), np.cos(t), 20 + 0 * t], axis=1)
    gamma = np.stack([np.cos(t), 0 * t, 0.07 + 0 * t], axis=1)
    data = {f"omega_{s}": (("time", "axis"), wave, {"units": "1"}) for s in ("analytic", "full", "orbit")}
    data.update({f"gamma_{s}": (("time", "axis"), gamma, {"units": "1"}) for s in ("analytic", "full", "orbit")})
    attrs = {"regime": "small_parameter", "rate_unit": "c"}
    if norm is not None:
        attrs["analytic_gamma0_norm"] = norm
    return xr.Dataset(data, coords={"time": ("time", t, {"units": "1", "long_name": "time [1/c]"})}, attrs=attrs)


@pytest.mark.parametrize("norm, stated, outside", [(1.0106, "0.011", True), (1.0000031, "3.1e-06", False),
                                                   (1.0, None, False), (None, None, False)])
def test_regime_figure_states_the_normalised_start(norm, stated, outside):
    from gyrolab.figures.regime import draw_regime_comparison

    fig = draw_regime_comparison(_regime(norm))
    full = [t.get_text() for t in fig.legends[0].get_texts() if t.get_text().startswith("full model")][0]
    if stated is None:
        assert "normalised" not in full
    else:
        assert "γ(0) normalised" in full and stated in full
    notes = " ".join(ax.get_title(loc="left") for ax in fig.axes)
    assert ("outside its domain" in notes) == outside


@pytest.mark.parametrize("key, units, expected", [
    ("initial.r0", "1", "initial.r0 (units of c)"),       # a nondimensional spin is in units of c
    ("initial.r0", "rad s-1", "initial.r0 (rad/s)"),
    ("initial.theta0", "rad", "initial.theta0 (rad)"),
    ("body.a", "1", "body.a"),                            # a ratio: no unit
    ("initial.r0", None, "initial.r0"),                   # a sweep.nc written before swept keys had units
])
def test_sweep_x_label_gives_the_swept_keys_unit(key, units, expected):
    from gyrolab.figures.sweep import draw_invariant_drift

    ds = _drift_sweep()
    ds["r0"].attrs.update({"override_key": key, **({"units": units} if units else {})})
    assert draw_invariant_drift(ds).axes[0].get_xlabel() == expected


def test_a_figure_laid_out_once_has_the_pixels_of_matplotlibs_own_save(tmp_path):
    """save() lays a constrained figure out once at the PNG's dpi (one draw, not two): the pixels are matplotlib's."""
    import matplotlib.pyplot as plt

    from gyrolab.figures.save import save
    from gyrolab.figures.style import STYLE
    from gyrolab.figures.sweep import draw_invariant_drift

    theirs = draw_invariant_drift(_drift_sweep())
    with plt.style.context(STYLE):
        theirs.savefig(tmp_path / "theirs.png", dpi=120)
    ours = draw_invariant_drift(_drift_sweep())
    engine = ours.get_layout_engine()
    assert engine is not None
    save(ours, tmp_path / "ours", ("png",), 120)
    assert ours.get_layout_engine() is engine  # left as it was
    plt.close("all")
    with Image.open(tmp_path / "theirs.png") as theirs, Image.open(tmp_path / "ours.png") as ours:
        assert np.array_equal(np.asarray(theirs), np.asarray(ours))


def _drawn_texts(fig):
    """Every text a figure draws (tick labels of ticks in view only: matplotlib keeps others, undrawn)."""
    texts = [fig._suptitle, *fig.texts, *(text for legend in fig.legends for text in legend.get_texts())]
    for ax in fig.axes:
        texts += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label, ax.xaxis.offsetText,
                  ax.yaxis.offsetText, *(ax.get_legend().get_texts() if ax.get_legend() else [])]
        for axis in (ax.xaxis, ax.yaxis):
            low, high = sorted(axis.get_view_interval())
            texts += [tick.label1 for tick in axis.get_major_ticks() if low <= tick.get_loc() <= high]
    return [text for text in texts if text is not None and text.get_visible() and text.get_text()]


@pytest.mark.parametrize("overrides", [TINY, ["experiment=gyrostat", *TINY], ["body=si_gyroscope", *TINY], ["initial=hanging", *TINY]])
def test_run_figures_laid_out_by_hand_keep_every_text_inside_the_figure_and_off_other_panels(overrides, tmp_path):
    """The run's grids of panels get fixed margins measured from their text (style.fit), not a layout engine: no text
    is clipped by the figure's edge or runs into another panel, at the dpi of the PNG, and saving leaves no engine."""
    from gyrolab.figures.run import draw_euler_angles, draw_invariants, draw_state
    from gyrolab.figures.save import save

    ds = Scene.from_config(compose_config(overrides)).run()
    for draw in (draw_state, draw_invariants, draw_euler_angles):
        fig = draw(ds)
        save(fig, tmp_path / draw.__name__, ("png", "pdf"), 200)
        assert fig.get_layout_engine() is None
        fig.set_dpi(200)
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        edge = fig.bbox
        panels = [ax.get_window_extent(renderer) for ax in fig.axes]
        texts = _drawn_texts(fig)
        assert len(texts) > 10
        for text in texts:
            box = text.get_window_extent(renderer)
            assert edge.x0 <= box.x0 and box.x1 <= edge.x1 + 1 and edge.y0 <= box.y0 and box.y1 <= edge.y1 + 1, \
                f"{draw.__name__}: {text.get_text()!r} is clipped by the figure's edge"
        for ax, panel in zip(fig.axes, panels):
            for label in (ax.xaxis.label, ax.yaxis.label, *ax.get_xticklabels(), *ax.get_yticklabels()):
                if label.get_visible() and label.get_text():
                    box = label.get_window_extent(renderer)
                    assert not any(_overlap(box, other) for other in panels if other is not panel), \
                        f"{draw.__name__}: {label.get_text()!r} runs into another panel"
