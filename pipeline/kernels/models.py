"""The compiled models integrator kernels can call.

Every model (the fixed point with its built-in or plugin torques, the orbiting gyrostat, a plugin system) is compiled
from its traced equations (``model``): its right-hand side is one call of the generated kernel through its address
(stored in ``p``), its Taylor coefficients one call of the generated series kernel (``taylor_series``). numba caches
a kernel only if the functions it calls are module globals (a function passed as an argument or closed over is
recompiled in every process), hence calls through addresses, not callbacks: the integrator kernels, cached once,
take the parameter array only and serve every model (the indirect call costs little: benchmarks/plugin_speed.py).
"""

from __future__ import annotations

from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.kernels.layout import TRACED_ADDRESS
from gyrolab.kernels import model as _model, simd, taylor_series
from gyrolab.kernels.compiler import inline_kernel, kernel


@intrinsic
def _call_rhs(typingctx, address, t, y, p, out):
    """Call ``void f(double t, double* y, double* p, double* out)`` at ``address`` with the arrays' data."""
    return types.void(types.int64, types.float64, y, p, out), simd.call_address


def block_rhs(compiled) -> int:
    """The address of a compiled model's right-hand side by columns (``model.block_kernel``): the batch kernels'
    stages, for every model."""
    return _model.block_kernel(_model.traced_model(compiled))


@intrinsic
def call_block(typingctx, address, t, Y, P, out, count):
    """Call ``void f(double* t, double* Y, double* P, double* out, int64 count, int64 stride)`` at ``address`` with
    the arrays' data (``block_rhs``); the stride is Y's row length."""

    def codegen(context, builder, signature, args):
        Y_ = context.make_array(signature.args[2])(context, builder, args[2])
        return simd.call_address(context, builder, signature, args, [cgutils.unpack_tuple(builder, Y_.shape)[1]])

    return types.void(types.int64, t, Y, P, out, types.int64), codegen


@inline_kernel
def rhs(t, y, p, out):
    """out = f(t, y): one call of the model's generated right-hand side through the address p holds. Compiled
    code only."""
    _call_rhs(int(p[TRACED_ADDRESS]), t, y, p, out)


@kernel
def evaluate(t, y, p, out):
    """``rhs`` as a plain compiled call, for Python and the cold paths (a first evaluation, the initial step)."""
    rhs(t, y, p, out)


@inline_kernel
def taylor_coefficients(p, Y, order, t=0.0):
    """Fill Y[1..order] from Y[0]: one call of the model's generated series kernel (``taylor_series``), inlined
    into the integrator's step (as a call of its own, with the arrays' reference counting, it cost ~30 ns a step:
    a sixth of the step of the reference scene). Compiled code only."""
    taylor_series.coefficients(p, Y, order, t)
