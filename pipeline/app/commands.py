"""The subcommands other than ``run``: ``batch``, ``plot``, ``reproduce``, ``aggregate``, ``new-force``, ``completion``.

Each takes its parsed options (``gyrolab.app.parser``) and returns the exit status; bad input is a
GyrolabError (one sentence). Logs go to stderr, results (paths written, reports) to stdout
(``gyrolab.output.written``).
"""

from __future__ import annotations

import argparse
import logging
import sys
from datetime import datetime
from pathlib import Path

from gyrolab.app import _job_overrides, _sweep_status, _sweeper_params, check_writable, parse_overrides
from gyrolab.app.completion import script
from gyrolab.app.parser import one_path
from gyrolab.batch.reproduce import is_batch, reproduce_batch
from gyrolab.batch.scheduler import use_command_line_scheduler
from gyrolab.batch.sweep import failed_points, run_batch_sweep
from gyrolab.engine.budget import check_sweep_size, check_tolerances
from gyrolab.engine.config import check_scene_config, compose_config
from gyrolab.engine.safety import check_config, check_output_dir
from gyrolab.errors import ConfigError, shorten
from gyrolab.experiments import BATCH_COMMAND, refuse_unread, reproduce_task, task_of
from gyrolab.figures.options import figure_options
from gyrolab.figures.redraw import redraw
from gyrolab.output.trust import check_kernel_cache, check_tree
from gyrolab.output.written import announce_written
from gyrolab.scaffold import new_force_package
from gyrolab.sweep.aggregate import aggregate_sweep, log_summary
from gyrolab.sweep.reproduce import checked_config, is_multirun, load_run, report, reproduce_sweep
from gyrolab.sweep.reproduce import reproduce as rerun

log = logging.getLogger("gyrolab")

LOG_FORMAT = "[%(asctime)s][%(name)s][%(levelname)s] - %(message)s"


def log_to_stderr() -> None:
    """The log format of a Hydra run, on stderr (the convention: logs to stderr, results to stdout)."""
    logging.basicConfig(level=logging.INFO, format=LOG_FORMAT, stream=sys.stderr)


def batch(args: argparse.Namespace) -> int:
    """``gyrolab batch KEY=V1,V2 ... [hydra.sweep.dir=DIR] [--scheduler ADDRESS]``: the grid in one batch, one
    sweep.nc (resumable). The sweep is the command line's plus the config's ``hydra.sweeper.params``, as for -m."""
    overrides = list(args.overrides)
    # the command line's own route to a Dask scheduler (issue 23: trusted only here and in the environment);
    # None when not given, so no value is left from an earlier command
    use_command_line_scheduler(args.scheduler)
    now = datetime.now()
    out_dir = Path(f"outputs/batch/{now:%Y-%m-%d}/{now:%H-%M-%S}")
    scene_overrides = []
    for override in overrides:
        if override.startswith("hydra.sweep.dir="):
            out_dir = Path(override.split("=", 1)[1])
        elif override.startswith("hydra."):
            raise ConfigError(f"{shorten(override)!r}: a batch sweep runs in one process; of Hydra's settings it "
                              "takes hydra.sweep.dir only")
        else:
            scene_overrides.append(override)
    parsed = parse_overrides(scene_overrides)
    refuse_unread(BATCH_COMMAND, scene_overrides)  # output.error_estimate: a batch measures no error
    check_sweep_size(parsed)  # before anything expands a range(0,1e12,1)
    check_output_dir(str(out_dir), "hydra.sweep.dir")
    first_overrides = _job_overrides(parsed, {})
    with_hydra = compose_config(first_overrides, return_hydra_config=True)
    given = {o.key_or_group for o in parsed}
    # the sweep a config declares (hydra.sweeper.params), unless the command line sets the same key, as Hydra does
    declared = [o for o in _sweeper_params(with_hydra) if o.key_or_group not in given]
    scene_overrides += [o.input_line for o in declared]
    if declared:
        check_sweep_size([*parsed, *declared])  # the config's sweep counts too
    first = compose_config(first_overrides)
    check_config(first)
    # the checks of the whole batch; each point's scene is validated by the batch's plan (an invalid point,
    # the first included, is a failed entry, not a refused batch)
    plain = check_scene_config(first)
    figure_options(plain.get("output"))
    check_tolerances(plain)
    check_tree(out_dir, sweep=True)
    check_kernel_cache()
    check_writable(out_dir)
    log_to_stderr()
    if declared:
        log.info("batch: the sweep declared in hydra.sweeper.params: %s", " ".join(o.input_line for o in declared))
    path = run_batch_sweep(scene_overrides, out_dir)
    announce_written(path)
    failed = failed_points(path)
    if failed:   # as gyrolab -m exits 1 when a job failed
        print(f"gyrolab: {failed}", file=sys.stderr)
    return 1 if failed else 0


