"""Taylor coefficients of a traced model (``model``), as generated code: one trajectory, its series in vector lanes.

A model's equations (``model.trace``) are a straight-line program of scalar operations on the state, time and
constants. Every operation has a recurrence giving the k-th Taylor coefficient of its result from the coefficients
0..k of its arguments and 0..k−1 of its own (Moore 1966; Jorba & Zou, Exp. Math. 14, 2005, §3; Haro et al. 2016,
§2.1; the functions' in ``recurrences``). This module writes those recurrences out as one generated ``cfunc``

    void f(double t, int64 order, double* Y, double* W, double* p)

which fills the state's coefficients Y[1..order] (rows of the state's size) from Y[0], with W as scratch (``order``
rows of ``columns`` entries). It is called once per Taylor step: the loop over the orders and the Cauchy sums are
inside the generated code.

The lowering (``_Program``) puts every value in the form const + Σ c_i s_i: a sum of series s_i (state components,
time, products, results of nonlinear functions) with coefficients c_i that do not depend on the state (the
equations' numbers, the inertia, and what is computed from them only, once per call). So sums, differences and
multiplications by numbers cost no series of their own, a product of two state-dependent values is one Cauchy
product of the values with their numeric factors pulled out, and equal products are one series: the fixed point's
I_2 ω_1 ω_2 and I_1 ω_2 ω_1 share the product ω_1 ω_2.

The emitter (``_emit``) writes LLVM IR whose vector lanes are the program's series: the state's components in one
vector (padded to a power of two: the fixed point's six in one ``<8 x double>``), the products of one depth in
others (``pieces``), so an order's work is a few vector operations: the products' operands gathered from the
state's and the products' lanes by shuffles (``gather``), their Cauchy sums Σ_j L_j ⊙ R_{k−j} by pairs (j, k − j)
in fused multiply-adds, and the rates' linear combinations as sums of shuffled lanes times coefficient vectors, the
1/(k + 1) folded into the coefficients (off the chain of dependent operations from one order to the next).
Functions of series (sin, sqrt, division, ...) run their recurrences in a lane of their own
(``recurrences.Functions``). Its speed against the hand-written fixed-point kernel it replaced: docs/performance.md.

Like the right-hand side's kernel it reads the equations' numbers from the parameter array, so the generated source
depends on the equations' form only: it is compiled once per form (cached on disk under a hash of the source, which
names this emitter's own hash, ``expression.generated_module``). The source contains only what the lowering writes:
local names it makes, indices into the arrays, the literals 1.0, −1.0, 0.0 and integer exponents, and the names of
``math`` functions from a fixed table — nothing a plugin spells. Time's series: t_0 = t, t_1 = 1. x^n (an integer
n) is repeated Cauchy products (no division, so x_0 = 0 is fine), 1/x^|n| for n < 0; x^y (y on the state) is
exp(y log x). The Taylor kernel compiles when a run first needs it (``ready``), not with the right-hand side's.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.kernels import simd
from gyrolab.kernels.compiler import kernel_cache_dir  # noqa: F401  (numba's cache set up before the decorators)
from gyrolab.kernels.expression import BINARY, UNARY, Expr, binary_power, generated_module
from gyrolab.kernels.layout import TRACED_ADDRESS, TRACED_FIRST_CONSTANT
from gyrolab.kernels.model import Model, traced_model
from gyrolab.kernels.recurrences import Functions, work_columns

ZERO, ONE, MINUS_ONE = "0.0", "1.0", "-1.0"
#: lanes of the widest vector the series uses (AVX-512's; an AVX2 CPU runs each as two)
VECTOR = 8
#: products whose Cauchy sums share one loop (their accumulators and operands stay in the vector registers)
GROUP = 32
#: the rates' aligned layout of the products (``_aligned``) is taken while it needs at most this many times the lanes
#: of the compact one (the fixed point: 16 lanes for 12 products, aligned: 8 % faster a step than compact)
ALIGNED_COST = 1.4
#: lanes up to which a Cauchy sum runs in two accumulators (two chains of dependent additions, half as long); with
#: more, the registers are better spent on the operands' loads
TWIN = 16
#: the generated series' source names the emitters' hash: an emitter change compiles the series anew
_EMITTER = hashlib.sha256(b"".join(Path(__file__).with_name(name).read_bytes()
                                   for name in ("taylor_series.py", "recurrences.py"))).hexdigest()[:12]
_P = types.CPointer(types.float64)
_PAD = object()  # a gathered lane that may hold any value (a padding lane)


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


class _Series:
    """A series the generated code computes order by order: a state component, time, a product or a function."""

    __slots__ = ("op", "args", "extra", "depth", "columns")

    def __init__(self, op: str, args: tuple[int, ...], extra: Any, depth: int) -> None:
        self.op = op  # "y", "time", "mul", or a function (see _VALUES)
        self.args = args  # operand ids (``_Program.operands``)
        self.extra = extra  # the state index of "y"; the exponent (a number's local) of "pow"
        self.depth = depth  # 0 for state and time; 1 + the deepest operand's for the others
        self.columns: list[int] = []  # its own columns of W (functions: the series and auxiliaries)


# the functions of numbers (folded into ``_Numbers``; ``series_dd``'s, in double)
NUMBER_FUNCTIONS = {**UNARY, **BINARY, "pow": "{0} ** {1}", "ipow": "{0} ** {1}", "powx": "{0} ** {1}"}


class Lowering:
    """What this module's lowering (``_Program``, in double) and ``series_dd``'s (in double-double) share: the walk
    over a traced model's nodes, each value made from its arguments' (``_node``), and a series' integer power."""

    def _lower(self, model: Model, zero: Any) -> list:
        """The values of the model's rates (``zero`` for a rate of no node)."""
        values: dict[int, Any] = {}
        for i in sorted(model.live()):  # the program's nodes in order (each after its arguments), dead ones left out
            op, args = model.graph.nodes[i]
            values[i] = self._node(op, [values[a.index] if isinstance(a, Expr) else a for a in args])
        return [values[v.index] if isinstance(v, Expr) else zero for v in model.rates]

    def _power(self, x: Any, n: int, one: Any) -> Any:
        """x^n by binary powering (Cauchy products: no division by x_0), 1/x^|n| for n < 0; ``one`` the number 1."""
        if n == 0:
            return one
        result = binary_power(x, abs(n), self._mul)
        return self._divide(one, result) if n < 0 else result


