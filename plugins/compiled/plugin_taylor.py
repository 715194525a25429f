"""Taylor coefficients of a traced plugin torque, by automatic propagation through its recorded operations.

The trace of a plugin's torque (``plugin_torque.trace``) is a straight-line program of scalar
operations on the state, time and constants. Every operation has a recurrence giving the k-th
Taylor coefficient of its result from the coefficients 0..k of its arguments and 0..k−1 of its
own (Moore 1966; Jorba & Zou, Exp. Math. 14, 2005, §3; Haro et al. 2016, §2.1). This module
writes those recurrences out as one more generated ``cfunc``

    void f(double t, int64 k, int64 n, double* Y, double* W, double* p, double* out)

which, for order k, reads the state's coefficients Y[0..k] (rows of n), writes row k of the
nodes' coefficients W (rows of ``columns`` entries, rows 0..k−1 from earlier calls) and sets
out[0:3] to the k-th coefficient of I⁻¹ T. Like the right-hand side's kernel it reads the
plugin's numbers from the parameter array, so it depends on the torque's form only and is
compiled once per form (cached on disk). ``coefficients`` adds the built-in quadratic terms
(``fixed_point``'s Cauchy helpers) and fills the state's series for ``taylor``.

Recurrences (x, y the arguments, f the result, a sum over j written Σ_j):
  ± and −x: linear; x·y: Σ_{j=0..k} x_j y_{k−j} (a constant factor: c·y_k);
  x/y: f_k = (x_k − Σ_{j<k} f_j y_{k−j}) / y_0;  √x: f_k = (x_k − Σ_{j=1..k−1} f_j f_{k−j}) / (2 f_0);
  exp: f_k = (1/k) Σ_{j=1..k} j x_j f_{k−j};  log: f_k = (x_k − (1/k) Σ_{j=1..k−1} j f_j x_{k−j}) / x_0;
  sin, cos as a pair: s_k = (1/k) Σ j x_j c_{k−j},  c_k = −(1/k) Σ j x_j s_{k−j};
  tan, tanh: f' = g x' with g = 1 ± f² (an auxiliary series);  arctan: f' (1 + x²) = x';
  arctan2(y, x): f' (x² + y²) = x y' − y x';  x^a (a constant): x f' = a f x', i.e.
  f_k = Σ_{j<k} (a(k−j) − j) x_{k−j} f_j / (k x_0);  x^y (y on the state): exp(y log x);
  x^n (integer n): repeated Cauchy products (no division, so x_0 = 0 is fine), 1/x^|n| for n < 0;
  |x|: sign(x_0) x_k, exact wherever x_0 ≠ 0 (at x_0 = 0, |x| has no Taylor series);
  time: t_0 = t, t_1 = 1.
The divisions make x/y, √x, log x, x^a (a not an integer), x^y and arctan2 (at x = y = 0) singular
where their argument's value is 0 (as the functions themselves, or their derivatives, are): there
the coefficients are inf/NaN and ``taylor`` stops with its one-sentence non-finite error.
The Taylor kernel compiles when a run first needs it (``ready``), not with the right-hand side's.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.plugins.compiled import fixed_point, inline_kernel
from gyrolab.plugins.compiled.layout import (
    ALPHA, CARRIES_ALPHA, FIRST_CONSTANT, GAMMA, INERTIA, INV_INERTIA, N_X, N_Y, N_Z, U_X, U_Y, U_Z,
)
from gyrolab.plugins.compiled.plugin_torque import Expr, Trace, load_generated

# fixed_point's Cauchy helpers, compiled inline here: a call per helper per order costs as much as its sums
_cauchy_cross = inline_kernel(fixed_point._cauchy_cross.py_func)
_cauchy_pairs = inline_kernel(fixed_point._cauchy_pairs.py_func)

#: Entries the Taylor kernel adds after the right-hand side's constants; they end the parameter array:
#: p[-2] = its address, p[-1] = its work columns (both 0 until ``ready`` compiles it).
TAIL = 2


class _Lowered:
    """The trace as columns of W: one per node, plus the auxiliary series some recurrences carry."""

    def __init__(self, result: Trace) -> None:
        self.value: list[str] = []  # row-0 statements
        self.step: list[str] = []  # row-k statements (k ≥ 1; r = k·M, the row's start)
        self.constant: set[int] = set()  # columns whose coefficients of order ≥ 1 vanish
        self.columns = 0
        column: dict[int, int] = {}
        for i, (op, args) in enumerate(result.graph.nodes):
            column[i] = self._op(op, [column[x.index] if isinstance(x, Expr) else x for x in args])
        self.outputs = [[column[v.index] for v in out if isinstance(v, Expr)] for out in zip(*result.outputs)]

    def _new(self, value: str, step: str, constant: bool = False) -> int:
        """A new column: its row-0 statement and row-k statements ({c} is the column), or zeros if constant."""
        c = self.columns
        self.columns += 1
        self.value.append(value.format(c=c))
        if constant:
            self.constant.add(c)
            self.step.append(f"W[r + {c}] = 0.0")
        else:
            self.step.extend(step.format(c=c).split("\n"))
        return c

    def _op(self, op: str, a: list[Any]) -> int:
        if op == "y":
            return self._new(f"W[{{c}}] = Y[{a[0]}]", f"W[r + {{c}}] = Y[k * n + {a[0]}]")
        if op == "time":
            return self._new("W[{c}] = t", "W[r + {c}] = 1.0 if k == 1 else 0.0")
        if op == "const":
            return self._new(f"W[{{c}}] = p[{FIRST_CONSTANT + a[0]}]", "", constant=True)
        if op == "ipow":
            return self._ipow(a[0], a[1])
        if op == "powx" and a[1] not in self.constant:  # x^y = exp(y log x)
            return self._op("exp", [self._op("mul", [a[1], self._op("log", [a[0]])])])
        if op in _BINARY:
            x, y = a
            constant = x in self.constant and y in self.constant
            if op == "mul" and (x in self.constant or y in self.constant):
                cx, cy = (x, y) if x in self.constant else (y, x)
                step = f"W[r + {{c}}] = W[{cx}] * W[r + {cy}]"
            elif op == "div" and y in self.constant:
                step = f"W[r + {{c}}] = W[r + {x}] / W[{y}]"
            elif op == "arctan2":  # f' d = x y' − y x' with d = x² + y² (here y = a[0], x = a[1])
                return self._arctan(f"math.atan2(W[{x}], W[{y}])", x, y, constant)
            else:
                step = _BINARY[op][1]
            return self._new(f"W[{{c}}] = {_BINARY[op][0]}".format(x=x, y=y, c="{c}"),
                             step.format(x=x, y=y, c="{c}"), constant)
        x = a[0]
        constant = x in self.constant
        if op in ("sin", "cos"):  # the pair: the other member in the next column
            c = self.columns
            s, co = (c, c + 1) if op == "sin" else (c + 1, c)
            self._new(f"W[{c}] = math.{op}(W[{x}])", _SINCOS.format(x=x, s=s, co=co), constant)
            other = "cos" if op == "sin" else "sin"
            self._new(f"W[{c + 1}] = math.{other}(W[{x}])", "", constant)
            if not constant:
                self.step.pop()  # the pair's statements fill both columns
            return c
        if op in ("tan", "tanh"):  # f' = g x' with g = 1 ± f²
            sign = "" if op == "tan" else "-"
            c = self._new(f"W[{{c}}] = math.{op}(W[{x}])", _TAN.format(x=x, c="{c}", g="{c} + 1", sign=sign),
                          constant)
            self._new(f"W[{{c}}] = 1.0 {'+' if op == 'tan' else '-'} W[{c}] * W[{c}]", "", constant)
            if not constant:
                self.step.pop()
            return c
        if op == "arctan":  # f' d = x' with d = 1 + x²
            return self._arctan(f"math.atan(W[{x}])", x, None, constant)
        if op == "powx":  # a constant exponent
            return self._new(f"W[{{c}}] = W[{x}] ** W[{a[1]}]", _POWER.format(x=x, e=a[1], c="{c}"),
                             constant and a[1] in self.constant)
        value, step = _UNARY[op]
        return self._new("W[{c}] = " + value.format(x=x), step.format(x=x, c="{c}"), constant)

    def _ipow(self, x: int, n: int) -> int:
        """x^n by binary powering (Cauchy products: no division by x_0), 1/x^|n| for n < 0."""
        if n == 0:
            return self._new("W[{c}] = 1.0", "", constant=True)
        result, square, m = None, x, abs(n)
        while True:
            if m & 1:
                result = square if result is None else self._op("mul", [result, square])
            m >>= 1
            if not m:
                break
            square = self._op("mul", [square, square])
        if n < 0:
            result = self._op("div", [self._new("W[{c}] = 1.0", "", constant=True), result])
        return result

    def _arctan(self, value: str, y: int, x: int | None, constant: bool) -> int:
        """f = arctan(y) (x None) or arctan2(y, x): d = 1 + y² or x² + y² in the next column, f' d = y' or x y' − y x'."""
        c = self.columns
        d = c + 1
        if x is None:
            numerator, square = f"k * W[r + {y}]", f"W[j * M + {y}] * W[(k - j) * M + {y}]"
            d_value = f"1.0 + W[{y}] * W[{y}]"
        else:
            numerator = "num"
            square = f"W[j * M + {x}] * W[(k - j) * M + {x}] + W[j * M + {y}] * W[(k - j) * M + {y}]"
            d_value = f"W[{x}] * W[{x}] + W[{y}] * W[{y}]"
        lines = ["s = 0.0", "for j in range(k + 1):", f"    s += {square}", f"W[r + {d}] = s"]
        if x is not None:
            lines += ["num = 0.0", "for j in range(k):",
                      f"    num += (k - j) * (W[j * M + {x}] * W[(k - j) * M + {y}] "
                      f"- W[j * M + {y}] * W[(k - j) * M + {x}])"]
        lines += [f"s = {numerator}", "for j in range(1, k):", f"    s -= j * W[j * M + {c}] * W[(k - j) * M + {d}]",
                  f"W[r + {c}] = s / (k * W[{d}])"]
        self._new(f"W[{c}] = {value}", "\n".join(lines), constant)
        self._new(f"W[{d}] = {d_value}", "", constant)
        if not constant:
            self.step.pop()
        return c


_BINARY = {
    "add": ("W[{x}] + W[{y}]", "W[r + {c}] = W[r + {x}] + W[r + {y}]"),
    "sub": ("W[{x}] - W[{y}]", "W[r + {c}] = W[r + {x}] - W[r + {y}]"),
    "mul": ("W[{x}] * W[{y}]", "s = 0.0\nfor j in range(k + 1):\n    s += W[j * M + {x}] * W[(k - j) * M + {y}]\n"
                               "W[r + {c}] = s"),
    "div": ("W[{x}] / W[{y}]", "s = W[r + {x}]\nfor j in range(k):\n    s -= W[j * M + {c}] * W[(k - j) * M + {y}]\n"
                               "W[r + {c}] = s / W[{y}]"),
    "arctan2": None,
}
_POWER = ("s = 0.0\nfor j in range(k):\n    s += (W[{e}] * (k - j) - j) * W[(k - j) * M + {x}] * W[j * M + {c}]\n"
          "W[r + {c}] = s / (k * W[{x}])")
_SINCOS = ("s = 0.0\nq = 0.0\nfor j in range(1, k + 1):\n    s += j * W[j * M + {x}] * W[(k - j) * M + {co}]\n"
           "    q += j * W[j * M + {x}] * W[(k - j) * M + {s}]\nW[r + {s}] = s / k\nW[r + {co}] = -q / k")
_TAN = ("s = 0.0\nfor j in range(1, k + 1):\n    s += j * W[j * M + {x}] * W[(k - j) * M + {g}]\nW[r + {c}] = s / k\n"
        "s = 0.0\nfor j in range(k + 1):\n    s += W[j * M + {c}] * W[(k - j) * M + {c}]\nW[r + {g}] = {sign}s")
_UNARY = {
    "neg": ("-W[{x}]", "W[r + {c}] = -W[r + {x}]"),
    "abs": ("abs(W[{x}])", "W[r + {c}] = (1.0 if W[{x}] > 0.0 else -1.0 if W[{x}] < 0.0 else 0.0) * W[r + {x}]"),
    "sqrt": ("math.sqrt(W[{x}])",
             "s = W[r + {x}]\nfor j in range(1, k):\n    s -= W[j * M + {c}] * W[(k - j) * M + {c}]\n"
             "W[r + {c}] = s / (2.0 * W[{c}])"),
    "exp": ("math.exp(W[{x}])",
            "s = 0.0\nfor j in range(1, k + 1):\n    s += j * W[j * M + {x}] * W[(k - j) * M + {c}]\nW[r + {c}] = s / k"),
    "log": ("math.log(W[{x}])",
            "s = 0.0\nfor j in range(1, k):\n    s += j * W[j * M + {c}] * W[(k - j) * M + {x}]\n"
            "W[r + {c}] = (W[r + {x}] - s / k) / W[{x}]"),
}


def source(result: Trace) -> tuple[str, int]:
    """The Taylor cfunc's source for a trace, and the number of columns of its work rows."""
    low = _Lowered(result)
    body = ["if k == 0:"] + [f"    {s}" for s in low.value]
    body += ["    r = 0", "else:", "    r = k * M"] + [f"    {s}" for s in low.step]
    for m, cols in enumerate(low.outputs):
        total = " + ".join(f"W[r + {c}]" for c in cols) or "0.0"
        body.append(f"out[{m}] = ({total}) * p[{INV_INERTIA + m}]")
    text = _HEADER.format(columns=low.columns) + "".join(f"    {line}\n" for line in body)
    return text, low.columns


