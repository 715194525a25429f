"""Taylor coefficients of a traced model (``model``), as generated straight-line code.

A model's equations (``model.trace``) are a straight-line program of scalar operations on the
state, time and constants. Every operation has a recurrence giving the k-th Taylor coefficient of
its result from the coefficients 0..k of its arguments and 0..k−1 of its own (Moore 1966; Jorba &
Zou, Exp. Math. 14, 2005, §3; Haro et al. 2016, §2.1). This module writes those recurrences out as
one generated ``cfunc``

    void f(double t, int64 order, double* Y, double* W, double* p)

which fills the state's coefficients Y[1..order] (rows of the state's size) from Y[0], with W
as scratch (``order`` rows of ``columns`` entries). It is called once per Taylor step: the
loops over the orders and over the Cauchy sums are inside the generated code, shaped like the
hand-written fixed-point kernel's (``fixed_point.taylor_coefficients``) and compiled with its fastmath flags (reassociation,
fused multiply-adds).

The lowering (``_Program``) puts every value in the form const + Σ c_i s_i: a sum of series s_i
(state components, time, products, results of nonlinear functions) with coefficients c_i that do
not depend on the state (the plugin's numbers, the inertia, and what is computed from them only,
once per call). So sums, differences and multiplications by numbers cost no series of their
own, a product of two state-dependent values is one Cauchy product of the values with their
numeric factors pulled out, and equal products are one series: the plugin's I_2 γ_1 γ_2 and
I_1 γ_2 γ_1 share the product γ_1 γ_2 (and the built-in (Iω) × ω's ω_1 ω_2 its terms), as the
built-in's code shares them. The Cauchy products that only depend on series computed earlier
in the order (products of the same depth) are summed in one loop over j, their operands in
adjacent columns of W, so that the compiler turns the sums into vector instructions (the built-in's
``taylor.run_vector`` does this by hand).

Like the right-hand side's kernel it reads the equations' numbers from the parameter array, so the
generated source depends on the equations' form only: it is compiled once per
form (cached on disk under a hash of the source, ``expression.load_generated``). The source
contains only what the lowering writes: local names it makes, indices into the arrays, the
literals 1.0, −1.0, 0.0 and integer exponents, and the names of ``math`` functions from a fixed
table — nothing a plugin spells.

Recurrences (x, y the arguments, f the result, a sum over j written Σ_j):
  ± and c·x: linear; x·y: Σ_{j=0..k} x_j y_{k−j};
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

from gyrolab.kernels.compiler import kernel_cache_dir  # noqa: F401  (numba's cache set up before the decorators)
from gyrolab.kernels.layout import TRACED_ADDRESS, TRACED_FIRST_CONSTANT
from gyrolab.kernels.expression import Expr, binary_power, load_generated
from gyrolab.kernels.model import TRACED, Model, traced_model

ZERO, ONE, MINUS_ONE = "0.0", "1.0", "-1.0"


class _Numbers:
    """The values that do not depend on the state, one local each (c0, c1, ...), computed once per call.

    Equal expressions share a local; 0 and ±1 are folded, so that a coefficient 1 costs no multiplication.
    """

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.names: dict[str, str] = {}

    def _local(self, expr: str) -> str:
        if expr not in self.names:
            self.names[expr] = f"c{len(self.names)}"
            self.lines.append(f"{self.names[expr]} = {expr}")
        return self.names[expr]

    def param(self, index: int) -> str:
        return self._local(f"p[{int(index)}]")

    def neg(self, a: str) -> str:
        return {ZERO: ZERO, ONE: MINUS_ONE, MINUS_ONE: ONE}.get(a) or self._local(f"-{a}")

    def add(self, a: str, b: str) -> str:
        if a == ZERO:
            return b
        if b == ZERO:
            return a
        return self._local(" + ".join(sorted((a, b))))

    def sub(self, a: str, b: str) -> str:
        return self.add(a, self.neg(b))

    def mul(self, a: str, b: str) -> str:
        if ZERO in (a, b):
            return ZERO
        if a == ONE:
            return b
        if b == ONE:
            return a
        if a == MINUS_ONE:
            return self.neg(b)
        if b == MINUS_ONE:
            return self.neg(a)
        return self._local(" * ".join(sorted((a, b))))

    def div(self, a: str, b: str) -> str:
        return a if b == ONE else self._local(f"{a} / {b}")

    def call(self, function: str, *args: Any) -> str:
        """``function`` (from the fixed tables below) of numbers (local names, or ints for a power)."""
        return self._local(function.format(*args))


class _Lin:
    """const + Σ coefficient · s_id: a value as a linear combination of series with numeric coefficients."""

    __slots__ = ("const", "terms")

    def __init__(self, const: str = ZERO, terms: tuple[tuple[int, str], ...] = ()) -> None:
        self.const = const
        self.terms = terms  # sorted by series id

    @property
    def key(self) -> tuple:
        return (self.const, self.terms)

    def expression(self, first: bool) -> str:
        """The value at order 0 (``first``: with the constant) or at order k ≥ 1 (the constant's coefficients vanish)."""
        parts = [self.const] if first and self.const != ZERO else []
        for i, c in self.terms:
            parts.append(f"s{i}" if c == ONE else f"-s{i}" if c == MINUS_ONE else f"{c} * s{i}")
        while len(parts) > 2:  # summed as a balanced tree: dependent additions log2(terms) deep, not terms deep
            parts = [f"({parts[i]} + {parts[i + 1]})" if i + 1 < len(parts) else parts[i]
                     for i in range(0, len(parts), 2)]
        return " + ".join(parts) or ZERO


class _Series:
    """A series the generated code computes order by order: a state component, time, a product or a function."""

    __slots__ = ("op", "args", "extra", "depth", "columns")

    def __init__(self, op: str, args: tuple[int, ...], extra: Any, depth: int) -> None:
        self.op = op  # "y", "time", "mul", or a function (see _VALUES)
        self.args = args  # operand ids (``_Program.operands``)
        self.extra = extra  # the state index of "y"; the exponent (a number's local) of "pow"
        self.depth = depth  # 0 for state and time; 1 + the deepest operand's for the others
        self.columns: list[int] = []  # its own columns of W (functions: the series and auxiliaries)


# order-0 values of the functions of a series (x, y: operand locals, e: a number)
_VALUES = {"sqrt": "math.sqrt({x})", "exp": "math.exp({x})", "log": "math.log({x})", "sin": "math.sin({x})",
           "cos": "math.cos({x})", "tan": "math.tan({x})", "tanh": "math.tanh({x})", "arctan": "math.atan({x})",
           "abs": "abs({x})", "div": "{x} / {y}", "arctan2": "math.atan2({x}, {y})", "pow": "{x} ** {e}"}
# the same of numbers (folded into ``_Numbers``)
_NUMBER_FUNCTIONS = {"sqrt": "math.sqrt({0})", "exp": "math.exp({0})", "log": "math.log({0})",
                     "sin": "math.sin({0})", "cos": "math.cos({0})", "tan": "math.tan({0})",
                     "tanh": "math.tanh({0})", "arctan": "math.atan({0})", "abs": "abs({0})",
                     "arctan2": "math.atan2({0}, {1})", "pow": "{0} ** {1}", "ipow": "{0} ** {1}"}

# order-k recurrences (k ≥ 1, r = k·M the row's start): {x}, {y} the operands' columns, {c} the result's,
# {d} an auxiliary's, {co} the cosine's (the sine's is {c}), {e} the exponent's local; rows 0..k of the operands
# and 0..k−1 of the result are in W
_STEPS = {
    "div": "s = W[r + {x}]\nfor j in range(k):\n    s -= W[j * M + {c}] * W[(k - j) * M + {y}]\nW[r + {c}] = s / W[{y}]",
    "sqrt": "s = W[r + {x}]\nfor j in range(1, k):\n    s -= W[j * M + {c}] * W[(k - j) * M + {c}]\n"
            "W[r + {c}] = s / (2.0 * W[{c}])",
    "exp": "s = 0.0\nfor j in range(1, k + 1):\n    s += j * W[j * M + {x}] * W[(k - j) * M + {c}]\nW[r + {c}] = s / k",
    "log": "s = 0.0\nfor j in range(1, k):\n    s += j * W[j * M + {c}] * W[(k - j) * M + {x}]\n"
           "W[r + {c}] = (W[r + {x}] - s / k) / W[{x}]",
    "sin": "s = 0.0\nq = 0.0\nfor j in range(1, k + 1):\n    s += j * W[j * M + {x}] * W[(k - j) * M + {co}]\n"
           "    q += j * W[j * M + {x}] * W[(k - j) * M + {c}]\nW[r + {c}] = s / k\nW[r + {co}] = -q / k",
    "tan": "s = 0.0\nfor j in range(1, k + 1):\n    s += j * W[j * M + {x}] * W[(k - j) * M + {d}]\nW[r + {c}] = s / k\n"
           "s = 0.0\nfor j in range(k + 1):\n    s += W[j * M + {c}] * W[(k - j) * M + {c}]\nW[r + {d}] = {sign}s",
    "arctan": "s = 0.0\nfor j in range(k + 1):\n    s += W[j * M + {x}] * W[(k - j) * M + {x}]\nW[r + {d}] = s\n"
              "s = k * W[r + {x}]\nfor j in range(1, k):\n    s -= j * W[j * M + {c}] * W[(k - j) * M + {d}]\n"
              "W[r + {c}] = s / (k * W[{d}])",
    # f = atan2(x, y): d = x² + y², f' d = y x' − x y'
    "arctan2": "s = 0.0\nfor j in range(k + 1):\n"
               "    s += W[j * M + {x}] * W[(k - j) * M + {x}] + W[j * M + {y}] * W[(k - j) * M + {y}]\n"
               "W[r + {d}] = s\ns = 0.0\nfor j in range(k):\n"
               "    s += (k - j) * (W[j * M + {y}] * W[(k - j) * M + {x}] - W[j * M + {x}] * W[(k - j) * M + {y}])\n"
               "for j in range(1, k):\n    s -= j * W[j * M + {c}] * W[(k - j) * M + {d}]\n"
               "W[r + {c}] = s / (k * W[{d}])",
    "pow": "s = 0.0\nfor j in range(k):\n    s += ({e} * (k - j) - j) * W[(k - j) * M + {x}] * W[j * M + {c}]\n"
           "W[r + {c}] = s / (k * W[{x}])",
    "abs": "W[r + {c}] = (1.0 if W[{x}] > 0.0 else -1.0 if W[{x}] < 0.0 else 0.0) * W[r + {x}]",
}
_STEPS["tanh"] = _STEPS["tan"]
# auxiliary series at order 0 ({c}: the result's column)
_AUXILIARY = {"tan": "1.0 + W[{c}] * W[{c}]", "tanh": "1.0 - W[{c}] * W[{c}]", "arctan": "1.0 + W[{x}] * W[{x}]",
              "arctan2": "W[{x}] * W[{x}] + W[{y}] * W[{y}]"}


_FUSE = ("contract",)  # a product and its sum may fuse (as the built-in's fastmath)

#: ``cauchy_sums``' vectors: at most _LANES lanes each (a power of two: the compiler splits other lengths into
#: pairs of lanes), at most _GROUP lanes summed in one loop (the accumulators stay in registers)
_LANES = 8
_GROUP = 64


def _chunks(start: int, n: int) -> list[tuple[int, int]]:
    """(first lane, lanes) of the vectors covering lanes start..start+n−1: powers of two, largest first."""
    out = []
    while n:
        size = min(_LANES, 1 << (n.bit_length() - 1))
        out.append((start, size))
        start, n = start + size, n - size
    return out


@intrinsic
def cauchy_sums(typingctx, W, k, columns, base, left, right):
    """The k-th coefficients of n products at once: Σ_{j=0..k} L_j ⊙ R_{k−j}, as an n-tuple.

    The products' first operands' coefficients sit side by side in W's rows (``columns`` wide) from column
    ``base``, their second operands' after them (from base + n); rows 0..k−1 are filled, row k is given as the
    n-tuples ``left`` and ``right`` and stored here, as vectors (a vector load of what scalar stores wrote
    would wait for them to reach the cache). The sums run in vectors, so the compiler emits packed fused
    multiply-adds (the built-in's ``taylor.run_vector`` does the same by hand): the terms of rows 1..k−1 first,
    alternately into two accumulators (two chains of dependent additions, half as long), then those with
    row k (j = 0 and j = k) from the registers it was packed in.
    """
    if not (isinstance(columns, types.IntegerLiteral) and isinstance(base, types.IntegerLiteral)):
        return None
    if not (isinstance(left, types.UniTuple) and isinstance(right, types.UniTuple) and left.count == right.count
            and isinstance(k, types.Integer)):
        return None
    n, stride, first = left.count, columns.literal_value, base.literal_value
    sig = types.UniTuple(types.float64, n)(W, k, columns, base, types.UniTuple(types.float64, n),
                                           types.UniTuple(types.float64, n))

    def codegen(context, builder, signature, args):
        b = builder
        i64, i32 = ir.IntType(64), ir.IntType(32)
        k_ = context.cast(b, args[1], signature.args[1], types.int64)
        one, two = ir.Constant(i64, 1), ir.Constant(i64, 2)
        newest = [[b.extract_value(args[a], i) for i in range(n)] for a in (4, 5)]

        def at(row, column, size):
            """The address of ``size`` lanes of row ``row`` (an i64 value) from ``column`` (an int)."""
            index = b.add(b.mul(row, ir.Constant(i64, stride)), ir.Constant(i64, column))
            return b.bitcast(b.gep(args[0], [index]), ir.VectorType(ir.DoubleType(), size).as_pointer())

        sums = []
        for group in range(0, n, _GROUP):
            chunks = _chunks(group, min(_GROUP, n - group))
            acc = {}
            newest_vectors = ({}, {})
            for lane, size in chunks:
                vec = ir.VectorType(ir.DoubleType(), size)
                for operand, column in ((0, first + lane), (1, first + n + lane)):  # row k, stored as vectors
                    v = ir.Constant(vec, ir.Undefined)
                    for i in range(size):
                        v = b.insert_element(v, newest[operand][lane + i], ir.Constant(i32, i))
                    b.store(v, at(k_, column, size), align=8)
                    newest_vectors[operand][lane] = v
                acc[lane] = [cgutils.alloca_once_value(b, ir.Constant(vec, [0.0] * size)) for _ in range(2)]

            def terms(j, which):
                for lane, size in chunks:
                    product = b.fmul(b.load(at(j, first + lane, size), align=8),
                                     b.load(at(b.sub(k_, j), first + n + lane, size), align=8), flags=_FUSE)
                    b.store(b.fadd(b.load(acc[lane][which]), product, flags=_FUSE), acc[lane][which])

            zero = ir.Constant(i64, 0)
            middle = b.sub(k_, one)  # rows 1..k−1, two at a time (none at k = 0)
            middle = b.select(b.icmp_signed(">", middle, zero), middle, zero)
            with cgutils.for_range(b, b.sdiv(middle, two)) as loop:
                j = b.add(b.mul(loop.index, two), one)
                terms(j, 0)
                terms(b.add(j, one), 1)
            with b.if_then(b.icmp_signed("!=", b.srem(middle, two), ir.Constant(i64, 0))):
                terms(middle, 0)
            for lane, size in chunks:
                a0 = b.fadd(b.load(acc[lane][0]), b.fmul(b.load(at(zero, first + lane, size), align=8),
                                                         newest_vectors[1][lane], flags=_FUSE), flags=_FUSE)
                a1 = b.fadd(b.load(acc[lane][1]), b.fmul(newest_vectors[0][lane],
                                                         b.load(at(zero, first + n + lane, size), align=8),
                                                         flags=_FUSE), flags=_FUSE)
                # (at k = 0, row 0 is row k: a0 = a1 = the one term L_0 R_0)
                total = b.select(b.icmp_signed("==", k_, zero), a0, b.fadd(a0, a1, flags=_FUSE))
                sums += [b.extract_element(total, ir.Constant(i32, i)) for i in range(size)]
        return context.make_tuple(b, signature.return_type, sums)

    return sig, codegen


class _Program:
    """A traced model's equations, lowered to series and their generated code."""

    def __init__(self, model: Model, first_constant: int = TRACED_FIRST_CONSTANT) -> None:
        self.first_constant = first_constant  # p's index of the trace's first number (0: a packed layout's own)
        self.numbers = _Numbers()
        self.series: list[_Series] = []
        self.found: dict[tuple, int] = {}  # a series' key (op and operands) → its id
        self.operands: list[_Lin] = []  # the values series are computed from, one local u<id> each
        self.operand_ids: dict[tuple, int] = {}
        values: dict[int, _Lin] = {}
        for i in sorted(model.live()):  # the program's nodes in order (each after its arguments), dead ones left out
            op, args = model.graph.nodes[i]
            values[i] = self._node(op, [values[a.index] if isinstance(a, Expr) else a for a in args])
        if len(model.rates) != model.size:
            raise ValueError(f"{model.what} has {len(model.rates)} rates for {model.size} state components")
        self.size = model.size
        self.rates = [values[v.index] if isinstance(v, Expr) else _Lin() for v in model.rates]

    # ---- values as linear combinations of series

    def _state(self, index: int) -> _Lin:
        return self._make("y", (), index, depth=0)

    def _make(self, op: str, operands: tuple[_Lin, ...], extra: Any, depth: int | None = None,
              pair: str | None = None) -> _Lin:
        """The series ``op`` of ``operands`` (one per distinct op, operands and extra), as a value."""
        ids = tuple(self._operand(v) for v in operands)
        key = (op, ids, extra)
        if key not in self.found:
            if depth is None:
                depth = 1 + max((self._depth(v) for v in operands), default=0)
            self.found[key] = len(self.series)
            self.series.append(_Series(op, ids, extra, depth))
            if pair is not None:  # sin and cos: computed together, the cosine the next series
                self.found[(pair, ids, extra)] = len(self.series)
                self.series.append(_Series(pair, ids, extra, depth))
        return _Lin(ZERO, ((self.found[key], ONE),))

    def _operand(self, value: _Lin) -> int:
        if value.key not in self.operand_ids:
            self.operand_ids[value.key] = len(self.operands)
            self.operands.append(value)
        return self.operand_ids[value.key]

    def _depth(self, value: _Lin) -> int:
        return max((self.series[i].depth for i, _ in value.terms), default=0)

    def _sum(self, values: list[_Lin], signs: list[int] | None = None) -> _Lin:
        n = self.numbers
        const, terms = ZERO, {}
        for value, sign in zip(values, signs or [1] * len(values)):
            const = n.add(const, value.const if sign > 0 else n.neg(value.const))
            for i, c in value.terms:
                c = c if sign > 0 else n.neg(c)
                terms[i] = n.add(terms[i], c) if i in terms else c
        return _Lin(const, tuple(sorted((i, c) for i, c in terms.items() if c != ZERO)))

    def _scale(self, value: _Lin, factor: str) -> _Lin:
        n = self.numbers
        return self._sum([_Lin(n.mul(value.const, factor), tuple((i, n.mul(c, factor)) for i, c in value.terms))])

    def _mul(self, a: _Lin, b: _Lin) -> _Lin:
        if not a.terms:
            return self._scale(b, a.const)
        if not b.terms:
            return self._scale(a, b.const)
        factor = ONE
        parts = []
        for v in (a, b):
            if v.const == ZERO and len(v.terms) == 1:  # c·s: the number is pulled out of the product
                factor = self.numbers.mul(factor, v.terms[0][1])
                v = _Lin(ZERO, ((v.terms[0][0], ONE),))
            parts.append(v)
        parts.sort(key=lambda v: v.key)  # x·y and y·x: one series
        return self._scale(self._make("mul", tuple(parts), None), factor)

    def _function(self, op: str, x: _Lin, y: _Lin | None = None, e: str | None = None) -> _Lin:
        args = (x,) if y is None else (x, y)
        if all(not v.terms for v in args):  # a number
            return _Lin(self.numbers.call(_NUMBER_FUNCTIONS[op], *[v.const for v in args], *([e] if e else [])))
        if op in ("sin", "cos"):
            sine = self._make("sin", args, None, pair="cos")
            if op == "sin":
                return sine
            return _Lin(ZERO, ((sine.terms[0][0] + 1, ONE),))
        return self._make(op, args, e)

    def _node(self, op: str, a: list[Any]) -> _Lin:
        n = self.numbers
        if op == "y":
            return self._state(a[0])
        if op == "time":
            return self._make("time", (), None, depth=0)
        if op == "const":
            return _Lin(n.param(self.first_constant + a[0]))
        if op == "add":
            return self._sum(a)
        if op == "sub":
            return self._sum(a, [1, -1])
        if op == "neg":
            return self._sum(a, [-1])
        if op == "mul":
            return self._mul(*a)
        if op == "div":
            if not a[1].terms:
                return self._scale(a[0], n.div(ONE, a[1].const))
            return self._function("div", a[0], a[1])
        if op == "ipow":
            return self._ipow(a[0], a[1])
        if op == "powx":
            base, exponent = a
            if not exponent.terms:
                return self._function("pow", base, e=exponent.const)
            return self._function("exp", self._mul(exponent, self._function("log", base)))
        if op == "arctan2":
            return self._function("arctan2", a[0], a[1])
        return self._function(op, a[0])

    def _ipow(self, x: _Lin, power: int) -> _Lin:
        """x^n by binary powering (Cauchy products: no division by x_0), 1/x^|n| for n < 0."""
        if power == 0:
            return _Lin(ONE)
        if not x.terms:
            return _Lin(self.numbers.call(_NUMBER_FUNCTIONS["ipow"], x.const, int(power)))
        result = binary_power(x, abs(power), self._mul)
        return self._function("div", _Lin(ONE), result) if power < 0 else result

    # ---- the generated code

    def source(self) -> tuple[str, int]:
        """The cfunc's source and the number of columns of W."""
        depth = max((s.depth for s in self.series), default=0)
        columns = 0
        slots: dict[int, list[tuple[int, int]]] = {}  # a depth's products: (series, first operand's column)
        operand_column: dict[int, int] = {}  # operands of functions: their series' columns
        for d in range(1, depth + 1):
            products = [i for i, s in enumerate(self.series) if s.depth == d and s.op == "mul"]
            slots[d] = [(i, columns + k) for k, i in enumerate(products)]
            columns += 2 * len(products)  # the first operands side by side, then the second
        for i, s in enumerate(self.series):
            if s.op in ("y", "time", "mul", "cos"):
                continue
            for u in s.args:
                if u not in operand_column:
                    operand_column[u] = columns
                    columns += 1
            s.columns = [columns]
            columns += 1
            if s.op == "sin":  # the cosine's column
                self.series[i + 1].columns = [columns]
                columns += 1
            elif s.op in _AUXILIARY:
                s.columns.append(columns)
                columns += 1
        self.columns = max(columns, 1)
        lines = [*self.numbers.lines, "# order 0"]
        lines += self._order(True, depth, slots, operand_column)
        lines += ["for k in range(1, order):", "    r = k * M", "    inv = 1.0 / (k + 1)"]
        lines += [f"    {line}" for line in self._order(False, depth, slots, operand_column)]
        text = _HEADER.format(columns=self.columns, size=self.size) + "".join(f"    {x}\n" for x in lines)
        return text, self.columns

    def _order(self, first: bool, depth: int, slots: dict[int, list[tuple[int, int]]],
               operand_column: dict[int, int]) -> list[str]:
        """The statements of order 0 (``first``) or of order k ≥ 1 (inside the loop over k)."""
        lines = []
        row = "" if first else "r + "
        known: set[int] = set()

        def operand(u: int) -> str:
            if u not in known:
                known.add(u)
                lines.append(f"u{u} = {self.operands[u].expression(first)}")
            return f"u{u}"

        for i, s in enumerate(self.series):
            if s.op == "y" and first:  # (at order k ≥ 1, the previous order left them in s<i>)
                lines.append(f"s{i} = Y[{s.extra}]")
            elif s.op == "time":
                lines.append(f"s{i} = t" if first else f"s{i} = 1.0 if k == 1 else 0.0")
        for d in range(1, depth + 1):
            products = slots[d]
            pairs = [self.series[i].args for i, _ in products]
            left, right = [operand(x) for x, _ in pairs], [operand(y) for _, y in pairs]
            if products:  # the depth's Cauchy sums at once, in vectors (``cauchy_sums`` stores row k's operands)
                names = ", ".join(f"s{i}" for i, _ in products)
                lines.append(f"{names}, = cauchy_sums(W, {0 if first else 'k'}, {self.columns}, {products[0][1]}, "
                             f"({', '.join(left)},), ({', '.join(right)},))")
            for i, s in enumerate(self.series):
                if s.depth != d or s.op in ("mul", "cos"):
                    continue
                cols = {"c": s.columns[0]}
                for name, u in zip("xy", s.args):
                    lines.append(f"W[{row}{operand_column[u]}] = {operand(u)}")
                    cols[name] = operand_column[u]
                if s.op == "sin":
                    cols["co"] = self.series[i + 1].columns[0]
                elif len(s.columns) > 1:
                    cols["d"] = s.columns[1]
                if first:
                    value = _VALUES[s.op].format(**{k: f"u{s.args[n]}" for n, k in enumerate("xy") if n < len(s.args)},
                                                 e=s.extra)
                    lines.append(f"W[{cols['c']}] = {value}")
                    if s.op == "sin":
                        lines.append(f"W[{cols['co']}] = math.cos(u{s.args[0]})")
                    elif s.op in _AUXILIARY:
                        lines.append(f"W[{cols['d']}] = {_AUXILIARY[s.op].format(**cols)}")
                else:
                    sign = "" if s.op == "tan" else "-"
                    lines += _STEPS[s.op].format(**cols, e=s.extra, sign=sign).split("\n")
                lines.append(f"s{i} = W[{row}{cols['c']}]")
                if s.op == "sin":
                    lines.append(f"s{i + 1} = W[{row}{cols['co']}]")
        state = {s.extra: i for i, s in enumerate(self.series) if s.op == "y"}
        for m, rate in enumerate(self.rates):  # the state's next coefficients
            value = rate.expression(first)
            lines.append(f"n{m} = {value}" if first else f"n{m} = ({value}) * inv")
        for m in range(len(self.rates)):  # stored, and kept for the next order (no reload)
            lines.append(f"Y[N + {m}] = n{m}" if first else f"Y[(k + 1) * N + {m}] = n{m}")
            if m in state:
                lines.append(f"s{state[m]} = n{m}")
        return lines


_HEADER = '''"""Generated by gyrolab: Taylor coefficients of a system's traced equations (gyrolab.kernels.taylor_series)."""
import math

import numba
from numba import types

from gyrolab.kernels.taylor_series import cauchy_sums

M = {columns}
N = {size}
_P = types.CPointer(types.float64)
SIGNATURE = types.void(types.float64, types.int64, _P, _P, _P)


@numba.cfunc(SIGNATURE, cache=True, error_model="numpy", fastmath={{"reassoc", "contract", "nsz"}})
def kernel(t, order, Y, W, p):
'''


def source(model: Model) -> tuple[str, int]:
    """The Taylor cfunc's source for a traced model, and W's columns."""
    return _Program(model).source()


#: the Taylor kernel's (address, work columns) by the address of its model's right-hand side kernel
_KERNELS: dict[int, tuple[float, float]] = {}


def ready(compiled: Any, rows: np.ndarray | None = None) -> bool:
    """Whether ``taylor`` can integrate a compiled model: the hand-written fixed point and every traced model.

    For a traced model this compiles (or loads) its Taylor kernel on first need and writes its address
    into ``compiled.params`` (and into every row of ``rows``, a batch's per-trajectory parameters).
    Nothing compiles before: most runs never use taylor, and a Taylor kernel's first compilation costs
    0.2–1 s (the reference problem's torque: 0.2 s; one with sqrt, powers, sin and exp: 1.2 s).
    """
    if compiled.model != TRACED:
        return compiled.model == 0  # models.FIXED_POINT (not imported: models imports this module)
    p = compiled.params
    if p[p.size - 4] == 0.0:
        address = int(p[TRACED_ADDRESS])
        if address not in _KERNELS:  # once per form and process (the rhs kernel's address names the form)
            model = traced_model(compiled)
            text, columns = source(model)
            kernel = load_generated(text, "gyrolab_taylor", f"{model.what} (Taylor)")
            _KERNELS[address] = (float(kernel.address), float(columns))
        p[p.size - 4:p.size - 2] = _KERNELS[address]
    if rows is not None:
        rows[:, -4:-2] = p[p.size - 4:p.size - 2]
    return True


#: W (``order`` rows of the kernel's columns) lives on the caller's stack up to this many doubles (128 KiB: a
#: quarter of the smallest default thread stack, macOS's 512 KiB, for a batch's threads), on the heap beyond:
#: an allocation per step (np.empty) would cost as much as a low order's Cauchy sums
_STACK_DOUBLES = 16384


@intrinsic
def _call(typingctx, address, t, order, size, Y, p):
    """Call ``void f(double t, int64 order, double* Y, double* W, double* p)`` at ``address`` with W a scratch
    array of ``size`` doubles, freed when the call returns: on the stack up to ``_STACK_DOUBLES``, else on
    numba's heap. (Code here, not in the calling kernel: an allocation or any call that takes the arrays
    there, even on a branch not taken, costs the kernel their reference counting, ~12 ns a step.)"""
    sig = types.void(types.int64, types.float64, types.int64, types.int64, Y, p)

    def codegen(context, builder, signature, args):
        b = builder
        address_, t_, order_, size_, Y_, p_ = args
        double, i64 = ir.DoubleType(), ir.IntType(64)
        double_ptr, byte_ptr = double.as_pointer(), ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [double, i64, double_ptr, double_ptr, double_ptr])
        y, pp = [b.bitcast(cgutils.create_struct_proxy(ty)(context, b, value=v).data, double_ptr)
                 for ty, v in ((signature.args[4], Y_), (signature.args[5], p_))]
        # stacksave/stackrestore: the stack's allocation is freed at once, not when the calling kernel returns
        save = cgutils.get_or_insert_function(b.module, ir.FunctionType(byte_ptr, []), "llvm.stacksave")
        restore = cgutils.get_or_insert_function(b.module, ir.FunctionType(ir.VoidType(), [byte_ptr]),
                                                 "llvm.stackrestore")
        small = b.icmp_signed("<=", size_, ir.Constant(i64, _STACK_DOUBLES))
        saved = b.call(save, [])
        with b.if_else(small) as (on_stack, on_heap):
            with on_stack:
                stack_w = b.alloca(double, size=size_)
                stack_block = b.block
            with on_heap:
                heap_w = b.bitcast(context.nrt.allocate(b, b.mul(size_, ir.Constant(i64, 8))), double_ptr)
                heap_block = b.block
        W = b.phi(double_ptr)
        W.add_incoming(stack_w, stack_block)
        W.add_incoming(heap_w, heap_block)
        b.call(b.inttoptr(address_, fnty.as_pointer()), [t_, order_, y, W, pp])
        with b.if_then(b.not_(small)):
            context.nrt.free(b, b.bitcast(W, byte_ptr))
        b.call(restore, [saved])
        return context.get_dummy_value()

    return sig, codegen


@numba.njit(cache=True, error_model="numpy", inline="always")
def coefficients(p, Y, order, work, t):
    """Fill Y[1..order] from Y[0] for a traced model (``models.TRACED``): one call of the generated kernel
    (``source``), whose address ``ready`` wrote at p[-4] and its work columns at p[-3] (``layout``). ``work`` is
    unused (the hand-written fixed-point kernels' β series)."""
    address = int(p[p.size - 4])
    if address == 0:  # the Taylor kernel was not compiled (``ready`` not called): no series, not a crash
        Y[1:] = np.nan
        return
    _call(address, t, order, order * int(p[p.size - 3]), Y, p)