"""LLVM IR helpers of the kernels' intrinsics: calls of generated functions by address (``call_address``) and the
batch Taylor kernel's vector arithmetic (``batch_taylor``).

Arrays of doubles are seen as rows of vectors: a row holds one component of LANES trajectories (8 on AVX-512,
4 on AVX2). ``Lanes.log2`` and ``Lanes.exp2`` are vector powers for the lanes' step rule. Why intrinsics and not
numba loops: ``batch_taylor``'s docstring ("Why LLVM IR").
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils

FUSE = ("contract",)  # the series' multiply and add may fuse (a rounding's worth, as fastmath's contract)


def array_data(context, builder, ty, value):
    """The data pointer (double*) of the array ``value`` of numba type ``ty``."""
    return builder.bitcast(context.make_array(ty)(context, builder, value).data, ir.DoubleType().as_pointer())


def call_address(context, builder, signature, args, extra=()):
    """An intrinsic's codegen: call ``void f(...)`` at the address args[0] with the other arguments (each array as
    its data pointer, ``array_data``), then ``extra``."""
    values = [array_data(context, builder, ty, v) if isinstance(ty, types.Array) else v
              for ty, v in zip(signature.args[1:], args[1:])] + list(extra)
    fnty = ir.FunctionType(ir.VoidType(), [v.type for v in values])
    builder.call(builder.inttoptr(args[0], fnty.as_pointer()), values)
    return context.get_dummy_value()


def splat(b, x, lanes):
    """The scalar value ``x`` in every one of ``lanes`` lanes."""
    undef = ir.Constant(ir.VectorType(x.type, lanes), ir.Undefined)
    return b.shuffle_vector(b.insert_element(undef, x, ir.Constant(ir.IntType(32), 0)), undef,
                            ir.Constant(ir.VectorType(ir.IntType(32), lanes), [0] * lanes))


def vector_call(b, vec, name, *args):
    """The LLVM vector intrinsic ``llvm.NAME`` (fabs, rint, sqrt, ...) on ``args`` of the vector type ``vec``."""
    fn = cgutils.get_or_insert_function(b.module, ir.FunctionType(vec, [vec] * len(args)),
                                        f"llvm.{name}.v{vec.count}f64")
    return b.call(fn, list(args))


def vector_arrays(arrays) -> bool:
    """The intrinsics' arrays: C-contiguous float64, a row of LANES doubles innermost."""
    return all(isinstance(a, types.Array) and a.layout == "C" and a.dtype == types.float64 for a in arrays)


class Lanes:
    """LLVM IR helpers of the intrinsics: arrays of doubles seen as rows of ``<LANES x double>`` vectors."""

    def __init__(self, context, builder, signature, args, width):
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
        return vector_call(self.builder, self.vec, name, *args)

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