_HEADER = '''"""Generated by gyrolab: Taylor coefficients of a force plugin's torque (gyrolab.plugins.compiled.plugin_taylor)."""
import math

import numba
from numba import types

M = {columns}
_P = types.CPointer(types.float64)
SIGNATURE = types.void(types.float64, types.int64, types.int64, _P, _P, _P, _P)


@numba.cfunc(SIGNATURE, cache=True, error_model="numpy", fastmath={{"reassoc", "contract", "nsz"}})
def kernel(t, k, n, Y, W, p, out):
'''

#: traces by the address of their right-hand side's kernel: the Taylor kernel compiles when first needed
_TRACES: dict[int, tuple[Trace, list[str]]] = {}


def register(address: int, result: Trace, names: list[str]) -> list[float]:
    """The parameter array's tail (``TAIL``) for a traced torque whose right-hand side's kernel is at ``address``.

    Nothing compiles here: most runs never use taylor, and a Taylor kernel's first compilation costs
    seconds. ``ready`` compiles it when an integrator needs it.
    """
    _TRACES[address] = (result, names)
    return [0.0, 0.0]


def ready(compiled: Any, rows: np.ndarray | None = None) -> bool:
    """Whether ``taylor`` can integrate a compiled model: the built-ins and every traced torque (time-dependent too).

    For a traced torque this compiles (or loads) its Taylor kernel on first need and writes its address
    into ``compiled.params`` (and into every row of ``rows``, a batch's per-trajectory parameters).
    """
    from gyrolab.plugins.compiled import models
    from gyrolab.plugins.compiled.plugin_torque import ADDRESS

    if compiled.model not in (models.FIXED_POINT_PLUGIN, models.FIXED_POINT_PLUGIN_ALPHA):
        return compiled.model in models.TAYLOR_MODELS
    p = compiled.params
    if p[-2] == 0.0:
        p[-2:] = compile_taylor(*_TRACES[int(p[ADDRESS])])
    if rows is not None:
        rows[:, -2:] = p[-2:]
    return True


