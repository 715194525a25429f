"""Equations as expressions: numpy code run once on symbols, recorded as a straight-line program.

A system's ``rhs(t, y)`` (and the force plugins' ``torque(omega, axes[, t])`` it calls) runs once on
symbolic values (numpy object arrays of ``Expr``): every arithmetic operation it performs is recorded
in a ``Graph``, one node per operation. ``gyrolab.kernels.model`` writes the graph out as the
right-hand side's scalar code and ``gyrolab.kernels.taylor_series`` as its Taylor recurrences: the
equations are written once, in numpy, and every kernel is generated from them (heyoka's way: the
system is an expression). Every number the equations use (a body's inertia, a plugin's parameters,
constants computed from them) becomes an entry of the parameter array instead of a literal, so the
generated source — hence the compiled machine code, cached on disk under a hash of that source —
depends only on the equations' *form*: a sweep over parameters compiles once.

What traces: + − × / unary −, powers, sqrt, exp, log, sin, cos, tan, arctan, tanh, abs, on the
state components, time, and numbers; numpy's elementwise operations, ``cross``, ``dot``, ``sum``,
``concatenate`` and ``linalg.norm`` on such vectors. What does not: a comparison or ``if`` on the
state (the compiled code has no branches), converting the state to a float (``float()``,
``math.*``), and numpy functions without an object-array form.
"""

from __future__ import annotations

import hashlib
import os
import importlib.util
import logging
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from gyrolab.physics.vectors import cross

log = logging.getLogger(__name__)

#: the generated sources' spelling of each operation of one and of two arguments (the generators' shared table)
UNARY = {"neg": "-{0}", "sqrt": "math.sqrt({0})", "exp": "math.exp({0})", "log": "math.log({0})",
         "sin": "math.sin({0})", "cos": "math.cos({0})", "tan": "math.tan({0})", "arctan": "math.atan({0})",
         "tanh": "math.tanh({0})", "abs": "abs({0})"}
BINARY = {"add": "{0} + {1}", "sub": "{0} - {1}", "mul": "{0} * {1}", "div": "{0} / {1}",
          "arctan2": "math.atan2({0}, {1})"}


class NotCompilable(Exception):
    """The torque uses a construct the tracer cannot record; the message names it (one sentence, no period)."""


class Graph:
    """The recorded operations: inputs (state components, time), constants and results."""

    def __init__(self) -> None:
        self.nodes: list[tuple[str, tuple[Any, ...]]] = []
        self.constants: list[float] = []

    def add(self, op: str, *args: Any) -> Expr:
        self.nodes.append((op, args))
        return Expr(self, len(self.nodes) - 1)

    def lift(self, value: Any) -> Expr:
        if isinstance(value, Expr):
            if value.graph is not self:
                raise NotCompilable("it mixes two traces")
            return value
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise NotCompilable(f"it combines the state with a {type(value).__name__}, not a number")
        if not math.isfinite(float(value)):
            raise NotCompilable(f"it uses the non-finite number {float(value)!r}")
        self.constants.append(float(value))
        return self.add("const", len(self.constants) - 1)


class Expr:
    """One recorded scalar; numpy object arrays of these stand for the state's vectors."""

    __slots__ = ("graph", "index")
    __array_priority__ = 1000.0

    def __init__(self, graph: Graph, index: int) -> None:
        self.graph = graph
        self.index = index

    def _bin(self, op: str, other: Any, reflected: bool = False) -> Expr:
        if isinstance(other, np.ndarray):  # a scalar with a vector: elementwise, an object array
            out = np.empty(other.shape, dtype=object)
            for k, item in np.ndenumerate(other):
                out[k] = self._bin(op, item, reflected)
            return out
        if not isinstance(other, Expr) and type(other) is int:  # exact integer identities fold away
            if op == "add" and other == 0:
                return self
            if op == "mul" and other == 1:
                return self
        o = self.graph.lift(other)
        return self.graph.add(op, o, self) if reflected else self.graph.add(op, self, o)

    def __add__(self, o): return self._bin("add", o)  # noqa: E704
    def __radd__(self, o): return self._bin("add", o, True)  # noqa: E704
    def __sub__(self, o): return self._bin("sub", o)  # noqa: E704
    def __rsub__(self, o): return self._bin("sub", o, True)  # noqa: E704
    def __mul__(self, o): return self._bin("mul", o)  # noqa: E704
    def __rmul__(self, o): return self._bin("mul", o, True)  # noqa: E704
    def __truediv__(self, o): return self._bin("div", o)  # noqa: E704
    def __rtruediv__(self, o): return self._bin("div", o, True)  # noqa: E704
    def __neg__(self): return self.graph.add("neg", self)  # noqa: E704
    def __pos__(self): return self  # noqa: E704
    def __abs__(self): return self.graph.add("abs", self)  # noqa: E704

    def __pow__(self, exponent: Any) -> Expr:
        if isinstance(exponent, Expr):
            return self.graph.add("powx", self, exponent)
        if isinstance(exponent, (int, np.integer)) or (isinstance(exponent, (float, np.floating))
                                                       and float(exponent).is_integer() and abs(exponent) <= 16):
            return self.graph.add("ipow", self, int(exponent))
        return self.graph.add("powx", self, self.graph.lift(exponent))

    def __rpow__(self, base: Any) -> Expr:
        return self.graph.add("powx", self.graph.lift(base), self)

    # numpy's ufuncs on object arrays call the element's method of the same name
    def sqrt(self): return self.graph.add("sqrt", self)  # noqa: E704
    def exp(self): return self.graph.add("exp", self)  # noqa: E704
    def log(self): return self.graph.add("log", self)  # noqa: E704
    def sin(self): return self.graph.add("sin", self)  # noqa: E704
    def cos(self): return self.graph.add("cos", self)  # noqa: E704
    def tan(self): return self.graph.add("tan", self)  # noqa: E704
    def arctan(self): return self.graph.add("arctan", self)  # noqa: E704
    def tanh(self): return self.graph.add("tanh", self)  # noqa: E704
    def square(self): return self.graph.add("ipow", self, 2)  # noqa: E704
    def conjugate(self): return self  # noqa: E704  (np.dot / vdot on object arrays)

    def arctan2(self, other: Any) -> Expr:
        return self.graph.add("arctan2", self, self.graph.lift(other))

    def __bool__(self) -> bool:
        raise NotCompilable("it branches on the state (an `if`, `and`/`or` or `max`/`min` on it), and compiled code "
                         "cannot branch")

    def _compare(self, other: Any) -> bool:
        raise NotCompilable("it compares the state (`<`, `>`, `==`, an `if` or `max`/`min` on it), and compiled code "
                         "cannot branch")

    __lt__ = __le__ = __gt__ = __ge__ = _compare

    def __eq__(self, other: Any) -> bool:  # type: ignore[override]
        return self._compare(other)

    __hash__ = object.__hash__

    def __float__(self) -> float:
        raise NotCompilable("it converts the state to a Python float (`float()` or a `math` function) instead of "
                         "using numpy's functions (np.sqrt, np.exp, ...)")

    __int__ = __index__ = __complex__ = __float__  # type: ignore[assignment]