class _Program(Lowering):
    """A traced model's equations, lowered to series and their generated code."""

    def __init__(self, model: Model, first_constant: int = TRACED_FIRST_CONSTANT) -> None:
        self.first_constant = first_constant  # p's index of the trace's first number (0: a packed layout's own)
        self.numbers = _Numbers()
        self.series: list[_Series] = []
        self.found: dict[tuple, int] = {}  # a series' key (op and operands) → its id
        self.operands: list[_Lin] = []  # the values series are computed from, one local u<id> each
        self.operand_ids: dict[tuple, int] = {}
        self.rates = self._lower(model, _Lin())
        if len(model.rates) != model.size:
            raise ValueError(f"{model.what} has {len(model.rates)} rates for {model.size} state components")
        self.size = model.size

    # ---- values as linear combinations of series

    def _make(self, op: str, operands: tuple[_Lin, ...], extra: Any, depth: int | None = None,
              pair: str | None = None) -> _Lin:
        """The series ``op`` of ``operands`` (one per distinct op, operands and extra), as a value."""
        ids = tuple(self._operand(v) for v in operands)
        key = (op, ids, extra)
        if key not in self.found:
            if depth is None:
                depth = 1 + max((self.series[i].depth for v in operands for i, _ in v.terms), default=0)
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
            return _Lin(self.numbers.call(NUMBER_FUNCTIONS[op], *[v.const for v in args], *([e] if e else [])))
        if op in ("sin", "cos"):
            sine = self._make("sin", args, None, pair="cos")
            if op == "sin":
                return sine
            return _Lin(ZERO, ((sine.terms[0][0] + 1, ONE),))
        return self._make(op, args, e)

    def _node(self, op: str, a: list[Any]) -> _Lin:
        n = self.numbers
        if op == "y":
            return self._make("y", (), a[0], depth=0)
        if op == "time":
            return self._make("time", (), None, depth=0)
        if op == "const":
            return _Lin(n._local(f"p[{int(self.first_constant + a[0])}]"))
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
            return self._divide(a[0], a[1])
        if op == "ipow":
            if a[0].terms or a[1] == 0:
                return self._power(a[0], a[1], _Lin(ONE))
            return _Lin(n.call(NUMBER_FUNCTIONS["ipow"], a[0].const, int(a[1])))
        if op == "powx":
            base, exponent = a
            if not exponent.terms:
                return self._function("pow", base, e=exponent.const)
            return self._function("exp", self._mul(exponent, self._function("log", base)))
        if op == "arctan2":
            return self._function("arctan2", a[0], a[1])
        return self._function(op, a[0])

    def _divide(self, x: _Lin, y: _Lin) -> _Lin:
        return self._function("div", x, y)


