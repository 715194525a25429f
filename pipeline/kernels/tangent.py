"""The tangent flow of a traced model, generated from its equations: the chaos indicators of any system.

A model's program (``model.Model``) is replayed in forward mode (the derivative of every operation by its
textbook rule, e.g. d(x·y) = dx·y + x·dy, d sin x = cos x dx) on symbolic states x and directions u: the replay
records f(x) and the directional derivative J(x) u as a new program. From it ``megno_model`` builds the model of
the augmented system

    x' = f(t, x),   u' = J u − λ u,   ℓ' = λ,   a' = t λ,   b' = 2 a / t,      λ = u · J u,

whose u stays a unit vector (so no renormalisation between steps: any integrator of the traced form runs it),
ℓ = ln |δ| of the tangent vector δ = e^ℓ u of the variational equations δ' = J δ, and b(t)/t the MEGNO ⟨Y⟩(t)
(Cincotta & Simó 2000: Y(t) = (2/t) ∫ s δ·δ'/δ·δ ds, δ·δ'/δ·δ = λ). The fast Lyapunov indicator is max ℓ over the
output times. b' = 2a/t is 0/0 at t = 0 (a = O(t²)): the augmented system starts at the smallest positive double,
``START``, where a = 0 makes it exactly 0 (no time is lost: ``START`` is below the resolution of any other time).

The augmented model's first numbers are the original model's, in the same order (``megno_params`` maps a
parameter row of the model to one of the augmented model), so a batch of points with different parameters needs
one compiled form.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gyrolab.kernels.expression import Expr, Graph, NotCompilable, symbols
from gyrolab.kernels.layout import TRACED_ADDRESS, TRACED_FIRST_CONSTANT, TRACED_TAIL
from gyrolab.kernels.model import MODELS, CompiledModel, Model, compile

#: the augmented system's start time (see the module's docstring)
START = 5e-324


def _is_zero(v: Any) -> bool:
    return not isinstance(v, Expr) and v == 0


def _add(a: Any, b: Any) -> Any:
    return b if _is_zero(a) else a if _is_zero(b) else a + b


def _mul(a: Any, b: Any) -> Any:
    return 0 if _is_zero(a) or _is_zero(b) else a * b


def replay(model: Model, graph: Graph, x: np.ndarray, u: np.ndarray, t: Any,
           constants: list[Expr]) -> tuple[list[Any], list[Any]]:
    """(f(t, x), J(x) u) of ``model`` recorded in ``graph``: each node's value and its derivative along u.

    ``constants[i]`` is the new graph's node for the model's number i (so both programs share their numbers).
    """
    value: dict[int, Any] = {}
    slope: dict[int, Any] = {}
    for i in sorted(model.live()):
        op, args = model.graph.nodes[i]
        a = [value[v.index] if isinstance(v, Expr) else v for v in args]
        d = [slope[v.index] if isinstance(v, Expr) else 0 for v in args]
        if op == "y":
            v, s = x[args[0]], u[args[0]]
        elif op == "time":
            v, s = t, 0
        elif op == "const":
            v, s = constants[args[0]], 0
        elif op == "add":
            v, s = a[0] + a[1], _add(d[0], d[1])
        elif op == "sub":
            v, s = a[0] - a[1], _add(d[0], _mul(-1, d[1]) if not _is_zero(d[1]) else 0)
        elif op == "neg":
            v, s = -a[0], (0 if _is_zero(d[0]) else -d[0])
        elif op == "mul":
            v, s = a[0] * a[1], _add(_mul(d[0], a[1]), _mul(a[0], d[1]))
        elif op == "div":
            v = a[0] / a[1]
            s = 0 if _is_zero(d[0]) and _is_zero(d[1]) else (_add(d[0], _mul(-1, _mul(v, d[1])))) / a[1]
        elif op == "ipow":
            n = int(args[1])
            v = a[0] ** n
            s = _mul(_mul(n, a[0] ** (n - 1)) if n != 1 else 1, d[0])
        elif op == "sqrt":
            v = np.sqrt(a[0])
            s = 0 if _is_zero(d[0]) else d[0] / (2 * v)
        elif op == "exp":
            v = np.exp(a[0])
            s = _mul(v, d[0])
        elif op == "log":
            v = np.log(a[0])
            s = 0 if _is_zero(d[0]) else d[0] / a[0]
        elif op == "sin":
            v, s = np.sin(a[0]), _mul(np.cos(a[0]), d[0])
        elif op == "cos":
            v, s = np.cos(a[0]), _mul(-np.sin(a[0]), d[0])
        elif op == "tan":
            v = np.tan(a[0])
            s = _mul(1 + v * v, d[0])
        elif op == "tanh":
            v = np.tanh(a[0])
            s = _mul(1 - v * v, d[0])
        elif op == "arctan":
            v = np.arctan(a[0])
            s = 0 if _is_zero(d[0]) else d[0] / (1 + a[0] * a[0])
        elif op == "abs":
            v = abs(a[0])
            s = 0 if _is_zero(d[0]) else _mul(a[0] / v, d[0])  # sign(x) dx (undefined at x = 0, as |x|' is)
        elif op == "arctan2":
            v = np.arctan2(a[0], a[1])
            s = (0 if _is_zero(d[0]) and _is_zero(d[1]) else
                 _add(_mul(a[1], d[0]), _mul(-1, _mul(a[0], d[1]))) / (a[0] * a[0] + a[1] * a[1]))
        elif op == "powx":  # x^y = exp(y log x)
            v = a[0] ** a[1]
            s = _mul(v, _add(_mul(d[1], np.log(a[0])), 0 if _is_zero(d[0]) else _mul(a[1], d[0] / a[0])))
        else:
            raise NotCompilable(f"its operation {op!r} has no derivative rule")
        value[i], slope[i] = v, s
    rates = [value[r.index] if isinstance(r, Expr) else 0.0 for r in model.rates]
    slopes = [slope[r.index] if isinstance(r, Expr) else 0 for r in model.rates]
    return rates, slopes


def megno_model(model: Model) -> Model:
    """The augmented system (x, u, ℓ, a, b) of ``model`` (the module's docstring), as a model of its own."""
    n = model.size
    graph = Graph()
    constants = [graph.lift(c) for c in model.constants]  # first, in order: ``megno_params`` relies on it
    z = symbols(graph, "y", 2 * n + 3)
    t = graph.add("time")
    x, u, a = z[:n], z[n:2 * n], z[2 * n + 1]
    f, Ju = replay(model, graph, x, u, t, constants)
    rate = 0
    for k in range(n):
        rate = _add(rate, _mul(u[k], Ju[k]))
    if _is_zero(rate):
        rate = graph.lift(0.0)
    tangent = [_add(Ju[k], -(rate * u[k])) for k in range(n)]
    rates = [*f, *tangent, rate, t * rate, 2 * a / t]
    values = [v if isinstance(v, Expr) or v == 0 else graph.lift(v) for v in rates]
    return Model(graph, values, 2 * n + 3, f"{model.what}, tangent flow")


#: augmented compiled models by the address of their model's right-hand side kernel
_MEGNO: dict[int, CompiledModel] = {}


def compiled_megno(compiled: CompiledModel) -> CompiledModel:
    """The compiled augmented system of a traced compiled model (generated and compiled once per form)."""
    address = int(compiled.params[TRACED_ADDRESS])
    if address not in _MEGNO:
        _MEGNO[address] = compile(megno_model(MODELS[address]))
    return _MEGNO[address]


def megno_params(augmented: CompiledModel, params: np.ndarray) -> np.ndarray:
    """Parameter rows of the augmented model for parameter rows (..., n) of its model: the model's numbers copied
    into the augmented model's first numbers, its own numbers and kernel addresses kept."""
    params = np.atleast_2d(params)
    rows = np.tile(augmented.params, (len(params), 1))
    count = params.shape[1] - TRACED_FIRST_CONSTANT - TRACED_TAIL
    rows[:, TRACED_FIRST_CONSTANT:TRACED_FIRST_CONSTANT + count] = params[:, TRACED_FIRST_CONSTANT:-TRACED_TAIL]
    return rows


def initial_augmented(y0s: np.ndarray, direction: np.ndarray | None = None) -> np.ndarray:
    """Initial states (x0, u0, 0, 0, 0) of the augmented system: u0 a fixed arbitrary unit direction (no symmetry of
    a problem singles it out), or ``direction`` (rows)."""
    y0s = np.atleast_2d(np.asarray(y0s, dtype=float))
    n = y0s.shape[1]
    if direction is None:
        direction = np.tile(np.cos(1.7 * np.arange(1, n + 1) + 0.3), (len(y0s), 1))
    u = np.asarray(direction, dtype=float)
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    return np.concatenate([y0s, u, np.zeros((len(y0s), 3))], axis=1)
