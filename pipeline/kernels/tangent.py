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
one compiled form. Without the MEGNO quadratures (``quadratures=False``: x, u, ℓ) it is the lean flow the growth of
perturbations needs (``accuracy.amplification``). A leading block of the state whose rates read only that block (the
fixed point's (ω, γ) when no torque reads α) can be followed alone (``size``): the rest (α) rides along passively.

Cost (the fixed point's flow against the hand-written kernels it replaced, issue 31): a division x / c becomes
x · (1/c) with 1/c computed once per divisor, so the state's rate and its slope share one division (the inertia's
three, not six); the state's rate so differs from the model's own by at most an ulp.
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


def _neg(a: Any) -> Any:
    return 0 if _is_zero(a) else -a


def _sub(a: Any, b: Any) -> Any:
    return a if _is_zero(b) else _neg(b) if _is_zero(a) else a - b


#: an operation's (value of its arguments' values a, slope from a, their slopes d and the value v): textbook rules
_RULES = {
    "add": (lambda a: a[0] + a[1], lambda a, d, v: _add(d[0], d[1])),
    "sub": (lambda a: a[0] - a[1], lambda a, d, v: _sub(d[0], d[1])),
    "neg": (lambda a: -a[0], lambda a, d, v: _neg(d[0])),
    "mul": (lambda a: a[0] * a[1], lambda a, d, v: _add(_mul(d[0], a[1]), _mul(a[0], d[1]))),
    "ipow": (lambda a: a[0] ** int(a[1]),
             lambda a, d, v: _mul(_mul(int(a[1]), a[0] ** (int(a[1]) - 1)) if int(a[1]) != 1 else 1, d[0])),
    "sqrt": (lambda a: np.sqrt(a[0]), lambda a, d, v: 0 if _is_zero(d[0]) else d[0] / (2 * v)),
    "exp": (lambda a: np.exp(a[0]), lambda a, d, v: _mul(v, d[0])),
    "log": (lambda a: np.log(a[0]), lambda a, d, v: 0 if _is_zero(d[0]) else d[0] / a[0]),
    "sin": (lambda a: np.sin(a[0]), lambda a, d, v: _mul(np.cos(a[0]), d[0])),
    "cos": (lambda a: np.cos(a[0]), lambda a, d, v: _mul(-np.sin(a[0]), d[0])),
    "tan": (lambda a: np.tan(a[0]), lambda a, d, v: _mul(1 + v * v, d[0])),
    "tanh": (lambda a: np.tanh(a[0]), lambda a, d, v: _mul(1 - v * v, d[0])),
    "arctan": (lambda a: np.arctan(a[0]), lambda a, d, v: 0 if _is_zero(d[0]) else d[0] / (1 + a[0] * a[0])),
    # sign(x) dx (undefined at x = 0, as |x|' is)
    "abs": (lambda a: abs(a[0]), lambda a, d, v: 0 if _is_zero(d[0]) else _mul(a[0] / v, d[0])),
    "arctan2": (lambda a: np.arctan2(a[0], a[1]),
                lambda a, d, v: (0 if _is_zero(d[0]) and _is_zero(d[1]) else
                                 _sub(_mul(a[1], d[0]), _mul(a[0], d[1])) / (a[0] * a[0] + a[1] * a[1]))),
    # x^y = exp(y log x)
    "powx": (lambda a: a[0] ** a[1],
             lambda a, d, v: _mul(v, _add(_mul(d[1], np.log(a[0])), 0 if _is_zero(d[0]) else _mul(a[1], d[0] / a[0])))),
}


def leading(model: Model, size: int) -> Model:
    """The first ``size`` rates of ``model`` as a model of the first ``size`` components; ValueError when they read
    a later component (the block is not closed)."""
    part = Model(model.graph, model.rates[:size], size, model.what)
    read = [model.graph.nodes[i][1][0] for i in part.live() if model.graph.nodes[i][0] == "y"]
    if any(k >= size for k in read):
        raise ValueError(f"the first {size} rates of {model.what} read later components")
    return part


def replay(model: Model, graph: Graph, x: np.ndarray, u: np.ndarray, t: Any,
           constants: list[Expr]) -> tuple[list[Any], list[Any]]:
    """(f(t, x), J(x) u) of ``model`` recorded in ``graph``: each node's value and its derivative along u.

    ``constants[i]`` is the new graph's node for the model's number i (so both programs share their numbers).
    """
    value: dict[int, Any] = {}
    slope: dict[int, Any] = {}
    reciprocal: dict[int, Any] = {}  # 1/divisor by the divisor's node: one division for a quotient and its slope
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
        elif op == "div":
            if args[1].index not in reciprocal:
                reciprocal[args[1].index] = 1.0 / a[1]
            r = reciprocal[args[1].index]
            v = a[0] * r
            s = _mul(_sub(d[0], _mul(v, d[1])), r)
        elif op in _RULES:
            value_of, slope_of = _RULES[op]
            v = value_of(a)
            s = slope_of(a, d, v)
        else:
            raise NotCompilable(f"its operation {op!r} has no derivative rule")
        value[i], slope[i] = v, s
    rates = [value[r.index] if isinstance(r, Expr) else 0.0 for r in model.rates]
    slopes = [slope[r.index] if isinstance(r, Expr) else 0 for r in model.rates]
    return rates, slopes


def megno_model(model: Model, quadratures: bool = True) -> Model:
    """The augmented system (x, u, ℓ, a, b) of ``model`` (the module's docstring), as a model of its own; (x, u, ℓ)
    without the MEGNO ``quadratures``."""
    n = model.size
    graph = Graph()
    constants = [graph.lift(c) for c in model.constants]  # first, in order: ``megno_params`` relies on it
    z = symbols(graph, "y", 2 * n + (3 if quadratures else 1))
    t = graph.add("time")
    x, u = z[:n], z[n:2 * n]
    f, Ju = replay(model, graph, x, u, t, constants)
    rate = 0
    for k in range(n):
        rate = _add(rate, _mul(u[k], Ju[k]))
    if _is_zero(rate):
        rate = graph.lift(0.0)
    rates = [*f, *(_sub(Ju[k], rate * u[k]) for k in range(n)), rate]
    if quadratures:
        rates += [t * rate, 2 * z[2 * n + 1] / t]
    values = [v if isinstance(v, Expr) or v == 0 else graph.lift(v) for v in rates]
    return Model(graph, values, len(values), f"{model.what}, tangent flow")


#: augmented compiled models by (the address of their model's right-hand side kernel, size, quadratures)
_MEGNO: dict[tuple[int, int, bool], CompiledModel] = {}


def flow_size(compiled: CompiledModel) -> int:
    """How many leading components of a traced compiled model its tangent flow follows: the fixed point's (ω, γ)
    when it carries α that no torque reads (a closed block, ``leading``), else the whole state. Kept per model form
    (``leading`` takes ~40 µs, and every measured Taylor run asks)."""
    key = (int(compiled.params[TRACED_ADDRESS]), compiled.built_in is not None)
    if key not in _FLOW_SIZES:
        model = MODELS[key[0]]
        _FLOW_SIZES[key] = model.size
        if key[1] and model.size > 6:
            try:
                leading(model, 6)
                _FLOW_SIZES[key] = 6
            except ValueError:
                pass
    return _FLOW_SIZES[key]


#: (traced model's address, built-in form or not) -> its ``flow_size``
_FLOW_SIZES: dict[tuple[int, bool], int] = {}


def compiled_megno(compiled: CompiledModel, quadratures: bool = True) -> CompiledModel:
    """The compiled augmented system of a traced compiled model over its ``flow_size`` leading components (generated
    and compiled once per form)."""
    address = int(compiled.params[TRACED_ADDRESS])
    size = flow_size(compiled)
    key = (address, size, quadratures)
    if key not in _MEGNO:
        _MEGNO[key] = compile(megno_model(leading(MODELS[address], size), quadratures))
    return _MEGNO[key]


def megno_params(augmented: CompiledModel, params: np.ndarray) -> np.ndarray:
    """Parameter rows of the augmented model for parameter rows (..., n) of its model: the model's numbers copied
    into the augmented model's first numbers, its own numbers and kernel addresses kept."""
    params = np.atleast_2d(params)
    rows = np.tile(augmented.params, (len(params), 1))
    count = params.shape[1] - TRACED_FIRST_CONSTANT - TRACED_TAIL
    rows[:, TRACED_FIRST_CONSTANT:TRACED_FIRST_CONSTANT + count] = params[:, TRACED_FIRST_CONSTANT:-TRACED_TAIL]
    return rows


def direction(y0s: np.ndarray, sphere: slice | None = None) -> np.ndarray:
    """Unit initial tangent directions, one row per state: a fixed arbitrary direction (no symmetry of a problem
    singles it out); the part in the components ``sphere`` of a state on a unit sphere (the fixed point's γ,
    |γ| = 1) made tangent to it, so the tangent vector stays on the constraint manifold (the flow keeps γ·δγ)."""
    y0s = np.atleast_2d(np.asarray(y0s, dtype=float))
    u = np.tile(np.cos(1.7 * np.arange(1, y0s.shape[1] + 1) + 0.3), (len(y0s), 1))
    if sphere is not None:
        g = y0s[:, sphere] / np.linalg.norm(y0s[:, sphere], axis=1, keepdims=True)
        u[:, sphere] -= np.sum(u[:, sphere] * g, axis=1, keepdims=True) * g
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def initial_augmented(y0s: np.ndarray, u0: np.ndarray | None = None, quadratures: bool = True) -> np.ndarray:
    """Initial states (x0, u0, 0, 0, 0) of the augmented system ((x0, u0, 0) without the ``quadratures``): u0 the
    unit rows ``direction(y0s)`` unless given."""
    y0s = np.atleast_2d(np.asarray(y0s, dtype=float))
    u = direction(y0s) if u0 is None else np.atleast_2d(np.asarray(u0, dtype=float))
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    return np.concatenate([y0s, u, np.zeros((len(y0s), 3 if quadratures else 1))], axis=1)
