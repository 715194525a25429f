"""The Taylor method (``taylor``) for many trajectories at once: per-trajectory steps, vectorised across them.

``run_lanes`` advances LANES trajectories of any compiled model in lock step, one vector register of doubles (8 on
AVX-512, 4 on AVX2). The Taylor coefficients are stored [order, component, lane], lane innermost, and every part of
a step runs over all lanes at once in vector registers: the series, the step sizes, the outputs and the state
update. Each lane keeps its own time, step, Kahan carry and output index, with the single-trajectory kernel's step
rule and dense output (``taylor.run``: same order, same Jorba–Zou step from the last two coefficients, Horner
evaluation at the output times, compensated update), so a lane takes the steps the single kernel takes on its
trajectory, to rounding (the vector sums add in another order than the scalar ones; the step rule's powers go
through a vector log2/exp2 a few ulps from libm's). A lane reads and writes only its own column, and its arithmetic
follows from its own parameters and state, so its result does not depend on its neighbours. Taylor rejects no step:
every busy lane advances at every step. A lane whose trajectory has reached the last output time (or failed) takes
the next trajectory of its task (``task_size`` trajectories; tasks run in parallel with ``prange``).

The series is generated from the model's equations, as the single-trajectory kernel's is (``taylor_series`` lowers
them to Cauchy products of linear combinations of series and functions of series; ``_emit_series`` writes that
program's recurrences as LLVM IR over ``<LANES x double>``, ``_Functions`` those of the functions and divisions):
one generated ``cfunc`` per form (cached on disk), with the numbers of the equations per lane in Q (``constants``,
run when a lane takes a trajectory). Every
product's Cauchy sum runs over pairs (j, k − j): the operands' rows at j and k − j, loaded once, serve two fused
multiply-adds of every product that reads them, the pair with the newest coefficient last (the next order's older
terms overlap its computation). The work arrays start on 64-byte boundaries (``_rows``): numba aligns to 32, and a
512-bit load across two cache lines costs two.

Why LLVM IR: written as numba loops over lanes, the Cauchy sums are reductions whose accumulators LLVM keeps in
memory (numba does not run LLVM's SLP vectoriser); such a kernel was 1.2–2× slower than one trajectory per
thread. The IR works on ``<LANES x double>`` values, the accumulators in registers.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.kernels import batch_dop853, simd, taylor
from gyrolab.kernels.compiler import kernel
from gyrolab.kernels.expression import generated_module
from gyrolab.kernels.layout import TRACED_ADDRESS
from gyrolab.kernels.model import CompiledModel, traced_model
from gyrolab.kernels.recurrences import AUXILIARY, Functions
from gyrolab.kernels.taylor_series import plan
from gyrolab.kernels.vector_width import batch_lanes

#: trajectories advanced in lock step: one vector register of doubles of the CPU numba compiles for (8 with
#: AVX-512, 4 with AVX2; never fewer than 4). Fixed when this module is imported, so frozen into the compiled
#: kernels; numba's cache keys every kernel by the target CPU's name and features (its ``magic_tuple``), from
#: which the width follows, so a cache written for another width is not loaded.
LANES = batch_lanes()
from gyrolab.kernels.taylor import NOT_FINITE, OK, TOO_SMALL_STEP  # noqa: E402

#: products whose Cauchy sums share one loop over the pairs (j, k − j): their accumulators and the operands'
#: rows stay in the 32 vector registers
GROUP = 16
#: fewer products than this in a group: two accumulators each (``_cauchy``)
TWIN = 8
#: the generated series' source names this module's own hash: an emitter change compiles the series anew
_EMITTER = hashlib.sha256(b"".join(Path(__file__).with_name(name).read_bytes()
                                   for name in ("batch_taylor.py", "recurrences.py"))).hexdigest()[:12]
_P = types.CPointer(types.float64)


# ---- the generated series

def _layout(series: list) -> dict[tuple, int]:
    """W's columns: ("u", operand) for every operand of a product or a function, ("f", series, 0) for a function's
    result and ("f", series, 1) for a sine's cosine or an auxiliary series."""
    column: dict[tuple, int] = {}
    for i, (op, args, _, _) in enumerate(series):
        if op in ("y", "time", "cos"):  # (the cosine is computed with its sine)
            continue
        for u in args:
            column.setdefault(("u", u), len(column))
        if op != "mul":
            column[("f", i, 0)] = len(column)
            if op == "sin" or op in AUXILIARY:
                column[("f", i, 1)] = len(column)
    return column


