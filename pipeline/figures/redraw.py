"""``gyrolab --plot PATH``: redraw every figure from the datasets under PATH, without integrating anything.

PATH is a run directory (``run.nc``), a regime run, an experiment or sweep directory, or one ``.nc``
file. Each dataset's figures are written to ``figures/`` beside it, with the current style, formats
and dpi. Datasets directly in PATH are always drawn; in a sweep directory the jobs' ``run.nc`` are
redrawn only where the job drew figures in the first place (``output.figures`` in its stored config).
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from pathlib import Path

import xarray as xr

from gyrolab.errors import ConfigError, GyrolabError, shorten
from gyrolab.figures.options import DEFAULT_DPI, DEFAULT_FORMATS, figure_options
from gyrolab.output.dataset import write_dataset
from gyrolab.output.foreign import FOREIGN_ERRORS, load_dataset, not_gyrolabs
from gyrolab.output.trust import check_tree
from gyrolab.output.user_yaml import stored_yaml

#: dataset file name -> the gyrolab.figures module that draws its figures
KINDS = {"run.nc": "run", "sweep.nc": "sweep", "regime.nc": "regime", "regime_validity.nc": "regime_validity",
         "work_precision.nc": "work_precision", "ismail2021_tables.nc": "tables", "precession_cases.nc": "precessions",
         "shaker_omega3.nc": "shaker", "orbit_family.nc": "orbit_family", "stability_map.nc": "stability_map"}

#: a variable every dataset of a kind has, for kinds whose figures would otherwise quietly draw nothing
SIGNATURES = {"run.nc": "time", "sweep.nc": "job_status"}


def draw_dataset(path: Path, formats: Iterable[str] = DEFAULT_FORMATS, dpi: int = DEFAULT_DPI) -> list[Path]:
    """Redraw the figures of one dataset file into ``figures/`` beside it."""
    path = Path(path)
    if path.name not in KINDS:
        raise ConfigError(f"{str(path)!r} is not a dataset gyrolab draws figures from; known: {', '.join(KINDS)}")
    expected = f"a {path.name} that gyrolab wrote"
    ds = load_dataset(path, expected)
    needed = SIGNATURES.get(path.name)
    if needed is not None and needed not in ds.variables:
        raise not_gyrolabs(path, KeyError(needed), expected)
    try:
        return save_kind(path.name, ds, path.parent / "figures", tuple(formats), dpi)
    except GyrolabError:
        raise
    except FOREIGN_ERRORS as error:  # a variable or attribute gyrolab's datasets have is missing
        raise not_gyrolabs(path, error, expected) from None


def save_kind(name: str, ds: xr.Dataset, directory: Path, formats: tuple[str, ...], dpi: int) -> list[Path]:
    """Every figure of dataset kind ``name`` drawn from ``ds``: the module's own ``save_figures`` when it
    has one (figures that depend on the data, parallel drawing), else each of its ``FIGURES``."""
    module = importlib.import_module(f"gyrolab.figures.{KINDS[name]}")
    if hasattr(module, "save_figures"):
        return module.save_figures(ds, directory, formats, dpi)
    from gyrolab.figures.save import save_all  # start-up: matplotlib only when figures are drawn

    return save_all({stem: draw(ds) for stem, draw in module.FIGURES.items()}, directory, ds, formats, dpi)


def _drew_figures(path: Path) -> bool:
    """Whether the run stored at ``path`` drew figures (its stored config's ``output.figures``); ConfigError for a
    stored config that is not what gyrolab stores (``gyrolab.output.user_yaml.stored_yaml``)."""
    try:
        import netCDF4  # start-up: netCDF4 only when a header is read

        with netCDF4.Dataset(path, "r") as nc:  # the header only: no coordinate is read
            config = nc.getncattr("config") if "config" in nc.ncattrs() else ""
    except Exception:  # noqa: BLE001 -- unreadable: leave it alone
        return False
    output = stored_yaml(config, f"the config attribute of {shorten(str(path))}").get("output")
    return bool(output.get("figures", True)) if isinstance(output, dict) else True


def datasets(path: Path) -> list[Path]:
    """The datasets ``gyrolab --plot PATH`` redraws."""
    path = Path(path)
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise ConfigError(f"--plot: {str(path)!r} is neither a directory nor a dataset file")
    found = [path / name for name in KINDS if (path / name).is_file()]
    found += [nested for nested in sorted(path.glob("*/run.nc")) if _drew_figures(nested)]  # a sweep's jobs
    if not found:
        raise ConfigError(f"--plot: no gyrolab dataset in {str(path)!r} (looked for {', '.join(KINDS)}, "
                          "and */run.nc in a sweep directory)")
    return found


def redraw(path: str | Path, formats: Iterable[str] = DEFAULT_FORMATS, dpi: int = DEFAULT_DPI) -> list[Path]:
    """Redraw every figure of the datasets under ``path``; returns the files written."""
    path = Path(path)
    if path.is_dir():  # a job directory that is a link would take its figures outside (a file's: own_dir)
        check_tree(path, sweep=True)
    return [written for dataset in datasets(path) for written in draw_dataset(dataset, formats, dpi)]


def write_and_draw(name: str, ds: xr.Dataset, out_dir: str | Path, output: object | None) -> list[Path]:
    """Write ``ds`` as ``out_dir/name`` and draw its figures (``draw_figures``); returns the dataset's path first."""
    return [write_dataset(ds, Path(out_dir) / name), *draw_figures(name, ds, out_dir, output)]


def draw_figures(name: str, ds: xr.Dataset, out_dir: str | Path, output: object | None) -> list[Path]:
    """The figures of dataset ``name`` (a key of ``KINDS``) drawn from ``ds`` into ``out_dir/figures``, in the
    formats and dpi of the ``output`` config section; none when ``output.figures`` is false."""
    output = output if output is not None else {}
    if not output.get("figures", True):
        return []
    formats, dpi = figure_options(output)
    return save_kind(name, ds, Path(out_dir) / "figures", formats, dpi)
