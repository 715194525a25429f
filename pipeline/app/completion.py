"""Shell completion for bash and zsh: ``eval "$(gyrolab completion bash)"`` (or ``zsh``).

The script carries every word it can offer, computed once when it is generated (so a TAB costs no
Python start-up): the subcommands, each subcommand's options, the config groups with their options
(``integrator=`` then ``integrator=taylor``), the config's keys one level at a time (``time.`` then
``time.end=``) and ``true``/``false`` for boolean keys. ``gyrolab --shell-completion install=bash``
(Hydra's spelling) prints the same script: Hydra's own completion cannot see an installed console script's
app, nor gyrolab's subcommands. Generate the script again after installing a plugin. The options of a config
group in the folder a command line names with ``--config-dir DIR`` (``DIR/experiment/*.yaml``, ...) are read by
the shell when TAB is pressed, so a user's own experiments are offered without generating anything.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from gyrolab.errors import ConfigError

SHELLS = ("bash", "zsh")

HYDRA_GROUPS = ("hydra/launcher", "hydra/sweeper")
#: nodes of gyrolab's ``hydra`` section that are not settings one types (help texts, logging, callbacks)
_HYDRA_NODES_NOT_TYPED = ("help", "job_logging", "hydra_logging", "callbacks")


def hydra_keys() -> list[str]:
    """Hydra's keys worth completing: the settings gyrolab's primary config gives (``hydra.run.dir``,
    ``hydra.sweep.dir``, ``hydra.sweep.subdir``, ``hydra.job.name``) and Hydra's ``hydra.verbose``."""
    from importlib.resources import files

    from omegaconf import OmegaConf

    from gyrolab.engine.config import CONFIG_MODULE

    hydra = OmegaConf.to_container(OmegaConf.load(str(files(CONFIG_MODULE) / "config.yaml")).hydra)
    keys = [f"hydra.{key}" for key, _ in _leaves(hydra) if key.split(".")[0] not in _HYDRA_NODES_NOT_TYPED]
    return [*keys, "hydra.verbose"]


def run_options() -> list[str]:
    """The options of ``gyrolab run``: Hydra's own (its argument parser's), gyrolab's ``-V`` (short for --version)
    and the old spellings of the subcommands."""
    from gyrolab.app.parser import ALIASES
    from gyrolab.compat import get_args_parser

    return [*(s for action in get_args_parser()._actions for s in action.option_strings), "-V", *ALIASES]


#: subcommands whose arguments are paths (the shell's file completion joins in)
PATH_COMMANDS = ("plot", "reproduce", "aggregate")


def config_words() -> list[str]:
    """Every completion of an override: ``group=``, ``group=option``, ``section.``, ``key=``, ``key=true``."""
    from omegaconf import DictConfig, OmegaConf

    from gyrolab.engine.config import (
        SELECTABLE_GROUPS,
        compose_config,
        group_options,
        hydra_for,
        register_plugin_configs,
    )

    words: list[str] = []
    register_plugin_configs()   # the installed plugins' options (force=viscous_drag, ...), from the registry
    with hydra_for():
        for group in (*SELECTABLE_GROUPS, *HYDRA_GROUPS):
            words.append(f"{group}=")
            words += [f"{group}={option}" for option in group_options(group)]
        cfg = compose_config([])
    plain = OmegaConf.to_container(cfg, resolve=False) if isinstance(cfg, DictConfig) else {}
    for key, value in _leaves(plain):
        words += _prefixes(key, SELECTABLE_GROUPS)
        words.append(f"{key}=")
        if isinstance(value, bool):
            words += [f"{key}=true", f"{key}=false"]
    for key in hydra_keys():
        words += [*_prefixes(key, ()), f"{key}="]
    return list(dict.fromkeys(words))


def _leaves(node: object, prefix: str = "") -> Iterator[tuple[str, object]]:
    if isinstance(node, dict) and node:
        for key, value in node.items():
            yield from _leaves(value, f"{prefix}{key}.")
    elif prefix and not prefix.startswith("hydra."):
        yield prefix.rstrip("."), node


def _prefixes(key: str, groups: Sequence[str]) -> list[str]:
    """``a.``, ``a.b.`` for key ``a.b.c``; a group's name is offered as ``group=``, its section as ``group.``
    only once the dot is typed (so ``integ<TAB>`` is ``integrator=``)."""
    parts = key.split(".")
    return [".".join(parts[:n]) + "." for n in range(1, len(parts)) if n > 1 or parts[0] not in groups]


def option_words() -> dict[str, list[str]]:
    """Each subcommand's options (``run``: Hydra's and the old spellings)."""
    from gyrolab.app.parser import build_parsers

    options = {"run": run_options()}
    for name, parser in build_parsers().items():
        options[name] = [s for action in parser._actions for s in action.option_strings]
    return options


def script(shell: str) -> str:
    """The completion script for ``shell`` (bash, or zsh through its bash compatibility)."""
    from gyrolab.app.parser import ALIASES, COMMANDS, build_parsers, run_parser, value_options

    if shell not in SHELLS:
        raise ConfigError(f"no completion for shell {shell!r}; valid choices: {', '.join(SHELLS)}")
    options = option_words()
    config = config_words()
    plot_words = [w for w in config if w.startswith("output.")]
    lines = [
        "# gyrolab completion (bash and zsh); generated by `gyrolab completion " + shell + "`",
        "# Put `eval \"$(gyrolab completion " + shell + ")\"` in your ~/." + shell + "rc; generate it again after "
        "installing a plugin.",
    ]
    if shell == "zsh":
        lines += ["autoload -U +X compinit && compinit", "autoload -U +X bashcompinit && bashcompinit"]
    lines += [
        f"_gyrolab_commands={_quote(' '.join(COMMANDS))}",
        f"_gyrolab_aliases={_quote(' '.join(ALIASES))}",
        f"_gyrolab_config={_quote(chr(10).join(config))}",
        f"_gyrolab_plot_config={_quote(chr(10).join(plot_words))}",
        f"_gyrolab_path_commands={_quote(' '.join(PATH_COMMANDS))}",
        f"_gyrolab_value_options={_quote(' '.join(sorted(value_options({'run': run_parser(), **build_parsers()}))))}",
    ]
    for name, words in options.items():
        lines.append(f"_gyrolab_options_{name.replace('-', '_')}={_quote(chr(10).join(words))}")
    lines.append(BODY)
    return "\n".join(lines)