def plan(model: Any, first_constant: int = TRACED_FIRST_CONSTANT) -> dict:
    """A model's lowered program (``_Program``) as plain data, for the emitters (this module's and the batch lanes').

    Numbers are given as indices into ``names`` (the locals the ``lines`` compute from the parameter array p) or the
    literals "0.0", "1.0", "-1.0"; a linear combination as (constant, ((series, coefficient), ...)); series as
    (op, operands, extra, depth), extra the state index of "y" and the exponent's number of "pow".
    """
    program = _Program(model, first_constant)
    rows: dict[str, int] = {}

    def number(name: str) -> Any:
        return name if name in (ZERO, ONE, MINUS_ONE) else rows.setdefault(name, len(rows))

    def combination(value: _Lin) -> tuple:
        return number(value.const), tuple((i, number(c)) for i, c in value.terms)

    series = [(s.op, s.args, number(s.extra) if s.op == "pow" else s.extra, s.depth) for s in program.series]
    operands = [combination(u) for u in program.operands]
    rates = [combination(r) for r in program.rates]
    return {"size": program.size, "series": series, "operands": operands, "rates": rates, "names": list(rows),
            "lines": program.numbers.lines}


def pieces(n: int) -> list[tuple[int, int]]:
    """(first lane, lanes) of the vectors holding n lanes: VECTOR lanes each, the last rounded up to a power of two
    (its top lanes padding, never stored where another row starts): one vector where an exact split takes two. A
    vector of another length is split by the compiler into scalars."""
    out, lo = [], 0
    while lo < n:
        width = min(VECTOR, 1 << (n - lo - 1).bit_length())
        out.append((lo, width))
        lo += width
    return out


def _padded(n: int) -> int:
    return sum(width for _, width in pieces(n))


def _groups(program: dict) -> dict[int, list[list[int | None]]]:
    """Each depth's products in groups (a group's vector lane l is its product l; None: a padding lane).

    Where it costs few lanes, depth 1 is laid out aligned with the rates (``_aligned``); otherwise each depth's
    products side by side, at most GROUP a group."""
    series = program["series"]
    depth = max((s[3] for s in series), default=0)
    out = {}
    for d in range(1, depth + 1):
        products = [i for i, s in enumerate(series) if s[3] == d and s[0] == "mul"]
        compact = [products[g:g + GROUP] for g in range(0, len(products), GROUP)]
        aligned = _aligned(program, products) if d == 1 else None
        lanes = (lambda groups: sum(_padded(len(g)) for g in groups))
        out[d] = aligned if aligned is not None and lanes(aligned) <= ALIGNED_COST * lanes(compact) else compact
    return out


