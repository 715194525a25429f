"""The compiled models integrator kernels can call.

numba caches a kernel only if the functions it calls are module globals
(a function passed as an argument or closed over is recompiled in every
process), hence calls through addresses instead of callbacks.

Every model (the fixed point with its built-in or plugin torques, the orbiting gyrostat, a plugin system) is
compiled from its traced equations (``model``): one form, whose right-hand side is one call of
the generated kernel through its address (stored in ``p``) and whose Taylor coefficients are one call of the
generated series kernel (``taylor_series``): the integrator kernels, cached once, serve every model.
Measured (benchmarks/plugin_speed.py): the indirect call itself costs little.

With one form there is nothing to dispatch: the kernels take the parameter array only, and the right-hand side
and the series calls are inlined into each of them.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.kernels.layout import TRACED_ADDRESS
from gyrolab.kernels import model as _model, taylor_series
from gyrolab.kernels.compiler import inline_kernel, kernel


@intrinsic
def _call_rhs(typingctx, address, t, y, p, out):
    """Call ``void f(double t, double* y, double* p, double* out)`` at ``address`` with the arrays' data."""
    sig = types.void(types.int64, types.float64, y, p, out)

    def codegen(context, builder, signature, args):
        address_, t_, y_, p_, out_ = args
        double_ptr = ir.DoubleType().as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [ir.DoubleType(), double_ptr, double_ptr, double_ptr])
        data = [cgutils.create_struct_proxy(ty)(context, builder, value=v).data
                for ty, v in zip(signature.args[2:], (y_, p_, out_))]
        fn = builder.inttoptr(address_, fnty.as_pointer())
        builder.call(fn, [t_] + [builder.bitcast(d, double_ptr) for d in data])
        return context.get_dummy_value()

    return sig, codegen


def block_rhs(compiled) -> int:
    """The address of a compiled model's right-hand side by columns (``model.block_kernel``): the batch kernels'
    stages, for every model."""
    return _model.block_kernel(_model.traced_model(compiled))


@intrinsic
def call_block(typingctx, address, t, Y, P, out, count):
    """Call ``void f(double* t, double* Y, double* P, double* out, int64 count, int64 stride)`` at ``address`` with
    the arrays' data (``block_rhs``); the stride is Y's row length."""
    sig = types.void(types.int64, t, Y, P, out, types.int64)

    def codegen(context, builder, signature, args):
        double_ptr, i64 = ir.DoubleType().as_pointer(), ir.IntType(64)
        fnty = ir.FunctionType(ir.VoidType(), [double_ptr] * 4 + [i64, i64])
        arrays = [context.make_array(ty)(context, builder, v) for ty, v in zip(signature.args[1:5], args[1:5])]
        stride = cgutils.unpack_tuple(builder, arrays[1].shape)[1]
        data = [builder.bitcast(a.data, double_ptr) for a in arrays]
        builder.call(builder.inttoptr(args[0], fnty.as_pointer()), [*data, args[5], stride])
        return context.get_dummy_value()

    return sig, codegen


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
