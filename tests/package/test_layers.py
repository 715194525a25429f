"""The package's layers: each sub-package imports only the layers below it, function-level imports included.

The table is the architecture (``gyrolab/__init__``'s docstring says it in words). An import that is only
read by type checkers (under ``if TYPE_CHECKING:``) never runs and is not counted; loading a plugin by name
through ``gyrolab.contracts.registry`` is not an import. A strict order forbids every cycle between
sub-packages.
"""

from __future__ import annotations

import ast
from pathlib import Path

from tests.helpers import REPO


SOURCES = {"pipeline": "gyrolab", "plugins": "gyrolab.plugins"}

#: sub-package -> layer; an import must go to a strictly lower layer or stay inside its own sub-package
LAYERS = {
    "gyrolab.errors": 0,
    "gyrolab.compat": 0,
    "gyrolab.physics": 1,
    "gyrolab.kernels": 2,
    "gyrolab.contracts": 3,
    "gyrolab.plugins.forces": 4,
    "gyrolab.plugins.systems": 4,
    "gyrolab.plugins.integrators": 5,
    "gyrolab.accuracy": 6,
    "gyrolab.analysis": 7,
    "gyrolab.plugins.regimes": 8,
    "gyrolab.output": 9,
    "gyrolab.figures": 10,
    "gyrolab.engine": 11,
    "gyrolab.sweep": 12,
    "gyrolab.batch": 13,
    "gyrolab.experiments": 14,
    "gyrolab.testing": 15,
    "gyrolab.scaffold": 15,
    "gyrolab.app": 16,
    "gyrolab.__main__": 17,
    "gyrolab": 17,
    "gyrolab.plugins": 17,
}


def _module_name(path: Path) -> str:
    folder, _, rest = path.relative_to(REPO).as_posix().partition("/")
    dotted = rest[:-3].replace("/", ".")
    dotted = dotted.removesuffix("__init__").rstrip(".")
    return f"{SOURCES[folder]}.{dotted}".rstrip(".")


def _unit(module: str) -> str:
    """The layer a module belongs to: the longest entry of LAYERS that is the module or a package of it."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        candidate = ".".join(parts[:n])
        if candidate in LAYERS:
            return candidate
    raise AssertionError(f"{module} belongs to no layer of tests/package/test_layers.py's LAYERS: add it")


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                lines.update(range(child.lineno, (child.end_lineno or child.lineno) + 1))
    return lines


def _imports(path: Path) -> list[tuple[str, int]]:
    """Every gyrolab module a file imports (``from gyrolab import x`` names gyrolab.x), with its line."""
    tree = ast.parse(path.read_text(), str(path))
    skipped = _type_checking_lines(tree)
    found = []
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skipped:
            continue
        if isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("gyrolab"):
            if node.module == "gyrolab" or node.module == "gyrolab.plugins":
                found += [(f"{node.module}.{alias.name}", node.lineno) for alias in node.names]
            else:
                found.append((node.module, node.lineno))
        elif isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names if alias.name.startswith("gyrolab")]
    return found


def _violations() -> list[str]:
    bad = []
    for folder in SOURCES:
        for path in sorted((REPO / folder).rglob("*.py")):
            here = _unit(_module_name(path))
            for target, line in _imports(path):
                there = _unit(target)
                if there != here and LAYERS[there] >= LAYERS[here]:
                    bad.append(f"{path.relative_to(REPO)}:{line}: {here} (layer {LAYERS[here]}) imports {target} "
                               f"(layer {LAYERS[there]})")
    return bad


def test_every_import_goes_down_the_layers():
    bad = _violations()
    assert not bad, "imports against the layers:\n" + "\n".join(bad)


def test_physics_imports_nothing_of_gyrolab_but_errors():
    for path in sorted((REPO / "pipeline" / "physics").rglob("*.py")):
        for target, line in _imports(path):
            assert target.startswith(("gyrolab.physics", "gyrolab.errors")), f"{path.name}:{line} imports {target}"


def test_the_checker_sees_a_function_level_import(tmp_path):
    # the rule must be able to fail: an upward import hidden in a function body is found
    tree = ast.parse("def f():\n    from gyrolab.engine.scene import Scene\n")
    imported = [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    assert imported == ["gyrolab.engine.scene"]
    assert LAYERS[_unit("gyrolab.engine.scene")] > LAYERS[_unit("gyrolab.physics.body")]


def test_no_moved_module_aliases():
    """A 0.1.0 package keeps one name per module: no import hook mapping old module paths to new ones."""
    import sys

    import gyrolab

    assert not hasattr(gyrolab, "MOVED_MODULES")
    assert not any(type(finder).__module__.startswith("gyrolab") for finder in sys.meta_path)


#: what only gyrolab.compat may import or call: Hydra's private API, xarray's internals
PRIVATE = ("hydra._internal", "xarray.backends", "xarray.namedarray", "xarray.core")


def test_library_internals_behind_one_module():
    for folder in SOURCES:
        for path in sorted((REPO / folder).rglob("*.py")):
            if path.name == "compat.py":
                continue
            tree = ast.parse(path.read_text())
            for node in ast.walk(tree):
                names = [node.module or ""] if isinstance(node, ast.ImportFrom) else \
                    [a.name for a in node.names] if isinstance(node, ast.Import) else []
                assert not any(n.startswith(PRIVATE) for n in names), \
                    f"{path.relative_to(REPO)}:{node.lineno} imports a library's internals; use gyrolab.compat"
                if isinstance(node, ast.Attribute):
                    assert node.attr not in ("_construct_direct", "_load_configuration_impl"), \
                        f"{path.relative_to(REPO)}:{node.lineno} uses a library's private attribute; use gyrolab.compat"


def test_the_compiled_parameter_array_is_read_by_name():
    """The fixed-point model's parameter array is laid out in pipeline/kernels/layout.py; code reads it by those
    names (p[U_Z + 1]), never by bare numbers (p[10]) that silently break when the layout changes."""
    import io
    import re
    import tokenize

    # p[3], params[3], P[:, 3] (rows of parameters) and P[3, j] (a transposed table): the parameter index as a number
    pattern = re.compile(r"\b(p\[\d|params\[\d|P\[:, *\d|P\[\d+, *j\])")
    bad = []
    for folder in SOURCES:
        for path in sorted((REPO / folder).rglob("*.py")):
            if path.name == "layout.py":
                continue
            source = path.read_text()
            for tok in tokenize.generate_tokens(io.StringIO(source).readline):
                # code only: a docstring or comment may quote the numbers
                if tok.type not in (tokenize.STRING, tokenize.COMMENT) and tok.type == tokenize.NAME \
                        and tok.string in ("p", "P", "params"):
                    line = tok.line[tok.start[1]:]
                    if pattern.match(line):
                        bad.append(f"{path.relative_to(REPO)}:{tok.start[0]}: {tok.line.strip()}")
    assert not bad, "bare indices of the compiled parameter array:\n" + "\n".join(bad)