def compile_taylor(result: Trace, names: list[str]) -> list[float]:
    """[address of the trace's Taylor kernel, its work columns], compiled once per form (cached on disk)."""
    text, columns = source(result)
    kernel = load_generated(text, "gyrolab_taylor", f"force {' + '.join(names)} (Taylor)")
    return [float(kernel.address), float(columns)]


@intrinsic
def _call(typingctx, address, t, k, n, Y, W, p, out):
    """Call ``void f(double t, int64 k, int64 n, double* Y, double* W, double* p, double* out)`` at ``address``."""
    sig = types.void(types.int64, types.float64, types.int64, types.int64, Y, W, p, out)

    def codegen(context, builder, signature, args):
        double_ptr = ir.DoubleType().as_pointer()
        i64 = ir.IntType(64)
        fnty = ir.FunctionType(ir.VoidType(), [ir.DoubleType(), i64, i64] + [double_ptr] * 4)
        data = [builder.bitcast(cgutils.create_struct_proxy(ty)(context, builder, value=v).data, double_ptr)
                for ty, v in zip(signature.args[4:], args[4:])]
        fn = builder.inttoptr(args[0], fnty.as_pointer())
        builder.call(fn, list(args[1:4]) + data)
        return context.get_dummy_value()

    return sig, codegen