def source(program: dict) -> str:
    """The generated module: ``constants`` (a lane's numbers from its parameter row) and ``kernel`` (the series)."""
    shape = {k: program[k] for k in ("size", "series", "operands", "rates")}
    lines = [*program["lines"], *(f"q[{row} * LANES + lane] = {name}" for row, name in enumerate(program["names"]))]
    body = "".join(f"    {line}\n" for line in lines) or "    pass\n"
    return _HEADER.format(emitter=_EMITTER, lanes=LANES, plan=repr(shape)) + body


_HEADER = '''"""Generated by gyrolab: Taylor coefficients of a model across LANES trajectories (gyrolab.kernels.batch_taylor)."""
import math

import numba
from numba import types

from gyrolab.kernels.batch_taylor import series_intrinsic

EMITTER = "{emitter}"
LANES = {lanes}
PLAN = {plan}
_P = types.CPointer(types.float64)
_series = series_intrinsic(PLAN, LANES)


@numba.cfunc(types.void(types.int64, _P, _P, _P, _P), cache=True, error_model="numpy")
def kernel(order, T, W, Q, t):
    _series(order, T, W, Q, t)


@numba.cfunc(types.void(_P, _P, types.int64), cache=True, error_model="numpy")
def constants(p, q, lane):
'''


def series_intrinsic(program: dict, lanes: int) -> Any:
    """The intrinsic ``(order, T, W, Q, t)`` (pointers) that fills T[1..order] from T[0] in every lane:
    T is (order+1, size, lanes), W the operands' rows (order, columns, lanes), Q the numbers (rows of lanes), t
    each lane's time."""

    @intrinsic
    def _series(typingctx, order, T, W, Q, t):
        sig = types.void(types.int64, _P, _P, _P, _P)

        def codegen(context, builder, signature, args):
            _emit_series(builder, program, lanes, *args)
            return context.get_dummy_value()

        return sig, codegen

    return _series