def plot(args: argparse.Namespace) -> int:
    """``gyrolab plot PATH [output.figure_formats=[png,pdf]] [output.dpi=300]``: redraw every figure of the datasets
    under PATH (nothing is integrated); ``--animate RUN`` animates a run instead (``gyrolab.figures.animation``)."""
    paths = [a for a in args.arguments if "=" not in a]
    overrides = [a for a in args.arguments if "=" in a]
    foreign = [o for o in overrides if not o.startswith("output.")]
    if foreign:
        raise ConfigError(f"plot {shorten(foreign[0])!r}: a redraw takes output.* settings only (figure_formats, dpi)")
    if args.animate is not None:
        if paths:
            raise ConfigError(f"plot --animate takes the run to animate as its value; drop "
                              f"{shorten(' '.join(paths))!r} or redraw it with a separate gyrolab plot PATH")
        from gyrolab.figures.animation import animate  # matplotlib's writers only when an animation is asked for

        options = {"output": args.output, "fmt": args.format, "frames": args.frames, "fps": args.fps}
        log_to_stderr()
        announce_written(animate(args.animate, **{k: v for k, v in options.items() if v is not None}))
        return 0
    animation_options = [name for name in ("format", "frames", "fps", "output") if getattr(args, name) is not None]
    if animation_options:
        raise ConfigError(f"plot --{animation_options[0]} is an option of --animate; usage: gyrolab plot "
                          f"--animate RUN --{animation_options[0]} ...")
    path = one_path("plot", paths, "plot PATH [output.figure_formats=[png,pdf]] [output.dpi=300]")
    log_to_stderr()
    formats, dpi = figure_options(compose_config(overrides).output)
    for written in redraw(Path(path), formats, dpi):
        announce_written(written)
    return 0


def reproduce(args: argparse.Namespace) -> int:
    """``gyrolab reproduce PATH`` (a run.nc, an experiment's dataset, a sweep.nc of ``gyrolab batch`` or ``-m``, with
    ``--points`` some of its points or jobs): the comparison report on stdout; 0 if identical, else 1."""
    path = Path(one_path("reproduce", args.paths, "reproduce PATH/run.nc"))
    check_kernel_cache()
    log_to_stderr()
    stored = load_run(path, sweeps=True)
    if is_multirun(stored):   # gyrolab -m's sweep.nc: each finished job's run.nc is reproduced
        comparison, head = reproduce_sweep(path, stored, args.points)
        print("\n".join(report(path, comparison, stored, head)))
        return 0 if comparison.identical else 1
    cfg = checked_config(path, stored)
    task = task_of(cfg)
    if args.points is not None and (task != "scene" or not is_batch(stored)):
        raise ConfigError(f"--points chooses points of a sweep.nc, and {path} is "
                          f"{'one run' if task == 'scene' else f'the dataset of task {task}'}; give it without --points")
    if task != "scene":    # an experiment's dataset (regime.nc, stability_map.nc, ...): the experiment runs again
        comparison, head = reproduce_task(path, cfg)
    elif is_batch(stored):
        comparison, head = reproduce_batch(path, stored, args.points)
    else:
        comparison, stored = rerun(path, stored)
        head = None
    print("\n".join(report(path, comparison, stored, head)))
    return 0 if comparison.identical else 1


def aggregate(args: argparse.Namespace) -> int:
    """``gyrolab aggregate SWEEP_DIR``: (re)write SWEEP_DIR/sweep.nc; 0 if every job finished, else 1."""
    path = Path(one_path("aggregate", args.paths, "aggregate SWEEP_DIR"))
    log_to_stderr()
    summary = aggregate_sweep(path)
    log_summary(summary)
    return _sweep_status(summary)


def new_force(args: argparse.Namespace) -> int:
    """``gyrolab new-force NAME``: a force plugin package to start from, with its tests."""
    if len(args.names) != 1:
        raise ConfigError("new-force takes one name; usage: gyrolab new-force NAME")
    root = new_force_package(args.names[0])
    announce_written(f"{root}/")
    print(f"next: pip install -e {root} && python -m pytest {root}/tests")
    return 0


def completion(args: argparse.Namespace) -> int:
    """``gyrolab completion bash|zsh``: the completion script on stdout (eval it in the shell's rc file)."""
    print(script(args.shell))
    return 0


#: subcommand -> what runs it (``run`` is Hydra's app, in gyrolab.app)
RUNNERS = {"batch": batch, "plot": plot, "reproduce": reproduce, "aggregate": aggregate, "new-force": new_force,
           "completion": completion}