def _quote(text: str) -> str:
    return "'" + text.replace("'", "'\\''") + "'"


#: the shell function: finds the word under the cursor (readline splits ``key=value`` at ``=``; the word is
#: put together again), the subcommand named so far, and offers the words of one level below the cursor
BODY = r'''
_gyrolab() {
    local line cur word command="" overrides=0 w c rest strip candidates
    [[ -n "${ZSH_VERSION-}" ]] && setopt localoptions shwordsplit   # split words as bash does
    if [[ -n "${COMP_LINE-}" ]]; then
        line="${COMP_LINE:0:${COMP_POINT:-${#COMP_LINE}}}"
    else
        line="${COMP_WORDS[*]:0:$((COMP_CWORD + 1))}"
        line="${line// =/=}"; line="${line//= /=}"; line="${line// :/:}"; line="${line//: /:}"
    fi
    cur="${line##* }"
    word="${COMP_WORDS[COMP_CWORD]}"
    strip=""
    if [[ -z "${ZSH_VERSION-}" && "$word" != "$cur" && "$cur" == *[=:]* ]]; then
        strip="${cur%"${cur##*[=:]}"}"   # readline replaces only the text after the last = or :
    fi
    set -- ${line% *}
    shift   # the command's own name
    local value_next=0 option="" confdir=""
    for w in "$@"; do
        if [[ $value_next -eq 1 ]]; then   # the value of --config-dir DIR, ...
            value_next=0
            [[ "$option" == --config-dir || "$option" == -cd ]] && confdir="$w"
            continue
        fi
        case "$w" in --config-dir=*|-cd=*) confdir="${w#*=}"; continue;; esac
        if [[ " $_gyrolab_value_options " == *" $w "* ]]; then value_next=1; option="$w"; continue; fi
        case " $_gyrolab_aliases " in *" ${w%%=*} "*) command="${w#--}"; command="${command%%=*}"; continue;; esac
        if [[ -z "$command" && $overrides -eq 0 && "$w" != -* && " $_gyrolab_commands " == *" $w "* ]]; then
            command="$w"
        elif [[ "$w" != -* ]]; then
            overrides=1
        fi
    done
    [[ -z "$command" ]] && command=run
    if [[ $value_next -eq 1 ]]; then   # the cursor is on an option's value
        local IFS=$'\n'
        case "$w" in
            --config-dir|-cd|--config-path|-cp) COMPREPLY=($(compgen -d -- "$cur"));;
            --animate|-o|--output|--experimental-rerun) COMPREPLY=($(compgen -f -- "$cur"));;
            --format) COMPREPLY=($(compgen -W $'gif\nmp4' -- "$cur"));;
            --cfg|-c) COMPREPLY=($(compgen -W $'job\nhydra\nall' -- "$cur"));;
            --info|-i) COMPREPLY=($(compgen -W $'all\nconfig\ndefaults\ndefaults-tree\nplugins\nsearchpath' -- "$cur"));;
            *) COMPREPLY=();;
        esac
        return 0
    fi
    if [[ "$cur" == -* ]]; then
        candidates="$(eval "printf '%s' \"\$_gyrolab_options_${command//-/_}\"")"
    else
        case "$command" in
            run|batch)
                candidates="$_gyrolab_config"
                if [[ -n "$confdir" && "$cur" == *=* ]]; then   # the options of the user's --config-dir
                    local group="${cur%%=*}" f
                    group="${group#+}"
                    confdir="${confdir/#\~/$HOME}"
                    for f in "$confdir/$group"/*.yaml; do
                        [[ -f "$f" ]] || continue
                        f="${f##*/}"
                        candidates+=$'\n'"${cur%%=*}=${f%.yaml}"
                    done
                fi;;
            plot) candidates="$_gyrolab_plot_config";;
            completion) candidates=$'bash\nzsh';;
            *) candidates="";;
        esac
        if [[ "$command" == run && $overrides -eq 0 ]]; then
            local nl=$'\n'
            candidates="${_gyrolab_commands// /$nl}$nl$candidates"
        fi
    fi
    COMPREPLY=()
    local IFS=$'\n'
    for c in $candidates; do
        [[ "$c" == "$cur"* && ( "$c" != "$cur" || "$c" != *[=.] ) ]] || continue
        rest="${c#"$cur"}"
        rest="${rest%[=.]}"
        [[ "$rest" == *[=.]* ]] && continue   # one level at a time: time. before time.end=
        COMPREPLY+=("${c#"$strip"}")
    done
    if [[ " $_gyrolab_path_commands " == *" $command "* && "$cur" != -* && "$cur" != *=* ]]; then
        COMPREPLY+=($(compgen -f -- "$cur"))
    fi
    if [[ ${#COMPREPLY[@]} -gt 0 ]] && type compopt >/dev/null 2>&1; then
        for c in "${COMPREPLY[@]}"; do
            [[ "$c" == *[=./] ]] && { compopt -o nospace 2>/dev/null; break; }
        done
    fi
    return 0
}
complete -F _gyrolab gyrolab
'''
