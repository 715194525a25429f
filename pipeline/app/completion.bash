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
