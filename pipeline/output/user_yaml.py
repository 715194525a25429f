"""A user's YAML files (``--config-dir``, ``--config-path``), and every config gyrolab stored (a dataset's
``config`` attribute, ``multirun.yaml``, ``.hydra/*.yaml``), read as what they claim to be before anything else
reads them (``stored_yaml``: a directory or a dataset received from someone else is untrusted input).

Hydra turns a YAML problem into a long traceback and expands anchors and aliases without bound; each file is
checked here first with PyYAML's safe loader, and any problem (syntax, tabs, control characters, not UTF-8, a
duplicate key, not a mapping, a tag, beyond ``MAX_EXPANDED_NODES``, ``MAX_DEPTH``, ``MAX_FILE_BYTES`` or
``MAX_FILES``) is one ConfigError sentence naming the file and line, never its contents (docs/faults.md).
"""

from __future__ import annotations

import contextlib
import os
import stat
from pathlib import Path

import yaml

from gyrolab.errors import ConfigError, shorten

MAX_FILE_BYTES = 1024 * 1024
#: the end of a sentence about a stored config that is not what gyrolab stores
EDITED = "gyrolab stores plain YAML mappings, so it was edited; give a file gyrolab wrote"
#: the tags YAML's core schema resolves plain values to; any other (!!python/..., !custom) is refused
CORE_TAGS = frozenset(f"tag:yaml.org,2002:{t}" for t in
                      ("str", "int", "float", "bool", "null", "map", "seq", "merge", "timestamp", "binary"))
MAX_FILES = 2000
#: nodes of a file with every alias expanded (gyrolab's largest packaged file has a few hundred)
MAX_EXPANDED_NODES = 100_000
#: nesting of lists and mappings (gyrolab's deepest packaged file: 5; Python's recursion ends near 1000)
MAX_DEPTH = 32


def check_user_config_dir(directory: str, option: str) -> None:
    """ConfigError (one sentence, file and line) for the first YAML file under ``directory`` that Hydra cannot read."""
    count = 0
    for root, dirs, files in os.walk(directory, followlinks=False):
        dirs.sort()
        for name in sorted(files):
            if not name.endswith((".yaml", ".yml")):
                continue
            count += 1
            if count > MAX_FILES:
                raise ConfigError(f"{option} {shorten(directory)!r} holds more than {MAX_FILES} YAML files; give the "
                                  "folder of your configs only")
            where = _display(Path(root) / name)
            check_yaml_text(_read(Path(root) / name, where), where)


def _read(path: Path, where: str, *, kind: str = "a config folder holds") -> bytes:
    """The bytes of the regular file ``path`` (at most MAX_FILE_BYTES), read without following a FIFO or a device."""
    try:
        if not stat.S_ISREG(path.stat().st_mode):  # a FIFO or a link to /dev/zero would block the read forever
            raise ConfigError(f"{where} is not a regular file; {kind} YAML files")
        if path.stat().st_size > MAX_FILE_BYTES:
            raise ConfigError(f"{where} is larger than {MAX_FILE_BYTES // 1024} KiB; a config file is a short "
                              "YAML mapping of settings")
        return path.read_bytes()
    except OSError as error:
        raise ConfigError(f"{where} cannot be read ({error.strerror or error}); {kind} readable "
                          "YAML files") from None


def check_yaml_text(data: bytes | str, where: str, *, stored: bool = False) -> yaml.Node | None:
    """ConfigError (one sentence naming ``where`` and the line) unless ``data`` is a plain YAML mapping within the
    limits; the composed node (None for an empty text). ``stored``: the sentences say a stored config was edited."""
    node = _composed(_decoded(data, where), where, stored)
    if node is None:
        return None  # an empty file is an empty config
    _check_nodes(node, where)
    _check_top_level(node, where, stored)
    return node


def _decoded(data: bytes | str, where: str) -> str:
    """The text of ``data``: within the size limit, UTF-8, no control character YAML refuses."""
    if isinstance(data, str):
        data = data.encode("utf-8", "surrogatepass")
    if len(data) > MAX_FILE_BYTES:
        raise ConfigError(f"{where} is larger than {MAX_FILE_BYTES // 1024} KiB; a config is a short YAML mapping "
                          "of settings")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        raise ConfigError(f"{where}, line {line}: not UTF-8 text; a config file is a YAML text file") from None
    bad = next((i for i, c in enumerate(text) if (ord(c) < 32 and c not in "\t\n\r") or c == "\x7f"), None)
    if bad is not None:
        raise ConfigError(f"{where}, line {text.count(chr(10), 0, bad) + 1}: a control character (code "
                          f"{ord(text[bad])}) that YAML does not allow; a config file is plain text")
    return text


def _composed(text: str, where: str, stored: bool) -> yaml.Node | None:
    """The YAML node of ``text`` (not deeper than the limit), or one sentence saying where it is not YAML."""
    try:
        _check_depth(text, where)  # before composing: PyYAML's composer recurses once per level
        return yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as error:
        if stored:
            mark = error.problem_mark or error.context_mark
            at = f" at line {mark.line + 1}" if mark is not None else ""
            raise ConfigError(f"{where} is not plain YAML{at} ({shorten(str(error.problem or error.context), 120)}); "
                              f"{EDITED}") from None
        raise ConfigError(_sentence(where, error)) from None
    except yaml.YAMLError as error:
        raise ConfigError(f"{where} is not valid YAML ({shorten(type(error).__name__)})") from None