# reassociated and contracted like fixed_point.taylor_coefficients (a coefficient's rounding enters the state times h^k)
@numba.njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract", "nsz"})
def coefficients(p, Y, order, work, t):
    """Fill Y[1..order] from Y[0] for the fixed-point system with a traced plugin torque (model FIXED_POINT_PLUGIN).

    Per order k: the k-th coefficients of the built-in quadratic terms, (Iω) × ω + Σ U_i × e_i + Σ N_i e_i × I e_i
    (Cauchy sums, as ``fixed_point``), plus the plugin torque's k-th coefficient from its Taylor kernel, divided by
    I and k + 1; γ̇ = γ × ω and α̇ = α × ω likewise. ``work`` (order+1, 3) holds β = γ × α's series when α is
    carried; the kernel's node series live in an array of p[-1] columns.
    """
    n = Y.shape[1]
    address = int(p[p.size - 2])
    if address == 0:  # the Taylor kernel was not compiled (``ready`` not called): no series, not a crash
        Y[1:] = np.nan
        return
    W = np.empty((order + 1) * int(p[p.size - 1]))
    I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    d0, d1, d2 = I1 - I2, I2 - I0, I0 - I1
    has_alpha = p[CARRIES_ALPHA] != 0.0
    acc = np.empty(3)
    tmp = np.empty(3)
    torque = np.empty(3)
    for k in range(order):
        _call(address, t, k, n, Y, W, p, torque)
        _cauchy_pairs(Y, 0, k, acc)  # (Iω) × ω = d ⊙ pairs of ω
        acc[0] *= d0
        acc[1] *= d1
        acc[2] *= d2
        _gradient_and_linear(p, Y, GAMMA, U_Z, N_Z, k, d0, d1, d2, acc, tmp)
        if has_alpha:
            work[k, 0] = work[k, 1] = work[k, 2] = 0.0  # β_k = Σ γ_j × α_{k−j}
            _cauchy_cross(Y, 3, Y, 6, k, 1.0, 1.0, 1.0, work[k])
            _gradient_and_linear(p, Y, ALPHA, U_X, N_X, k, d0, d1, d2, acc, tmp)
            _gradient_and_linear(p, work, 0, U_Y, N_Y, k, d0, d1, d2, acc, tmp)  # β_k is work[k, 0:3]
        inv = 1.0 / (k + 1)
        for m in range(3):
            Y[k + 1, m] = (acc[m] * p[INV_INERTIA + m] + torque[m]) * inv
        for axis in range(3, n, 3):  # γ̇ = γ × ω (and α̇ = α × ω)
            tmp[0] = tmp[1] = tmp[2] = 0.0
            _cauchy_cross(Y, axis, Y, 0, k, 1.0, 1.0, 1.0, tmp)
            for m in range(3):
                Y[k + 1, axis + m] = tmp[m] * inv


@inline_kernel
def _gradient_and_linear(p, E, ie, iu, iN, k, d0, d1, d2, acc, tmp):
    """acc += U × e_k + N e × I e (k-th coefficients) for the axis e = E[:, ie:ie+3], U = p[iu:iu+3], N = p[iN]."""
    e0, e1, e2 = E[k, ie], E[k, ie + 1], E[k, ie + 2]
    acc[0] += p[iu + 1] * e2 - p[iu + 2] * e1
    acc[1] += p[iu + 2] * e0 - p[iu] * e2
    acc[2] += p[iu] * e1 - p[iu + 1] * e0
    if p[iN] != 0.0:
        _cauchy_pairs(E, ie, k, tmp)  # e × I e = −d ⊙ pairs of e
        acc[0] -= p[iN] * d0 * tmp[0]
        acc[1] -= p[iN] * d1 * tmp[1]
        acc[2] -= p[iN] * d2 * tmp[2]