def _aligned(program: dict, products: list[int]) -> list[list[int | None]] | None:
    """Groups whose lane m holds a product the rate of state component m reads (its t-th product term in group
    t), then the products no rate reads, side by side: the rates' sums then add whole vectors, with no shuffle
    between the Cauchy sums and the next order (the hand-written fixed-point kernel's layout, found for any
    model). None when a rate reads a product twice or more than GROUP lanes would be needed."""
    size, placed, groups = program["size"], set(), []
    reads = [[i for i, _ in terms if i in products] for _, terms in program["rates"]]
    for t in range(max((len(r) for r in reads), default=0)):
        group = []
        for m in range(size):
            i = reads[m][t] if t < len(reads[m]) else None
            if i in placed:
                return None
            group.append(i)
            placed.add(i)
        groups.append(group)
    rest = [i for i in products if i not in placed]
    groups += [rest[g:g + GROUP] for g in range(0, len(rest), GROUP)]
    return groups if all(_padded(len(g)) <= GROUP for g in groups) else None


def layout(program: dict) -> tuple[dict[tuple, int], int]:
    """W's columns and their number: each group of products' first operands ("L", depth, group) and second operands
    ("R", ...) side by side (padded to whole vectors); then the functions' operands ("u", operand), results ("f",
    series, 0) and cosines or auxiliary series ("f", series, 1)."""
    column: dict[tuple, int] = {}
    width = 0
    for d, groups in _groups(program).items():
        for g, products in enumerate(groups):
            column[("L", d, g)] = width
            column[("R", d, g)] = width + _padded(len(products))
            width += 2 * _padded(len(products))
    functions = work_columns(program["series"], ("y", "time", "cos", "mul"), width)
    return {**column, **functions}, max(width + len(functions), 1)


def source(program: dict) -> str:
    """The generated module: ``kernel``, the numbers computed from p once per call, then the series."""
    shape = {k: program[k] for k in ("size", "series", "operands", "rates")}
    shape["numbers"] = len(program["names"])
    body = "".join(f"    {line}\n" for line in program["lines"])
    names = ", ".join(program["names"]) or "0.0"
    return _HEADER.format(emitter=_EMITTER, plan=repr(shape)) + body + f"    _series(t, order, Y, W, ({names},))\n"


_HEADER = '''"""Generated by gyrolab: Taylor coefficients of a system's traced equations (gyrolab.kernels.taylor_series)."""
import math

import numba
from numba import types

from gyrolab.kernels.taylor_series import series_intrinsic

EMITTER = "{emitter}"
PLAN = {plan}
_P = types.CPointer(types.float64)
_series = series_intrinsic(PLAN)


@numba.cfunc(types.void(types.float64, types.int64, _P, _P, _P), cache=True, error_model="numpy")
def kernel(t, order, Y, W, p):
'''


def series_intrinsic(program: dict) -> Any:
    """The intrinsic ``(t, order, Y, W, numbers)`` (numbers: the tuple of ``names``' values) that fills Y[1..order]
    from Y[0] (``_emit``)."""

    @intrinsic
    def _series(typingctx, t, order, Y, W, numbers):
        sig = types.void(types.float64, types.int64, _P, _P, numbers)

        def codegen(context, builder, signature, args):
            _Emitter(builder, program, args[4]).series(*args[:4])
            return context.get_dummy_value()

        return sig, codegen

    return _series


