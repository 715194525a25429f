"""Double-double arithmetic (≈ 32 significant digits) for the compiled kernels.

A double-double number is an unevaluated sum hi + lo of two doubles with |lo| ≤ ulp(hi)/2: a 106-bit
significand, unit round-off u² = 2^-106 per operation (Dekker 1971; Hida, Li & Bailey's QD library, 2001).
Every function takes and returns plain floats (a number is two arguments, a result a pair), so numba
inlines them into the kernels as scalar code in registers: no arrays, no objects.

The error-free transformations are exact:

* ``two_sum(a, b) = (s, e)`` with s = fl(a + b) and s + e = a + b exactly (Knuth, 6 flops, any order);
* ``quick_two_sum(a, b)``: the same in 3 flops when |a| ≥ |b| (Dekker);
* ``two_prod(a, b) = (p, e)`` with p = fl(a·b) and p + e = a·b exactly: e = fma(a, b, −p), one fused
  multiply-add (``fma``: LLVM's ``llvm.fma.f64``, one instruction on x86-64 with FMA, a correctly rounded
  library call elsewhere).

The double-double operations round: ``dd_add`` (the accurate "IEEE" addition, relative error ≤ 2u² even
under cancellation), ``dd_mul`` and ``dd_mul_d`` (≤ ~4u²), ``dd_div_d`` (a double-double over a double,
≤ ~4u²). ``dot_add`` is the inner step of a compensated dot product (Ogita, Rump & Oishi's Dot2): the
products' high parts summed by ``two_sum``, every low part gathered in one double, so a sum of n products
has an error ≤ ~n·u²·Σ|terms| at about a third of the cost of ``dd_mul`` then ``dd_add`` per term; ``dd_norm``
renormalises the result. The kernels are compiled without fast-math: reassociation would optimise the
error terms away (they are 0 in real arithmetic).
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from gyrolab.kernels.compiler import inline_kernel


@intrinsic
def fma(typingctx, a, b, c):
    """a·b + c with one rounding (``llvm.fma.f64``)."""
    if not all(isinstance(x, types.Float) for x in (a, b, c)):
        return None
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        args = [context.cast(builder, v, t, types.float64) for v, t in zip(args, signature.args)]
        double = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [double], ir.FunctionType(double, [double] * 3))
        return builder.call(fn, args)

    return sig, codegen


@inline_kernel
def two_sum(a, b):
    """(s, e): s = fl(a + b), s + e = a + b exactly."""
    s = a + b
    bb = s - a
    e = (a - (s - bb)) + (b - bb)
    return s, e


@inline_kernel
def quick_two_sum(a, b):
    """(s, e): s = fl(a + b), s + e = a + b exactly, provided |a| ≥ |b| (or a = 0)."""
    s = a + b
    e = b - (s - a)
    return s, e


@inline_kernel
def two_prod(a, b):
    """(p, e): p = fl(a·b), p + e = a·b exactly (no overflow or underflow), by one fused multiply-add."""
    p = a * b
    e = fma(a, b, -p)
    return p, e


@inline_kernel
def dd_norm(hi, lo):
    """The normalised double-double of hi + lo (any two doubles)."""
    return two_sum(hi, lo)


@inline_kernel
def dd_add(ah, al, bh, bl):
    """a + b, relative error ≤ 2u² (QD's accurate addition: no loss under cancellation)."""
    s, e = two_sum(ah, bh)
    t, f = two_sum(al, bl)
    e += t
    s, e = quick_two_sum(s, e)
    e += f
    return quick_two_sum(s, e)


@inline_kernel
def dd_add_d(ah, al, b):
    """a + b for a double b."""
    s, e = two_sum(ah, b)
    e += al
    return quick_two_sum(s, e)


@inline_kernel
def dd_mul(ah, al, bh, bl):
    """a·b (the al·bl term, below u² relative, left out)."""
    p, e = two_prod(ah, bh)
    e = fma(ah, bl, e)
    e = fma(al, bh, e)
    return quick_two_sum(p, e)


@inline_kernel
def dd_mul_d(ah, al, b):
    """a·b for a double b."""
    p, e = two_prod(ah, b)
    e = fma(al, b, e)
    return quick_two_sum(p, e)


@inline_kernel
def dd_div_d(ah, al, b):
    """a / b for a double b (a correction of the double quotient by its exact residual)."""
    q1 = ah / b
    p, e = two_prod(q1, b)
    s, f = two_sum(ah, -p)
    f -= e
    f += al
    q2 = (s + f) / b
    return quick_two_sum(q1, q2)


@inline_kernel
def dd_div(ah, al, bh, bl):
    """a / b for double-doubles (QD's sloppy division: two quotient digits, relative error ≤ ~10u²)."""
    q1 = ah / bh
    rh, rl = dd_mul_d(bh, bl, q1)
    sh, sl = dd_add(ah, al, -rh, -rl)
    q2 = sh / bh
    rh, rl = dd_mul_d(bh, bl, q2)
    sh, sl = dd_add(sh, sl, -rh, -rl)
    q3 = sh / bh
    q1, q2 = quick_two_sum(q1, q2)
    return dd_add_d(q1, q2, q3)


@inline_kernel
def dot_add(sh, sl, ah, al, bh, bl):
    """(sh, sl) + a·b for a compensated sum of products: sh collects the products' high parts (error-free, by
    ``two_sum``), sl every error and low part in plain double. The pair is not normalised: finish with ``dd_norm``."""
    p, e = two_prod(ah, bh)
    e = fma(ah, bl, e)
    e = fma(al, bh, e)
    s, t = two_sum(sh, p)
    return s, sl + (t + e)