def _emit_series(b: ir.IRBuilder, program: dict, lanes: int, order, T, W, Q, t) -> None:
    """``series_intrinsic``'s IR: for k = 0 … order − 1, the products' order-k coefficients by depth (the
    operands' rows stored in W, the Cauchy sums by pairs), then T[k + 1] = (the rates' combinations) / (k + 1)."""
    vec = ir.VectorType(ir.DoubleType(), lanes)
    i64 = ir.IntType(64)
    T, W, Q, t = (b.bitcast(x, vec.as_pointer()) for x in (T, W, Q, t))
    size, series = program["size"], program["series"]
    operands = program["operands"]
    column = _layout(series)
    width = max(len(column), 1)

    def const(x: int) -> ir.Constant:
        return ir.Constant(i64, x)

    def splat(x: float) -> ir.Constant:
        return ir.Constant(vec, [x] * lanes)

    def load(base, index):
        return b.load(b.gep(base, [index]), align=8)

    def store(value, base, index) -> None:
        b.store(value, b.gep(base, [index]), align=8)

    def at(row, stride, col):
        return b.add(b.mul(row, const(stride)), const(col))

    numbers = {}

    def number(ref):
        if isinstance(ref, str):
            return splat(float(ref))
        if ref not in numbers:  # loaded once, before the loop over orders
            numbers[ref] = load(Q, const(ref))
        return numbers[ref]

    for _, terms in [*operands, *program["rates"]]:  # every number's load ahead of the loop
        for _, c in terms:
            number(c)
    for c, _ in [*operands, *program["rates"]]:
        number(c)
    for op, _, extra, _ in series:
        if op == "pow":
            number(extra)
    newest = [cgutils.alloca_once_value(b, load(T, const(m))) for m in range(size)]
    zero = const(0)
    with cgutils.for_range(b, order) as loop:
        k = loop.index
        first = b.icmp_signed("==", k, zero)
        only_first = b.select(first, splat(1.0), splat(0.0))  # a constant's coefficient: 1 at order 0, else 0

        def combination(value, values):
            c, terms = value
            parts = []
            for i, ref in terms:
                x = values[i]
                parts.append(x if ref == "1.0" else b.fneg(x) if ref == "-1.0" else b.fmul(number(ref), x, flags=simd.FUSE))
            if c != "0.0":
                parts.append(b.fmul(number(c), only_first, flags=simd.FUSE))
            while len(parts) > 1:  # a balanced tree: dependent additions log2(terms) deep
                parts = [b.fadd(parts[i], parts[i + 1], flags=simd.FUSE) if i + 1 < len(parts) else parts[i]
                         for i in range(0, len(parts), 2)]
            return parts[0] if parts else splat(0.0)

        values = {}
        for i, (op, _, extra, _) in enumerate(series):
            if op == "y":
                values[i] = b.load(newest[extra])
            elif op == "time":
                later = b.select(b.icmp_signed("==", k, const(1)), splat(1.0), splat(0.0))
                values[i] = b.select(first, load(t, zero), later)
        depth = max((s[3] for s in series), default=0)
        emit = Functions(b, lanes, k, first, lambda row, key: load(W, at(row, width, column[key])),
                          lambda value, row, key: store(value, W, at(row, width, column[key])), number)
        for d in range(1, depth + 1):
            here = [(i, s) for i, s in enumerate(series) if s[3] == d and s[0] != "cos"]
            rows = {}
            for _, (_, args, _, _) in here:
                for u in args:
                    if u not in rows:
                        rows[u] = combination(operands[u], values)
                        store(rows[u], W, at(k, width, column[("u", u)]))
            products = [(i, args) for i, (op, args, _, _) in here if op == "mul"]
            for g in range(0, len(products), GROUP):
                values.update(_cauchy(b, products[g:g + GROUP], k, rows,
                                      lambda row, u: load(W, at(row, width, column[("u", u)])), splat(0.0), first))
            for i, (op, args, extra, _) in here:
                if op != "mul":
                    values.update(emit(op, i, args, extra, rows))
        inv = b.fdiv(splat(1.0), simd.splat(b, b.sitofp(b.add(k, const(1)), ir.DoubleType()), lanes))
        rates = [b.fmul(combination(rate, values), inv, flags=simd.FUSE) for rate in program["rates"]]
        k1 = b.add(k, const(1))
        for m, value in enumerate(rates):
            store(value, T, at(k1, size, m))
            b.store(value, newest[m])