class _Emitter:
    """The series' IR (see the module's docstring). A value at the current order is a list of vectors (``pieces``);
    ``where`` maps a series to its (vector, lane)."""

    def __init__(self, b: ir.IRBuilder, program: dict, numbers: Any) -> None:
        self.b, self.program = b, program
        self.column, self.width = layout(program)
        self.numbers = [b.extract_value(numbers, i) for i in range(program["numbers"])]
        self.i32, self.i64 = ir.IntType(32), ir.IntType(64)

    # ---- small pieces of IR

    @staticmethod
    def vec(n: int) -> ir.VectorType:
        return ir.VectorType(ir.DoubleType(), n)

    def int(self, x: int) -> ir.Constant:
        return ir.Constant(self.i64, x)

    def number(self, ref: Any) -> Any:
        return ir.Constant(ir.DoubleType(), float(ref)) if isinstance(ref, str) else self.numbers[ref]

    def splat(self, scalar_vector: Any, n: int) -> Any:
        """n lanes of a <1 x double>'s value."""
        return self.b.shuffle_vector(scalar_vector, ir.Constant(scalar_vector.type, ir.Undefined),
                                     ir.Constant(ir.VectorType(self.i32, n), [0] * n))

    def address(self, base: Any, index: Any, n: int) -> Any:
        return self.b.bitcast(self.b.gep(base, [index]), self.vec(n).as_pointer())

    def at(self, row: Any, column: int) -> Any:
        return self.b.add(self.b.mul(row, self.int(self.width)), self.int(column))

    def load(self, base: Any, index: Any, n: int) -> list:
        return [self.b.load(self.address(base, self.b.add(index, self.int(lo)), w), align=8) for lo, w in pieces(n)]

    def store(self, value: list, base: Any, index: Any, n: int) -> None:
        """The first n lanes of ``value`` (padding lanes are not stored: rows of Y are n wide), in vectors whose
        lengths are powers of two."""
        b = self.b
        for (lo, w), v in zip(pieces(n), value):
            used, sub = min(w, n - lo), 0
            while sub < used:
                size = 1 << (used - sub).bit_length() - 1
                part = v if size == w else b.shuffle_vector(v, ir.Constant(v.type, ir.Undefined), ir.Constant(
                    ir.VectorType(self.i32, size), list(range(sub, sub + size))))
                b.store(part, self.address(base, b.add(index, self.int(lo + sub)), size), align=8)
                sub += size

    @staticmethod
    def locate(value: list, lane: int) -> tuple:
        for v in value:
            if lane < v.type.count:
                return v, lane
            lane -= v.type.count
        raise IndexError(lane)

    # ---- gathers and linear combinations

    def gather(self, sources: list) -> list:
        """A value whose lane l is sources[l] ((vector, lane), None for 0, or _PAD for any value)."""
        return [self._gather(sources[lo:lo + w], w) for lo, w in pieces(len(sources))]

    def _gather(self, sources: list, n: int) -> Any:
        """One vector of n lanes: a shuffle per source vector (none where a vector's lanes are already in place),
        merged by pairs (a balanced tree: the merges of three sources are two deep, not three); zeros by a blend.
        Lanes beyond ``sources`` are padding (any value)."""
        b = self.b
        by_vector: dict[int, tuple[Any, list]] = {}
        zeros = []
        for lane, source in enumerate(sources):
            if source is None:
                zeros.append(lane)
            elif source is not _PAD:
                by_vector.setdefault(id(source[0]), (source[0], []))[1].append((lane, source[1]))
        mask = ir.VectorType(self.i32, n)
        parts = []  # (vector of n lanes, the lanes it holds)
        for v, lanes in by_vector.values():
            pick = list(range(n)) if v.type.count == n else [0] * n
            for lane, source_lane in lanes:
                pick[lane] = source_lane
            same = v.type.count == n and pick == list(range(n))
            parts.append((v if same else b.shuffle_vector(v, ir.Constant(v.type, ir.Undefined),
                                                           ir.Constant(mask, pick)), {lane for lane, _ in lanes}))
        while len(parts) > 1:
            merged = [(b.shuffle_vector(x, y, ir.Constant(mask, [n + lane if lane in ys else lane for lane in range(n)])),
                       xs | ys) for (x, xs), (y, ys) in zip(parts[0::2], parts[1::2])]
            parts = merged + parts[len(merged) * 2:]
        zero = ir.Constant(self.vec(n), [0.0] * n)
        if not parts:
            return zero
        if not zeros:
            return parts[0][0]
        keep = ir.Constant(ir.VectorType(ir.IntType(1), n), [int(lane not in zeros) for lane in range(n)])
        return b.select(keep, parts[0][0], zero)

    def constants(self, refs: list, scale: Any = None) -> list:
        """The value whose lanes are the numbers ``refs`` (times ``scale``, a <1 x double>, if given). Loop-invariant
        but for the scale: the compiler hoists them out of the loop over orders."""
        out = []
        for lo, w in pieces(len(refs)):
            v = ir.Constant(self.vec(w), [0.0] * w)
            for lane, ref in enumerate(refs[lo:lo + w]):
                v = self.b.insert_element(v, self.number(ref), ir.Constant(self.i32, lane))
            out.append(v if scale is None else self.b.fmul(v, self.splat(scale, w)))
        return out

    def combinations(self, values: list, where: dict, only_first: Any, scale: Any = None) -> list:
        """The value whose lane m is the linear combination values[m] = (constant, ((series, coefficient), ...)) at
        this order (its constant at order 0 only; None: a padding lane), times ``scale`` (a <1 x double>, applied to
        the coefficients: off the chain of dependent operations from one order to the next).

        The terms are summed by slots: a slot takes from one source vector (the state, a group of products, a
        function's lane) one term of every lane that reads it, so a slot is one gathered vector — no shuffle at all
        where the lanes are aligned (``_aligned``) — times one coefficient vector; the slots are summed as a
        balanced tree."""
        b, n = self.b, len(values)
        slots: dict[tuple, list] = {}
        for lane, value in enumerate(values):
            seen: dict[int, int] = {}
            for i, ref in (value or (ZERO, ()))[1]:
                source = where[i]
                count = seen[id(source[0])] = seen.get(id(source[0]), -1) + 1
                slots.setdefault((id(source[0]), count), []).append((lane, source, ref))
        filler = [_PAD if value is None else None for value in values]
        parts = []
        for entries in slots.values():
            sources, refs = list(filler), [ZERO] * n
            for lane, source, ref in entries:
                sources[lane], refs[lane] = source, ref
            x = self.gather(sources)
            if scale is None and set(refs) <= {ONE, ZERO}:
                parts.append(x)
            elif scale is None and set(refs) <= {MINUS_ONE, ZERO}:
                parts.append([b.fneg(v) for v in x])
            else:
                parts.append([b.fmul(c, v, flags=simd.FUSE) for c, v in zip(self.constants(refs, scale), x)])
        consts = [ZERO if value is None else value[0] for value in values]
        if any(c != ZERO for c in consts):
            parts.append([b.fmul(c, self.splat(only_first, c.type.count), flags=simd.FUSE)
                          for c in self.constants(consts, scale)])
        while len(parts) > 1:
            parts = [[b.fadd(x, y, flags=simd.FUSE) for x, y in zip(parts[i], parts[i + 1])]
                     if i + 1 < len(parts) else parts[i] for i in range(0, len(parts), 2)]
        return parts[0] if parts else [ir.Constant(self.vec(w), [0.0] * w) for _, w in pieces(n)]

    # ---- the series

    def series(self, t: Any, order: Any, Y: Any, W: Any) -> None:
        """For k = 0 … order − 1: each depth's products (operands gathered and stored in W, Cauchy sums) and
        functions, then Y[k + 1] = (the rates' combinations) / (k + 1)."""
        b, program, column = self.b, self.program, self.column
        double = ir.DoubleType()
        size, series, operands = program["size"], program["series"], program["operands"]
        Y, W = (b.bitcast(x, double.as_pointer()) for x in (Y, W))
        newest = []  # the state's coefficients of the current order, in registers from one order to the next
        for lo, w in pieces(size):
            v = ir.Constant(self.vec(w), [0.0] * w)
            for m in range(lo, min(lo + w, size)):
                v = b.insert_element(v, b.load(b.gep(Y, [self.int(m)])), ir.Constant(self.i32, m - lo))
            newest.append(cgutils.alloca_once_value(b, v))
        one = ir.Constant(self.vec(1), [1.0])
        with cgutils.for_range(b, order) as loop:
            k = loop.index
            first = b.icmp_signed("==", k, self.int(0))
            only_first = b.select(first, one, ir.Constant(self.vec(1), [0.0]))
            state = [b.load(x) for x in newest]
            where: dict[int, tuple] = {}
            for i, (op, _, extra, _) in enumerate(series):
                if op == "y":
                    where[i] = self.locate(state, extra)
                elif op == "time":
                    later = b.select(b.icmp_signed("==", k, self.int(1)), one, ir.Constant(self.vec(1), [0.0]))
                    where[i] = (b.select(first, b.insert_element(one, t, ir.Constant(self.i32, 0)), later), 0)
            functions = Functions(
                b, 1, k, first, lambda row, key: b.load(self.address(W, self.at(row, column[key]), 1), align=8),
                lambda value, row, key: b.store(value, self.address(W, self.at(row, column[key]), 1), align=8),
                lambda ref: self.constants([ref])[0])
            for d, groups in _groups(program).items():
                for g, products in enumerate(groups):
                    self._products(d, g, products, k, first, where, only_first, W)
                rows = {}
                for i, (op, args, extra, depth) in enumerate(series):
                    if depth != d or op in ("mul", "cos"):
                        continue
                    for u in args:
                        if u not in rows:
                            rows[u] = self.combinations([operands[u]], where, only_first)[0]
                            b.store(rows[u], self.address(W, self.at(k, column[("u", u)]), 1), align=8)
                    for j, value in functions(op, i, args, extra, rows).items():
                        where[j] = (value, 0)
            inv = b.fdiv(one, b.insert_element(one, b.sitofp(b.add(k, self.int(1)), double), ir.Constant(self.i32, 0)))
            rate = self.combinations(program["rates"], where, only_first, inv)
            self.store(rate, Y, b.mul(b.add(k, self.int(1)), self.int(size)), size)
            for x, v in zip(newest, rate):
                b.store(v, x)

    def _products(self, d: int, g: int, products: list, k: Any, first: Any, where: dict, only_first: Any,
                  W: Any) -> None:
        """A group's order-k coefficients Σ_{j=0..k} L_j ⊙ R_{k−j}: the operands' row k gathered and stored in W,
        the pairs (j, k − j) into two accumulators (or one, ``TWIN``), the middle term when k is even, then the
        newest row's terms (in registers) against row 0."""
        b, operands, series = self.b, self.program["operands"], self.program["series"]
        n = len(products)
        left_column, right_column = self.column[("L", d, g)], self.column[("R", d, g)]
        left, right = (self.combinations([None if i is None else operands[series[i][1][side]] for i in products], where,
                                         only_first) for side in (0, 1))
        for value, column in ((left, left_column), (right, right_column)):
            for (lo, w), v in zip(pieces(n), value):
                b.store(v, self.address(W, self.at(k, column + lo), w), align=8)

        def rows(row):
            return self.load(W, self.at(row, left_column), n), self.load(W, self.at(row, right_column), n)

        zero = [ir.Constant(v.type, [0.0] * v.type.count) for v in left]
        acc0 = [cgutils.alloca_once_value(b, z) for z in zero]
        acc1 = [cgutils.alloca_once_value(b, z) for z in zero] if _padded(n) <= TWIN else acc0

        def add(acc, xs, ys):
            for slot, x, y in zip(acc, xs, ys):
                b.store(b.fadd(b.load(slot), b.fmul(x, y, flags=simd.FUSE), flags=simd.FUSE), slot)

        one, two = self.int(1), self.int(2)
        pairs = b.sdiv(b.sub(k, one), two)  # (k − 1) // 2 for k ≥ 1; 0 at k = 0 (sdiv rounds toward zero)
        with cgutils.for_range(b, pairs) as loop:
            j = b.sub(pairs, loop.index)  # from the middle outwards: the pair nearest the newest row last
            (lj, rj), (lk, rk) = rows(j), rows(b.sub(k, j))
            add(acc0, lj, rk)
            add(acc1, lk, rj)
        even = b.icmp_signed("==", b.and_(k, one), self.int(0))
        with b.if_then(b.and_(even, b.icmp_signed(">", k, self.int(0)))):
            add(acc0, *rows(b.lshr(k, one)))
        total = []
        for slot0, slot1, l0, r0, lk, rk in zip(acc0, acc1, *rows(self.int(0)), left, right):
            a0 = b.fadd(b.load(slot0), b.fmul(l0, rk, flags=simd.FUSE), flags=simd.FUSE)
            a1 = b.fadd(b.load(slot1) if acc1 is not acc0 else a0, b.fmul(lk, r0, flags=simd.FUSE), flags=simd.FUSE)
            total.append(b.select(first, a0, a1 if acc1 is acc0 else b.fadd(a0, a1, flags=simd.FUSE)))
        for lane, i in enumerate(products):
            if i is not None:
                where[i] = self.locate(total, lane)


