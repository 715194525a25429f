"""LLVM IR helpers for the Taylor kernels' vector intrinsics (``batch_taylor``, ``taylor``).

Arrays of doubles are seen as rows of vectors: in ``batch_taylor`` a row holds one component of LANES
trajectories (8 on AVX-512, 4 on AVX2), in ``taylor`` one 3-vector of one trajectory (and a zero) in a
``<4 x double>``. ``taylor`` forms the fixed-point right-hand side's coefficient from its Cauchy sums with
``Lanes.fixed_point_rate`` and updates the state with ``update`` (Horner, then Kahan); ``batch_taylor`` emits
the recurrences generated from a model's equations, its sums in another order (by pairs), so a trajectory in a
lane and alone agree to rounding, not bit for bit. ``Lanes.log2`` and ``Lanes.exp2`` are vector powers for the
lanes' step rule.

Why intrinsics: numba does not run LLVM's SLP vectoriser, and the Cauchy sums
written as numba loops keep their accumulators in memory (``batch_taylor``'s
docstring); the intrinsics emit the arithmetic over ``<4 x double>`` values
directly, the accumulators in registers.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

LANES = 4  # one AVX2 vector of doubles: the single trajectory's (x, y, z, 0) rows (``taylor``)
FUSE = ("contract",)  # the series' multiply and add may fuse (as in the scalar kernel's fastmath)


def vector_arrays(arrays) -> bool:
    """The intrinsics' arrays: C-contiguous float64, a row of LANES doubles innermost."""
    return all(isinstance(a, types.Array) and a.layout == "C" and a.dtype == types.float64 for a in arrays)


class Lanes:
    """LLVM IR helpers of the intrinsics: arrays of doubles seen as rows of ``<LANES x double>`` vectors."""

    def __init__(self, context, builder, signature, args, width=LANES):
        self.builder = builder
        self.width = width
        self.vec = ir.VectorType(ir.DoubleType(), width)
        self.arrays = [builder.bitcast(context.make_array(ty)(context, builder, value).data, self.vec.as_pointer())
                       if isinstance(ty, types.Array) else value for ty, value in zip(signature.args, args)]

    def ptr(self, array, row):
        """Pointer to vector ``row`` (an int or an LLVM integer) of ``array`` (an argument's position)."""
        index = ir.Constant(ir.IntType(64), row) if isinstance(row, int) else row
        return self.builder.gep(self.arrays[array], [index])

    def load(self, array, row):
        return self.builder.load(self.ptr(array, row), align=8)

    def store(self, value, array, row):
        self.builder.store(value, self.ptr(array, row), align=8)

    @staticmethod
    def row(builder, index, stride, column):
        """The vector row of T[index, column] in an array of ``stride`` vectors per index: index · stride + column."""
        return builder.add(builder.mul(index, ir.Constant(index.type, stride)), ir.Constant(index.type, column))

    def splat(self, scalar):
        b = self.builder
        one = b.insert_element(ir.Constant(self.vec, ir.Undefined), scalar, ir.Constant(ir.IntType(32), 0))
        return b.shuffle_vector(one, ir.Constant(self.vec, ir.Undefined), ir.Constant(ir.VectorType(ir.IntType(32), self.width),
                                                                                      [0] * self.width))

    def variables(self, count):
        """Vector variables (stack slots that LLVM promotes to registers)."""
        return [cgutils.alloca_once(self.builder, self.vec) for _ in range(count)]

    def fma_into(self, variable, x, y, subtract=False):
        """variable ± x·y, multiply and add allowed to fuse."""
        b = self.builder
        product = b.fmul(x, y, flags=FUSE)
        old = b.load(variable)
        b.store(b.fsub(old, product, flags=FUSE) if subtract else b.fadd(old, product, flags=FUSE), variable)

    def inverse(self, k):
        """splat(1 / (k + 1)) for the LLVM integer k."""
        b = self.builder
        return self.splat(b.fdiv(ir.Constant(ir.DoubleType(), 1.0),
                                 b.sitofp(b.add(k, ir.Constant(k.type, 1)), ir.DoubleType())))

    def fixed_point_rate(self, q, n, pairs_w, pairs_g, qa, ea, qb, eb, inv):
        """The fixed-point ω̇'s order-(k+1) Taylor coefficient, without α (``fixed_point.taylor_coefficients``):
        (q ⊙ (pairs_w − n ⊙ pairs_g) + (qa ⊙ ea − qb ⊙ eb)) ⊙ inv, with q = (I_y − I_z)/I_x (and cyclically),
        n = N_2, qa ⊙ ea − qb ⊙ eb the torque U_2 × γ_k over the inertia, inv = 1/(k + 1). Multiply and add
        may fuse; both kernels emit this one expression, so LLVM fuses it alike in both."""
        b = self.builder
        torque = b.fsub(b.fmul(qa, ea, flags=FUSE), b.fmul(qb, eb, flags=FUSE), flags=FUSE)
        inner = b.fsub(pairs_w, b.fmul(n, pairs_g, flags=FUSE), flags=FUSE)
        return b.fmul(b.fadd(b.fmul(q, inner, flags=FUSE), torque, flags=FUSE), inv, flags=FUSE)


    # Vector log2 and exp2 (the Taylor step rule's powers, ``batch_taylor._step_sizes``): relative error a few
    # ulps for normal positive x and for 2^y in [2^−1022, 2^1023]; the callers route other values elsewhere.
    _LN2 = 0.6931471805599453
    _SQRT2 = 1.4142135623730951

    def _bits(self, x):
        return self.builder.bitcast(x, ir.VectorType(ir.IntType(64), self.width))

    def _ints(self, value):
        return ir.Constant(ir.VectorType(ir.IntType(64), self.width), [value] * self.width)

    def constant(self, value):
        return ir.Constant(self.vec, [float(value)] * self.width)

    def call(self, name, *args):
        """The LLVM vector intrinsic ``llvm.NAME.vWf64`` (fabs, rint, ...) on ``args``."""
        function = cgutils.get_or_insert_function(self.builder.module, ir.FunctionType(self.vec, [self.vec] * len(args)),
                                                  f"llvm.{name}.v{self.width}f64")
        return self.builder.call(function, list(args))

    def log2(self, x):
        """log2(x) for positive normal x: x = 2^e m, m in [√½, √2), ln m = 2 atanh(s), s = (m − 1)/(m + 1),
        |s| ≤ 0.172, by its series to s²¹ (the next term is below 1e-18 of the sum)."""
        b = self.builder
        bits = self._bits(x)
        e = b.sitofp(b.sub(b.lshr(bits, self._ints(52)), self._ints(1023)), self.vec)
        m = b.bitcast(b.or_(b.and_(bits, self._ints((1 << 52) - 1)), self._ints(1023 << 52)), self.vec)
        big = b.fcmp_ordered(">", m, self.constant(self._SQRT2))
        m = b.select(big, b.fmul(m, self.constant(0.5)), m)
        e = b.select(big, b.fadd(e, self.constant(1.0)), e)
        s = b.fdiv(b.fsub(m, self.constant(1.0)), b.fadd(m, self.constant(1.0)))
        z = b.fmul(s, s)
        poly = self.constant(1.0 / 21.0)
        for n in range(9, -1, -1):
            poly = b.fadd(b.fmul(poly, z, flags=FUSE), self.constant(1.0 / (2 * n + 1)), flags=FUSE)
        ln_m = b.fmul(b.fmul(s, poly), self.constant(2.0))
        return b.fadd(e, b.fmul(ln_m, self.constant(1.0 / self._LN2)))

    def exp2(self, y):
        """2^y for y in [−1022, 1023]: y = n + f, n the nearest integer, |f| ≤ ½; 2^f = exp(f ln 2) by its
        Taylor series to the 13th power (the next term is below 1e-17), times 2^n from its bits."""
        b = self.builder
        n = self.call("rint", y)
        g = b.fmul(b.fsub(y, n), self.constant(self._LN2))
        poly = self.constant(1.0 / 6227020800.0)  # 1/13!
        factorial = 6227020800.0
        for k in range(12, -1, -1):
            factorial /= (k + 1)
            poly = b.fadd(b.fmul(poly, g, flags=FUSE), self.constant(1.0 / factorial), flags=FUSE)
        scale = b.bitcast(b.shl(b.add(b.fptosi(n, ir.VectorType(ir.IntType(64), self.width)), self._ints(1023)),
                                self._ints(52)), self.vec)
        return b.fmul(poly, scale)


