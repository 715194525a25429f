"""The compiled models integrator kernels can call, selected by an integer id.

numba caches a kernel only if the functions it calls are module globals
(a function passed as an argument or closed over is recompiled in every
process), hence one dispatch on ``model`` instead of a callback. A force
plugin's torque, compiled separately (``plugin_torque``), joins through its
address, stored in the parameter array: the call is indirect, the kernels that
make it are compiled and cached once for every plugin.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.plugins.compiled import fixed_point, inline_kernel, plugin_taylor
from gyrolab.plugins.compiled.plugin_torque import ADDRESS

FIXED_POINT = 0
#: The fixed-point system with compiled plugin torques added.
FIXED_POINT_PLUGIN = 1
#: Models whose Taylor coefficients ``taylor_coefficients`` computes (plugin torques: see plugin_taylor.ready).
TAYLOR_MODELS = (FIXED_POINT, FIXED_POINT_PLUGIN)


@intrinsic
def _call_torque(typingctx, address, t, y, p, out):
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


@inline_kernel
def rhs(model, t, y, p, out):
    if model == FIXED_POINT:
        fixed_point.rhs(t, y, p, out)
    elif model == FIXED_POINT_PLUGIN:
        fixed_point.rhs(t, y, p, out)
        _call_torque(int(p[ADDRESS]), t, y, p, out)


@inline_kernel
def taylor_coefficients(model, p, Y, order, work, t=0.0):
    if model == FIXED_POINT:
        fixed_point.taylor_coefficients(p, Y, order, work)
    elif model == FIXED_POINT_PLUGIN:  # the traced torque's series by automatic propagation (plugin_taylor)
        plugin_taylor.coefficients(p, Y, order, work, t)
    else:
        raise ValueError("this compiled model has no Taylor coefficients")