#: the Taylor kernel's (address, work columns) by the address of its model's right-hand side kernel
_KERNELS: dict[int, tuple[float, float]] = {}


def ready(compiled: Any, rows: np.ndarray | None = None) -> bool:
    """Whether ``taylor`` can integrate a compiled model: every traced model can.

    This compiles (or loads) its Taylor kernel on first need and writes its address and work columns into
    ``compiled.params`` (and into every row of ``rows``, a batch's per-trajectory parameters). Nothing compiles
    before: most runs never use taylor, and a Taylor kernel's first compilation costs 0.2–1 s.
    """
    p = compiled.params
    if p[p.size - 4] == 0.0:
        address = int(p[TRACED_ADDRESS])
        if address not in _KERNELS:  # once per form and process (the rhs kernel's address names the form)
            model = traced_model(compiled)
            program = plan(model)
            module = generated_module(source(program), "gyrolab_taylor", f"{model.what} (Taylor)")
            _KERNELS[address] = (float(module.kernel.address), float(layout(program)[1]))
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
        address_, t_, order_, size_ = args[:4]
        double, i64 = ir.DoubleType(), ir.IntType(64)
        double_ptr, byte_ptr = double.as_pointer(), ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [double, i64, double_ptr, double_ptr, double_ptr])
        y, pp = (simd.array_data(context, b, signature.args[a], args[a]) for a in (4, 5))
        # stacksave/stackrestore: the stack's allocation is freed at once, not when the calling kernel returns
        save = cgutils.get_or_insert_function(b.module, ir.FunctionType(byte_ptr, []), "llvm.stacksave")
        restore = cgutils.get_or_insert_function(b.module, ir.FunctionType(ir.VoidType(), [byte_ptr]),
                                                 "llvm.stackrestore")
        small = b.icmp_signed("<=", size_, ir.Constant(i64, _STACK_DOUBLES))
        saved = b.call(save, [])
        with b.if_else(small) as (on_stack, on_heap):
            with on_stack:
                stack_w = b.alloca(double, size=size_)
                stack_w.align = 64  # (else its alignment follows the process's random stack base: steps ~15 % apart)
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
def coefficients(p, Y, order, t):
    """Fill Y[1..order] from Y[0] for a traced model: one call of the generated kernel
    (``source``), whose address ``ready`` wrote at p[-4] and its work columns at p[-3] (``layout``)."""
    address = int(p[p.size - 4])
    if address == 0:  # the Taylor kernel was not compiled (``ready`` not called): no series, not a crash
        Y[1:] = np.nan
        return
    _call(address, t, order, order * int(p[p.size - 3]), Y, p)