def _cauchy(b, products, k, rows, load_row, zero, first):
    """The order-k coefficients Σ_{j=0..k} L_j R_{k−j} of ``products`` ((series, (L, R)) pairs of operands): the
    middle terms by pairs (j, k − j), j = 1 … ⌈k/2⌉ − 1, into two accumulators per product (L_j R_{k−j} and
    L_{k−j} R_j), the middle term j = k/2 when k is even, then the terms with the newest row k (``rows``, in
    registers) against row 0."""
    i64 = k.type
    one, two = ir.Constant(i64, 1), ir.Constant(i64, 2)
    used = sorted({u for _, args in products for u in args})
    # two accumulators per product (half as long a chain of dependent additions) only where few products would
    # leave the fused multiply-adds waiting for each other; with more, the registers are better spent on loads
    twin = len(products) < TWIN
    acc = {}
    for i, _ in products:
        first_half = cgutils.alloca_once_value(b, zero)
        acc[i] = (first_half, cgutils.alloca_once_value(b, zero) if twin else first_half)

    def add(variable, x, y):
        b.store(b.fadd(b.load(variable), b.fmul(x, y, flags=simd.FUSE), flags=simd.FUSE), variable)

    pairs = b.sdiv(b.sub(k, one), two)  # (k − 1) // 2 for k ≥ 1; 0 at k = 0 (sdiv rounds toward zero)
    with cgutils.for_range(b, pairs) as loop:
        j = b.sub(pairs, loop.index)  # the pairs from the middle outwards: the one nearest the newest row last
        low = {u: load_row(j, u) for u in used}
        high = {u: load_row(b.sub(k, j), u) for u in used}
        for i, (x, y) in products:
            add(acc[i][0], low[x], high[y])
            add(acc[i][1], high[x], low[y])
    even = b.icmp_signed("==", b.and_(k, one), ir.Constant(i64, 0))
    with b.if_then(b.and_(even, b.icmp_signed(">", k, ir.Constant(i64, 0)))):
        mid = {u: load_row(b.lshr(k, one), u) for u in used}
        for i, (x, y) in products:
            add(acc[i][0], mid[x], mid[y])
    start = {u: load_row(ir.Constant(i64, 0), u) for u in used}
    out = {}
    for i, (x, y) in products:
        a0 = b.fadd(b.load(acc[i][0]), b.fmul(start[x], rows[y], flags=simd.FUSE), flags=simd.FUSE)
        if twin:
            a1 = b.fadd(b.load(acc[i][1]), b.fmul(rows[x], start[y], flags=simd.FUSE), flags=simd.FUSE)
            out[i] = b.select(first, a0, b.fadd(a0, a1, flags=simd.FUSE))  # at k = 0 the one term L_0 R_0
        else:
            a1 = b.fadd(a0, b.fmul(rows[x], start[y], flags=simd.FUSE), flags=simd.FUSE)
            out[i] = b.select(first, a0, a1)
    return out


#: (series address, constants address, numbers, W's columns) of each form's generated lanes, by its rhs kernel's address
_KERNELS: dict[int, tuple[int, int, int, int]] = {}


def lanes_kernel(compiled: CompiledModel) -> tuple[int, int, int, int]:
    """The generated lanes of a compiled model: (series address, constants address, numbers, W's columns), compiled
    (or loaded from the disk cache) on first need."""
    key = int(compiled.params[TRACED_ADDRESS])  # the right-hand side kernel's address names the form
    if key not in _KERNELS:
        model = traced_model(compiled)
        program = plan(model)
        module = generated_module(source(program), "gyrolab_lanes", f"{model.what} (Taylor lanes)")
        _KERNELS[key] = (int(module.kernel.address), int(module.constants.address), max(len(program["names"]), 1),
                         max(len(_layout(program["series"])), 1))
    return _KERNELS[key]


def run_lanes(compiled: CompiledModel, Params: np.ndarray, order: int, tol: float, t_out: np.ndarray,
              Y0: np.ndarray, Y: np.ndarray, steps: np.ndarray, status: np.ndarray) -> None:
    """Every trajectory by lanes (``run_blocks``) with the model's generated series (``lanes_kernel``)."""
    run_blocks(*lanes_kernel(compiled), Params, order, tol, t_out, Y0, Y, steps, status,
               batch_dop853.task_size(len(Y0), LANES))


# ---- calls of the generated functions

@intrinsic
def _call_series(typingctx, address, order, T, W, Q, t):
    """The generated series at ``address``: ``void f(int64 order, double* T, double* W, double* Q, double* t)``."""
    return types.void(types.int64, types.int64, T, W, Q, t), simd.call_address


@intrinsic
def _call_constants(typingctx, address, p, Q, lane):
    """The generated ``void constants(double* p, double* q, int64 lane)``: a lane's numbers from its parameters."""
    return types.void(types.int64, p, Q, types.int64), simd.call_address


# ---- the step's other parts, for any state size n

def _components(b, n, emit, block=3):
    """``emit(components)`` over 0 … n − 1: blocks of ``block`` components (their chains interleave in the
    processor), then the rest one by one."""
    i64 = n.type
    blocks = b.sdiv(n, ir.Constant(i64, block))
    with cgutils.for_range(b, blocks) as loop:
        c = b.mul(loop.index, ir.Constant(i64, block))
        emit([b.add(c, ir.Constant(i64, m)) for m in range(block)])
    with cgutils.for_range(b, b.srem(n, ir.Constant(i64, block))) as loop:
        emit([b.add(b.mul(blocks, ir.Constant(i64, block)), loop.index)])


def _lane_types(T, order, n, *arrays) -> bool:
    """Whether an intrinsic's arguments are the series T (order + 1, n, LANES), the order, the state size n and
    arrays of rows of lanes."""
    return (simd.vector_arrays([T, *arrays]) and T.ndim == 3 and isinstance(order, types.Integer)
            and isinstance(n, types.Integer))


def _lanes_codegen(body):
    """An intrinsic's codegen that emits ``body(v, b, p, size)``: v its arguments as rows of vectors (``simd.Lanes``),
    p and size the order and the state size (arguments 1 and 2) as intp."""

    def codegen(context, builder, signature, args):
        v = simd.Lanes(context, builder, signature, args, LANES)
        p, size = (context.cast(builder, args[i], signature.args[i], types.intp) for i in (1, 2))
        body(v, builder, p, size)
        return context.get_dummy_value()

    return codegen


@intrinsic
def _step_sizes(typingctx, T, order, n, K, S):
    """Every lane's Jorba–Zou step (``taylor.step_size``) from its series T[:, :, lane] (n components), in vector
    registers.

    K is (4, LANES): tol, the safety factor, 1/(order − 1), 1/order in every lane. S (2, LANES) receives in row 0
    h = safety · min_k (tol · scale / n_k)^(1/k), k = order − 1, order (scale = max(1, ‖T[0]‖∞), n_k = ‖T[k]‖∞;
    a vanishing n_k drops its term) through 2^(log2(·)/k) (``simd.Lanes.log2``, ``exp2``: a few ulps from the
    scalar power), and in row 1 a flag (1.0) where that path does not apply: a non-finite coefficient, a ratio
    outside the normal doubles, both n_k zero or a step beyond 2^±1000. There the caller takes the scalar rule,
    so every lane steps as ``taylor.run`` would, to rounding.
    """
    if not _lane_types(T, order, n, K, S):
        return None

    def body(v, b, p, size):
        tol, safety, inv1, inv2 = [v.load(3, r) for r in range(4)]
        zero, one = v.constant(0.0), v.constant(1.0)
        scale, n1, n2, probe = (cgutils.alloca_once_value(b, x) for x in (one, zero, zero, zero))
        last = b.sub(p, ir.Constant(p.type, 1))

        def emit(components):
            for c in components:
                x0, x1, x2 = (v.load(0, b.add(b.mul(index, size), c)) for index in (ir.Constant(p.type, 0), last, p))
                for x, variable in ((x0, scale), (x1, n1), (x2, n2)):
                    a, old = v.call("fabs", x), b.load(variable)
                    b.store(b.select(b.fcmp_ordered(">", a, old), a, old), variable)
                for x in (x0, x1, x2):  # stays 0 unless a value is inf or NaN (x · 0 is NaN then)
                    b.store(b.fadd(b.load(probe), b.fmul(x, zero)), probe)

        _components(b, size, emit)
        scale, n1, n2 = b.load(scale), b.load(n1), b.load(n2)
        special = b.fcmp_unordered("!=", b.load(probe), zero)
        smallest, huge, inf = v.constant(2.0 ** -1021), v.constant(1000.0), v.constant(math.inf)
        exponents = []
        for norm, inv in ((n1, inv1), (n2, inv2)):
            ratio = b.fdiv(b.fmul(tol, scale), norm)
            present = b.fcmp_ordered(">", norm, zero)
            normal = b.and_(b.fcmp_ordered(">=", ratio, smallest), b.fcmp_ordered("<", ratio, inf))
            special = b.or_(special, b.and_(present, b.not_(normal)))
            exponents.append(b.select(present, b.fmul(v.log2(ratio), inv), inf))
        y = b.select(b.fcmp_ordered("<", exponents[1], exponents[0]), exponents[1], exponents[0])
        in_range = b.and_(b.fcmp_ordered("<", y, huge), b.fcmp_ordered(">", y, b.fneg(huge)))
        special = b.or_(special, b.not_(in_range))
        y = b.select(in_range, y, zero)
        v.store(b.fmul(v.exp2(y), safety), 4, 0)
        v.store(b.select(special, one, zero), 4, 1)

    return types.void(T, order, n, K, S), _lanes_codegen(body)