def symbols(graph: Graph, op: str, count: int, first: int = 0) -> np.ndarray:
    """``count`` symbolic inputs (``op`` "y": state components ``first``...; "time"), as an object array."""
    out = np.empty(count, dtype=object)
    for k in range(count):
        out[k] = graph.add(op, first + k) if op == "y" else graph.add(op)
    return out


def check_torques(forces: list[Any]) -> None:
    """Raise NotCompilable naming the first force whose torque cannot be traced, and the construct.

    A system's equations are traced as a whole (``model.trace``); tracing each force's torque alone first, on
    symbolic ω, reference axes and time, lets the refusal name the force. Costs microseconds.
    """
    for force in forces:
        graph = Graph()
        omega, gamma, alpha = (symbols(graph, "y", 3, first) for first in (0, 3, 6))
        frame = (alpha, cross(gamma, alpha), gamma)
        axes = tuple(v if i in force.required_axes else None for i, v in enumerate(frame))
        try:
            with np.errstate(all="ignore"):
                value = force.torque(omega, axes, graph.add("time")) if getattr(force, "time_dependent", False) \
                    else force.torque(omega, axes)
        except NotCompilable as exc:
            raise NotCompilable(f"the torque of force {force.name!r} cannot be compiled: {exc}") from None
        except Exception as exc:  # numpy functions without an object form, undeclared axes (None), ...
            raise NotCompilable(f"the torque of force {force.name!r} cannot be compiled: tracing it raised "
                                f"{type(exc).__name__}: {exc}") from None
        shape = np.shape(value)
        if shape != (3,):
            raise NotCompilable(f"the torque of force {force.name!r} has shape {shape}, not (3,)")


def binary_power(x: Any, n: int, multiply: Any) -> Any:
    """x^n for an integer n ≥ 1 by binary powering with ``multiply(a, b)``: the generators' series of an integer
    power, Cauchy products only (no division by x_0, so x_0 = 0 is fine)."""
    result, square = None, x
    while True:
        if n & 1:
            result = square if result is None else multiply(result, square)
        n >>= 1
        if not n:
            return result
        square = multiply(square, square)


_LOADED: dict[str, Any] = {}


def generated_module(source: str, prefix: str, what: str) -> Any:
    """A generated module of numba ``cfunc``s: written to PREFIX_<hash of source>.py in the kernel cache, imported
    (numba compiles it, or loads its cache) once per process; the first compilation on a machine logs
    "compiling WHAT, once"."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:16]
    module_name = f"{prefix}_{digest}"
    if module_name not in _LOADED:
        from gyrolab.kernels.compiler import kernel_cache_dir  # start-up: imports numba, needed only to compile

        folder = Path(kernel_cache_dir()) / "forces"
        try:
            folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        except OSError:  # a read-only cache (some cluster nodes): this user's private temporary folder
            from gyrolab.kernels.cache import private_temporary  # (rare: a read-only cache)

            folder = private_temporary() / "forces"
            folder.mkdir(mode=0o700, exist_ok=True)
        path = folder / f"{module_name}.py"
        marker = path.with_suffix(".compiled")
        if not path.exists() or path.read_text() != source:
            # written beside its final name and renamed, so a concurrent process never imports half a file
            # (the kernels sit below gyrolab.output, whose atomic_path does the same with more ceremony)
            tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
            tmp.write_text(source)
            os.replace(tmp, path)
        if not marker.exists():
            log.info("compiling %s, once (cached for later runs)", what)
        spec = importlib.util.spec_from_file_location(module_name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[module_name] = module
        spec.loader.exec_module(module)
        _LOADED[module_name] = module  # its cfuncs compiled (or loaded their cache) on import
        marker.touch()
    return _LOADED[module_name]