def series(stride, width=LANES):
    """Decorator: an intrinsic ``(T, order, Q)`` (T: ``stride`` vector rows per order, Q: rows of constants) from
    ``emit(v, order, row)``, which writes its IR with ``v`` (``Lanes``), ``order`` (an LLVM integer) and
    ``row(index, column)`` (T's vector row of that order and column)."""

    def wrap(emit):
        def typer(typingctx, T, order, Q):
            if not (vector_arrays([T, Q]) and T.ndim == 3 and Q.ndim == 2 and isinstance(order, types.Integer)):
                return None

            def codegen(context, builder, signature, args):
                v = Lanes(context, builder, signature, args, width)
                p = context.cast(builder, args[1], signature.args[1], types.intp)
                emit(v, p, lambda index, column: v.row(builder, index, stride, column))
                return context.get_dummy_value()

            return types.void(T, order, Q), codegen

        typer.__name__, typer.__doc__ = emit.__name__, emit.__doc__
        return intrinsic(typer)

    return wrap


def update(stride, count, width=LANES):
    """An intrinsic ``(T, order, H, carry)``: the state rows T[0, 0..count−1] += Σ_{k≥1} T[k, c] h^k (Horner,
    multiply and add may fuse), a compensated (Kahan, strict arithmetic) sum with carry's rows 0..count−1.

    T holds ``stride`` vector rows per order; H is (1, LANES): the step in each lane. The chains of the
    ``count`` rows interleave.
    """

    @intrinsic
    def _update(typingctx, T, order, H, carry):
        if not (vector_arrays([T, H, carry]) and T.ndim == 3 and isinstance(order, types.Integer)):
            return None
        sig = types.void(T, order, H, carry)

        def codegen(context, builder, signature, args):
            v = Lanes(context, builder, signature, args, width)
            b = builder
            p = context.cast(builder, args[1], signature.args[1], types.intp)
            h = v.load(2, 0)
            acc = v.variables(count)
            for c in range(count):
                b.store(v.load(0, v.row(b, p, stride, c)), acc[c])
            with cgutils.for_range(b, b.sub(p, ir.Constant(p.type, 1))) as loop:
                k = b.sub(b.sub(p, ir.Constant(p.type, 1)), loop.index)  # order − 1 … 1
                for c in range(count):
                    b.store(b.fadd(b.fmul(b.load(acc[c]), h, flags=FUSE), v.load(0, v.row(b, k, stride, c)),
                                   flags=FUSE), acc[c])
            for c in range(count):
                y = v.load(0, c)
                inc = b.fsub(b.fmul(b.load(acc[c]), h), v.load(3, c))
                total = b.fadd(y, inc)
                v.store(b.fsub(b.fsub(total, y), inc), 3, c)
                v.store(total, 0, c)
            return context.get_dummy_value()

        return sig, codegen

    return _update