def _horner(v, b, p, size, components, chains):
    """Horner sums Σ_{k≥1..p} T[k, c] x^k / x (k = p … 1) of each component c for each (x, fuse) of ``chains``,
    interleaved; returns [[sum per chain] per component]."""
    acc = []
    for c in components:
        top = v.load(0, b.add(b.mul(p, size), c))
        acc.append([cgutils.alloca_once_value(b, top) for _ in chains])
    last = b.sub(p, ir.Constant(p.type, 1))
    with cgutils.for_range(b, last) as loop:
        k = b.sub(last, loop.index)  # order − 1 … 1
        for c, variables in zip(components, acc):
            x = v.load(0, b.add(b.mul(k, size), c))
            for (h, flags), variable in zip(chains, variables):
                b.store(b.fadd(b.fmul(b.load(variable), h, flags=flags), x, flags=flags), variable)
    return [[b.load(variable) for variable in variables] for variables in acc]


@intrinsic
def _advance(typingctx, T, order, n, H, carry, D, O, F):
    """Every lane's output at its own t + dt and its step: O[c] = T[0, c] + (Σ_{k≥1} T[k, c] dt^k − carry[c])
    with dt = D[0] (Horner in strict arithmetic, ``_dense``'s), then the state T[0] += Σ_{k≥1} T[k] h^k with
    h = H[0] (Horner, multiply and add may fuse), a compensated (Kahan, strict) sum with ``carry``
    (``simd.update``'s arithmetic). The output's and the step's Horner chains share their loads of T and
    interleave. Idle lanes have h = 0; a lane without an output ignores O. F[0] receives 0 in every lane whose new
    state is finite (NaN in the others: the sum of its components times 0)."""
    if not _lane_types(T, order, n, H, carry, D, O, F):
        return None

    def body(v, b, p, size):
        h, dt = v.load(3, 0), v.load(5, 0)
        probe = cgutils.alloca_once_value(b, v.constant(0.0))

        def emit(components):
            sums = _horner(v, b, p, size, components, ((h, simd.FUSE), (dt, ())))
            for c, (step, output) in zip(components, sums):
                y, old = v.load(0, c), v.load(4, c)
                v.store(b.fadd(y, b.fsub(b.fmul(output, dt), old)), 6, c)
                inc = b.fsub(b.fmul(step, h), old)
                total = b.fadd(y, inc)
                v.store(b.fsub(b.fsub(total, y), inc), 4, c)
                v.store(total, 0, c)
                b.store(b.fadd(b.load(probe), b.fmul(total, v.constant(0.0))), probe)

        _components(b, size, emit)
        v.store(b.load(probe), 7, 0)

    return types.void(T, order, n, H, carry, D, O, F), _lanes_codegen(body)


@intrinsic
def _dense(typingctx, T, order, n, D, carry, O):
    """O[c] = T[0, c] + (Σ_{k≥1} T[k, c] dt^k − carry[c]) in every lane, dt = D[0] (one per lane): each lane's
    series at its own t + dt, Horner in strict arithmetic. Lane for lane the arithmetic of the scalar dense
    output of ``taylor.run``."""
    if not _lane_types(T, order, n, D, carry, O):
        return None

    def body(v, b, p, size):
        dt = v.load(3, 0)

        def emit(components):
            for c, (output,) in zip(components, _horner(v, b, p, size, components, ((dt, ()),))):
                v.store(b.fadd(v.load(0, c), b.fsub(b.fmul(output, dt), v.load(4, c))), 5, c)

        _components(b, size, emit)

    return types.void(T, order, n, D, carry, O), _lanes_codegen(body)


# ---- the driver

@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_blocks(series, constants, numbers, columns, Params, order, tol, t_out, Y0, Y, steps, status, task_size):
    """Every trajectory j (initial state Y0[j], parameters Params[j]) over t_out into Y[j], with the generated
    series at ``series`` and its numbers' function at ``constants`` (``lanes_kernel``).

    steps[j] receives its number of steps, status[j] OK, NOT_FINITE or TOO_SMALL_STEP (a step of a
    huge series that does not advance time; the single kernel would loop forever); its outputs from the
    failed step on are NaN. t_out has at least two times. Tasks of ``task_size`` trajectories run in parallel.
    """
    count = Y0.shape[0]
    n_tasks = (count + task_size - 1) // task_size
    for task in numba.prange(n_tasks):  # the loop stays small: numba's parallel pass compiles slowly on big bodies
        _task(series, constants, numbers, columns, Params, order, tol, t_out, Y0, Y, steps, status,
              task * task_size, min(task * task_size + task_size, count))


@kernel
def _load(lane, j, Y0, Params, T, Q, carry, constants):
    """Put trajectory j into ``lane`` (or, with j < 0, make the lane idle: a zero state and zero numbers, whose
    series is zero): its state, a zero carry, and its numbers (``constants``) in Q[:, lane]."""
    for c in range(Y0.shape[1]):
        T[0, c, lane] = Y0[j, c] if j >= 0 else 0.0
        carry[c, lane] = 0.0
    if j < 0:
        for r in range(Q.shape[0]):
            Q[r, lane] = 0.0
    else:
        _call_constants(constants, Params[j], Q, lane)


@kernel
def _rows(count, width):
    """Zeros of shape (count, width, LANES) whose rows of LANES doubles start on 64-byte boundaries (numba aligns
    arrays to 32 bytes): a 512-bit load across two cache lines costs two, and the Cauchy sums are bound by their
    loads (0.2 µs aligned, 0.3 µs not, per lane group and step at order 17 on AVX-512)."""
    size = count * width * LANES
    buffer = np.zeros(size + 8)
    start = (-buffer.ctypes.data % 64) // 8
    return buffer[start:start + size].reshape((count, width, LANES))


@kernel
def _task(series, constants, numbers, columns, Params, order, tol, t_out, Y0, Y, steps, status, first, stop):
    """``run_blocks`` for the trajectories first..stop−1, LANES at a time."""
    n = Y0.shape[1]
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    T = _rows(order + 1, n)
    W = _rows(order + 1, columns)  # the products' operands, by order (the generated series')
    Q = _rows(1, numbers)[0]  # each lane's numbers of the equations
    H = _rows(1, 1)[0]  # each lane's step (0 in idle lanes)
    carry = _rows(1, n)[0]  # the Kahan compensation of each lane's state
    t = _rows(1, 1)[0]  # each lane's time (the series' time)
    t_next = np.zeros(LANES)
    index = np.zeros(LANES, dtype=np.int64)  # each lane's next output time
    traj = np.full(LANES, -1, dtype=np.int64)
    safety = math.exp(-0.7 / (order - 1))
    K = _rows(1, 4)[0]  # _step_sizes' constants
    K[0], K[1], K[2], K[3] = tol, safety, 1.0 / (order - 1), 1.0 / order
    S = _rows(1, 2)[0]  # each lane's step from _step_sizes, and where the scalar rule must take over
    D = _rows(1, 1)[0]  # each lane's time from its step's start to its next output time (_dense)
    O = _rows(1, n)[0]  # the lanes' states there
    F = _rows(1, 1)[0]  # 0 where a lane's new state is finite (``_advance``)
    due = np.zeros(LANES, dtype=np.bool_)  # the lanes with an output in this step
    following = first
    for lane in range(LANES):
        if following < stop:
            traj[lane] = following
            Y[following, 0] = Y0[following]
            following += 1
        _load(lane, traj[lane], Y0, Params, T, Q, carry, constants)
        t[0, lane] = t_out[0]
        index[lane] = 1
    busy = min(LANES, stop - first)
    while busy > 0:
        _call_series(series, order, T, W, Q, t)
        _step_sizes(T, order, n, K, S)
        several = False
        for lane in range(LANES):  # each lane's step (``taylor.run``'s rule) and the outputs it covers
            due[lane] = False
            j = traj[lane]
            if j < 0:
                continue
            h = S[0, lane] if S[1, lane] == 0.0 else _scalar_step_size(lane, T, order, tol, safety)
            if not h < np.inf:
                h = t_end - t[0, lane]
            t_new = min(t[0, lane] + h, t_end)
            t_next[lane] = t_new
            H[0, lane] = t_new - t[0, lane]
            i = index[lane]  # a busy lane has an output time left: i < n_out
            due[lane] = t_out[i] <= t_new
            D[0, lane] = t_out[i] - t[0, lane] if due[lane] else 0.0
            several = several or (due[lane] and i + 1 < n_out and t_out[i + 1] <= t_new)
        if several:  # a step over two output times or more (rare): all its outputs first, then the step alone
            _outputs(T, order, t_out, t, t_next, traj, index, carry, D, O, Y)
            due[:] = False
            D[0, :] = 0.0
        _advance(T, order, n, H, carry, D, O, F)
        for lane in range(LANES):
            if due[lane]:
                for c in range(n):
                    Y[traj[lane], index[lane], c] = O[c, lane]
                index[lane] += 1
        for lane in range(LANES):
            j = traj[lane]
            if j < 0:
                continue
            finite = F[0, lane] == 0.0
            if finite and t_next[lane] > t[0, lane]:
                steps[j] += 1
                t[0, lane] = t_next[lane]
                if index[lane] < n_out:
                    continue
                status[j] = OK
            else:  # non-finite, or a step too small to advance time: its outputs from here on are NaN
                status[j] = NOT_FINITE if not finite else TOO_SMALL_STEP
                for i in range(index[lane], n_out):
                    for c in range(n):
                        Y[j, i, c] = np.nan
            traj[lane] = following if following < stop else -1  # the lane takes the task's next trajectory
            if following < stop:
                Y[following, 0] = Y0[following]
                following += 1
            else:
                busy -= 1
            _load(lane, traj[lane], Y0, Params, T, Q, carry, constants)
            t[0, lane] = t_out[0]
            index[lane] = 1
            H[0, lane] = 0.0


@kernel
def _scalar_step_size(lane, T, order, tol, safety):
    """``taylor.run``'s step rule on ``lane``'s series T[:, :, lane], in scalar arithmetic (where ``_step_sizes``
    flags the lane)."""
    scale = 1.0
    n1 = 0.0
    n2 = 0.0
    for c in range(T.shape[1]):
        scale = max(scale, abs(T[0, c, lane]))
        n1 = max(n1, abs(T[order - 1, c, lane]))
        n2 = max(n2, abs(T[order, c, lane]))
    return taylor.step_size(tol, scale, n1, n2, order, safety)


@kernel
def _outputs(T, order, t_out, t, t_next, traj, index, carry, D, O, Y):
    """The outputs of every lane's step from t to t_next: its series at each output time the step covers
    (``_dense``, all lanes at once; a lane without an output in this step is evaluated and ignored)."""
    n = T.shape[1]
    n_out = t_out.size
    while True:
        due = False
        for lane in range(LANES):
            D[0, lane] = 0.0
            if traj[lane] >= 0 and index[lane] < n_out and t_out[index[lane]] <= t_next[lane]:
                D[0, lane] = t_out[index[lane]] - t[0, lane]
                due = True
        if not due:
            return
        _dense(T, order, n, D, carry, O)
        for lane in range(LANES):
            j = traj[lane]
            if j >= 0 and index[lane] < n_out and t_out[index[lane]] <= t_next[lane]:
                for c in range(n):
                    Y[j, index[lane], c] = O[c, lane]
                index[lane] += 1