def _check_top_level(node: yaml.Node, where: str, stored: bool) -> None:
    """ConfigError unless the file is a mapping whose ``defaults``, if any, is a list."""
    if not isinstance(node, yaml.MappingNode):
        kind = "a list" if isinstance(node, yaml.SequenceNode) else "a single value"
        if stored:
            raise ConfigError(f"{where} is {kind}, not a YAML mapping of config sections; {EDITED}")
        raise ConfigError(f"{where}, line {node.start_mark.line + 1}: the file is {kind}, not a mapping of settings "
                          "(key: value lines); every config file is a mapping")
    for key, value in node.value:
        if key.value == "defaults" and not isinstance(value, yaml.SequenceNode):
            raise ConfigError(f"{where}, line {value.start_mark.line + 1}: `defaults` must be a list (- group: option "
                              "lines), as in Hydra's defaults list")


def stored_yaml(data: bytes | str, where: str) -> dict:
    """A config gyrolab stored (a dataset's ``config`` attribute, ``multirun.yaml``, ``.hydra/config.yaml``) as
    plain data, after the checks of a user's file (it may come from someone else)."""
    if not isinstance(data, (str, bytes)):
        raise ConfigError(f"{where} is not text; a stored config is a YAML mapping that gyrolab wrote")
    if check_yaml_text(data, where, stored=True) is None:
        return {}
    return yaml.safe_load(data)  # checked: plain tags, bounded size and depth


def stored_yaml_file(path: Path, where: str | None = None) -> dict:
    """``stored_yaml`` of the file ``path`` (a regular file of at most MAX_FILE_BYTES)."""
    where = where or _display(path)
    return stored_yaml(_read(Path(path), where, kind="a stored config is"), where)


def _check_depth(text: str, where: str) -> None:
    """ConfigError when lists and mappings nest deeper than MAX_DEPTH (PyYAML's parser is iterative; its composer
    is not, and Python's recursion would end near 1000 levels)."""
    depth = 0
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            depth += 1
            if depth > MAX_DEPTH:
                raise ConfigError(f"{where}, line {event.start_mark.line + 1}: lists and mappings nested more than "
                                  f"{MAX_DEPTH} deep; a config file is a short mapping of settings")
        elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            depth -= 1


def _display(path: Path) -> str:
    """The file as the user can find it: relative to the working directory when inside it."""
    text = str(path)
    with contextlib.suppress(ValueError):
        relative = os.path.relpath(path)
        text = relative if not relative.startswith("..") else text
    return shorten(text, 200)


def _sentence(where: str, error: yaml.MarkedYAMLError) -> str:
    mark = error.problem_mark or error.context_mark
    at = f", line {mark.line + 1}" if mark is not None else ""
    problem = str(error.problem or error.context or "syntax error")
    if "'\\t'" in problem:
        problem = "a tab, which YAML does not allow for indentation (use spaces)"
    return f"{where}{at}: not valid YAML ({shorten(problem, 120)}); fix the file or remove it from the folder"


def _check_nodes(root: yaml.Node, where: str) -> None:
    """Duplicate keys, and the size of the file with its aliases expanded (a shared node counts every time)."""
    sizes: dict[int, int] = {}
    stack: list[tuple[yaml.Node, bool, int]] = [(root, False, 0)]
    on_path: set[int] = set()
    while stack:
        node, done, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise ConfigError(f"{where}, line {node.start_mark.line + 1}: lists and mappings nested more than "
                              f"{MAX_DEPTH} deep; a config file is a short mapping of settings")
        key = id(node)
        if done:
            on_path.discard(key)
            children = _children(node)
            sizes[key] = 1 + sum(sizes[id(c)] for c in children)
            if sizes[key] > MAX_EXPANDED_NODES:
                raise ConfigError(f"{where}, line {node.start_mark.line + 1}: its anchors and aliases expand to more "
                                  f"than {MAX_EXPANDED_NODES} values; a config file is a short mapping of settings")
            continue
        if key in sizes:
            continue
        if key in on_path:
            raise ConfigError(f"{where}, line {node.start_mark.line + 1}: an alias refers to itself; "
                              "a config file cannot be recursive")
        on_path.add(key)
        if node.tag not in CORE_TAGS:
            raise ConfigError(f"{where}, line {node.start_mark.line + 1}: the YAML tag {shorten(node.tag, 60)!r} is not "
                              "allowed (not plain YAML: gyrolab refuses tags such as !!python/...); a config holds "
                              "plain values (numbers, strings, lists, mappings)")
        if isinstance(node, yaml.MappingNode):
            _check_keys(node, where)
        stack.append((node, True, depth))
        stack.extend((c, False, depth + 1) for c in _children(node) if id(c) not in sizes)


def _check_keys(node: yaml.MappingNode, where: str) -> None:
    """ConfigError for a key that is not a plain name, or given twice in one mapping."""
    seen: dict[object, int] = {}
    for k, _ in node.value:
        if not isinstance(k, yaml.ScalarNode):
            raise ConfigError(f"{where}, line {k.start_mark.line + 1}: a key is a list or a mapping; keys of a "
                              "config are plain names")
        if k.value in seen and k.tag != "tag:yaml.org,2002:merge":
            raise ConfigError(f"{where}, line {k.start_mark.line + 1}: the key {shorten(k.value, 60)!r} "
                              f"is given twice in one mapping (first on line {seen[k.value]}); give each key once")
        seen[k.value] = k.start_mark.line + 1


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []
