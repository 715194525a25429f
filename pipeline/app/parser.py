"""The command line's grammar: which subcommand a command line names, and one argparse parser per subcommand.

``gyrolab run`` (the default: ``gyrolab``, ``gyrolab -m ...``, ``gyrolab experiment=x``) is Hydra's own app: its
parser is Hydra's (``get_args_parser``) with gyrolab's ``--scheduler`` and ``--version``, and its namespace goes to
Hydra as it is (``gyrolab.compat.run_hydra``). The old spellings (``--batch``, ``--plot``, ...) name the same
subcommands as the words (``gyrolab batch ...``), anywhere on the line; options go in any position.
"""

from __future__ import annotations

import argparse
import difflib
from collections.abc import Sequence

from gyrolab.compat import get_args_parser
from gyrolab.errors import ConfigError, shorten

#: subcommand -> one line saying what it does (the order of ``gyrolab --help``)
COMMANDS = {
    "run": "run one scene or experiment, or a sweep with -m (the default subcommand)",
    "batch": "run a grid of scenes in one process, into one sweep.nc (resumable)",
    "plot": "redraw the figures of the datasets under a path (or animate a run with --animate)",
    "reproduce": "rerun a dataset's stored config and compare bit for bit (exit 0: identical)",
    "aggregate": "(re)write SWEEP_DIR/sweep.nc from the jobs already there",
    "new-force": "write a force plugin package to start from",
    "completion": "print the shell completion script for bash or zsh",
}

#: the old option spellings of the subcommands, kept as aliases
ALIASES = {"--batch": "batch", "--plot": "plot", "--reproduce": "reproduce", "--aggregate": "aggregate",
           "--new-force": "new-force"}

#: where logs and results go, said in every --help
LOGGING_CONVENTION = ("Log lines and progress go to stderr; results (the paths written, reports) go to stdout, "
                      "so `gyrolab ... > written.txt` keeps a list of the files.")


def parse_command_line(argv: Sequence[str]) -> tuple[str, argparse.Namespace]:
    """(the subcommand ``argv`` names, its options parsed by that subcommand's parser, in any order); ``--help``
    of a subcommand other than ``run`` prints and exits 0 (``run``'s is Hydra's, from its config)."""
    parsers = {"run": run_parser(), **build_parsers()}
    command, rest = split_command(argv, value_options(parsers))
    return command, parsers[command].parse_intermixed_args(rest)


def value_options(parsers: dict[str, argparse.ArgumentParser]) -> set[str]:
    """The options of any subcommand that take a value (the next word is then a value, not a subcommand)."""
    return {option for parser in parsers.values() for action in parser._actions if action.nargs != 0
            for option in action.option_strings}


def split_command(argv: Sequence[str], value_options: set[str]) -> tuple[str, list[str]]:
    """(the subcommand ``argv`` names, the rest of ``argv``): a word before the first override, or an old
    ``--batch``-style spelling anywhere (``--plot=PATH`` keeps PATH), else ``run``; ``value_options`` take a value."""
    argv = list(argv)
    takes_value = False
    bare_words_allowed = True
    for i, arg in enumerate(argv):
        if takes_value:
            takes_value = False
            continue
        name, has_value, value = arg.partition("=")
        if name in ALIASES:
            return ALIASES[name], argv[:i] + ([value] if has_value else []) + argv[i + 1:]
        if arg in value_options:
            takes_value = True
        elif arg.startswith("-"):
            continue
        elif bare_words_allowed and arg in COMMANDS:
            return arg, argv[:i] + argv[i + 1:]
        elif bare_words_allowed and "=" not in arg and not arg.startswith(("~", "+")):
            close = difflib.get_close_matches(arg, list(COMMANDS), n=1)
            hint = f"did you mean gyrolab {close[0]}? " if close else ""
            raise ConfigError(f"unknown subcommand {shorten(repr(arg))} (an override is key=value); {hint}valid "
                              f"choices: {', '.join(COMMANDS)}")
        else:
            bare_words_allowed = False  # an override (or a path): a later word is a value, not a subcommand
    return "run", argv


class _Parser(argparse.ArgumentParser):
    """argparse with gyrolab's one-sentence errors (``gyrolab: error: ...``, a ConfigError's exit code)."""

    def error(self, message: str):  # noqa: ANN201 - argparse's signature
        raise ConfigError(f"{message}; see {self.prog} --help")


def _sentence(text: str) -> str:
    return text[:1].upper() + text[1:]


def _source_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("where configs come from (as for gyrolab run)")
    group.add_argument("--config-dir", "-cd", metavar="DIR",
                       help="a folder of your own configs (conf/ layout), searched after gyrolab's: "
                            "give yours new names (a file named like one of gyrolab's is not read; a warning says so)")
    group.add_argument("--config-path", "-cp", metavar="DIR",
                       help="a folder that replaces gyrolab's primary config folder")
    group.add_argument("--config-name", "-cn", metavar="NAME", help="the primary config (default: config)")


def run_parser() -> argparse.ArgumentParser:
    """``gyrolab run``'s parser: Hydra's own (``--help`` is Hydra's app help, from the config), with gyrolab's
    ``--version`` for Hydra's and ``--scheduler``."""
    parser = _Parser(prog="gyrolab", parents=[get_args_parser()], add_help=False, conflict_handler="resolve",
                     description=_sentence(COMMANDS["run"]))
    parser.add_argument("--version", "-V", action="store_true", help="print gyrolab's version and exit")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="where an experiment's batch runs: process, local or tcp://HOST:PORT (as gyrolab batch)")
    return parser


def _subparser(name: str, details: str, epilog: str | None = LOGGING_CONVENTION) -> _Parser:
    return _Parser(prog=f"gyrolab {name}", formatter_class=argparse.RawDescriptionHelpFormatter, epilog=epilog,
                   description=_sentence(COMMANDS[name]) + details)


def build_parsers() -> dict[str, argparse.ArgumentParser]:
    """One parser per subcommand except ``run`` (``run_parser``); each one's ``--help`` lists its options."""
    batch = _subparser("batch", ".\nThe sweep comes from the same place as for -m: the command "
                       "line (initial.r0=1,2,3 body.a=range(1,2,0.25)) and hydra.sweeper.params of the config or an "
                       "experiment. Only body, initial and force parameters may vary (docs/batch.md).\n"
                       "Example: gyrolab batch initial.r0=10,20,40 time.end=20 hydra.sweep.dir=grid")
    batch.add_argument("overrides", nargs="*", metavar="KEY=VALUE", help="overrides and sweeps (a=1,2 "
                       "b=range(0,1,0.1)); hydra.sweep.dir=DIR names the output folder")
    batch.add_argument("--scheduler", metavar="ADDRESS",
                       help="where chunks run: process (this process, the default), local (a local Dask cluster) "
                            "or a Dask scheduler's address tcp://HOST:PORT (the same as batch.scheduler=...)")
    batch.add_argument("-m", "--multirun", action="store_true",
                       help="accepted for symmetry with gyrolab run -m: a batch is always a sweep")
    _source_options(batch)

    plot = _subparser("plot", "; nothing is integrated.\n"
                      "Examples: gyrolab plot outputs/ output.figure_formats=[png,pdf] output.dpi=300\n"
                      "          gyrolab plot --animate outputs/2026-01-01/12-00-00/run.nc")
    plot.add_argument("arguments", nargs="*", metavar="PATH | output.KEY=VALUE",
                      help="a dataset or a folder searched for datasets, and output.* settings only: "
                           "output.figure_formats=[png,pdf,svg], output.dpi=300")
    animation = plot.add_argument_group("animation (a run.nc: the body turning about the fixed point)")
    animation.add_argument("--animate", metavar="RUN", help="animate the run stored at RUN (run.nc or its folder)")
    animation.add_argument("--format", choices=("gif", "mp4"), help="gif (Pillow, the default) or mp4 (ffmpeg)")
    animation.add_argument("--frames", type=int, metavar="N", help="number of frames (output times shown)")
    animation.add_argument("--fps", type=float, metavar="F", help="frames per second")
    animation.add_argument("-o", "--output", metavar="FILE",
                           help="the file to write (default: RUN's folder/figures/animation.FORMAT)")
    _source_options(plot)

    reproduce = _subparser("reproduce", ".\nExit status 0: identical; 1: it differs (the report on stdout says where).")
    reproduce.add_argument("paths", nargs="*", metavar="PATH", help="a run.nc, an experiment's dataset, or a "
                           "sweep.nc (of gyrolab batch or gyrolab -m) written by gyrolab")
    reproduce.add_argument("--points", metavar="LIST", help="a sweep.nc: rerun only these points (jobs), by number "
                           "(0,5,10-19; point n is grid position numpy.unravel_index(n, shape)); default: all")

    aggregate = _subparser("aggregate", " (after an interrupted multirun, or a full disk).")
    aggregate.add_argument("paths", nargs="*", metavar="SWEEP_DIR", help="the folder of a multirun (hydra.sweep.dir)")

    new_force = _subparser("new-force", " (a package with its tests, docs/plugins.md).")
    new_force.add_argument("names", nargs="*", metavar="NAME", help="the force's name (a Python identifier)")

    completion = _subparser("completion", ".\nbash: eval \"$(gyrolab completion bash)\" (in ~/.bashrc); zsh: eval "
                            "\"$(gyrolab completion zsh)\" (in ~/.zshrc).\nIt completes subcommands, options, config "
                            "groups, their options and config keys; run it again after installing a plugin.",
                            epilog=None)
    completion.add_argument("shell", choices=("bash", "zsh"), help="the shell")
    _source_options(completion)
    return {"batch": batch, "plot": plot, "reproduce": reproduce, "aggregate": aggregate, "new-force": new_force,
            "completion": completion}


def one_path(command: str, paths: Sequence[str], usage: str) -> str:
    """The single path a subcommand takes, or one sentence."""
    if len(paths) != 1:
        raise ConfigError(f"{command} takes exactly one path (got {len(paths)}: "
                          f"{shorten(' '.join(paths)) or 'none'}); usage: gyrolab {usage}")
    return paths[0]
