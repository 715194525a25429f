"""The compiled models integrator kernels can call.

numba caches a kernel only if the functions it calls are module globals
(a function passed as an argument or closed over is recompiled in every
process), hence calls through addresses instead of callbacks.

Every model (the fixed point with its built-in or plugin torques, the orbiting gyrostat, a plugin system) is
compiled from its traced equations (``model``): one form, ``TRACED``, whose right-hand side is one call of
the generated kernel through its address (stored in ``p``) and whose Taylor coefficients are one call of the
generated series kernel (``taylor_series``): the integrator kernels, cached once, serve every model.
Measured (benchmarks/plugin_speed.py): the indirect call itself costs little.

A kernel given the model as an int dispatches at run time, so every model's code
is typed and compiled into it. Given a ``Form`` (``form(compiled)``), the model is
part of the argument's type: numba compiles a specialisation of the kernel per form,
containing that form's code only, and caches each on disk like any other signature.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.datamodel.models import OpaqueModel
from numba.core.imputils import lower_constant
from numba.extending import NativeValue, intrinsic, overload, register_model, unbox

from gyrolab.kernels.layout import TRACED_ADDRESS
from gyrolab.kernels import model as _model, taylor_series
from gyrolab.kernels.compiler import inline_kernel, kernel

#: A model compiled from its traced equations (``model``): every model.
TRACED = _model.TRACED


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


class FormType(types.Type):
    def __init__(self, id: int) -> None:
        self.id = id
        super().__init__(name=f"gyrolab.Form({id})")


class Form:
    """A model as the kernels' argument: its form id becomes part of the argument's numba type (``FormType``).

    ``_numba_type_`` gives numba the type without a call back into Python: a kernel call with a Form costs
    ~1 µs more than with an int (11 µs when numba had to ask a Python typing function).
    """

    __slots__ = ("id", "_numba_type_")

    def __init__(self, id: int) -> None:
        self.id = id
        self._numba_type_ = FormType(id)

    def __repr__(self) -> str:
        return f"Form({self.id})"


register_model(FormType)(OpaqueModel)  # no data: everything is in the type


@unbox(FormType)
def _unbox_form(typ, obj, c):
    return NativeValue(c.context.get_dummy_value())


@lower_constant(FormType)
def _constant_form(context, builder, ty, value):
    return context.get_dummy_value()


FORMS = {TRACED: Form(TRACED)}


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


def form(compiled) -> Form:
    """The kernels' model argument for a ``CompiledModel``: compiles and runs its form's code only."""
    return FORMS[compiled.model]


@inline_kernel
def _traced(t, y, p, out):
    _call_rhs(int(p[TRACED_ADDRESS]), t, y, p, out)


_RHS = {TRACED: _traced}


def rhs(model, t, y, p, out):
    """out = f(t, y) of ``model`` (an int: dispatch at run time; a ``Form``: that form's code only). Compiled code only."""
    raise TypeError("models.rhs is called from compiled kernels only (use models.evaluate)")


@overload(rhs, inline="never", jit_options={"error_model": "numpy"})
def _rhs_form(model, t, y, p, out):
    """A form's code as a plain call: compiled once per process and linked into every kernel."""
    if isinstance(model, FormType):
        f = _RHS[model.id]
        return lambda model, t, y, p, out: f(t, y, p, out)
    return None


_TRACED = FORMS[TRACED]


@inline_kernel
def _rhs_any(model, t, y, p, out):
    """The run-time dispatch: a branch per form, each the form's plain call."""
    if model == TRACED:
        rhs(_TRACED, t, y, p, out)


@overload(rhs, inline="always")
def _rhs_any_model(model, t, y, p, out):
    """The run-time dispatch (an int model), inlined at numba's level: compiled as one function calling every
    form it was too large for LLVM to inline into the kernels' loops, which ran up to 1.7× slower."""
    if isinstance(model, types.Integer):
        return lambda model, t, y, p, out: _rhs_any(model, t, y, p, out)
    return None


@kernel
def evaluate(model, t, y, p, out):
    """``rhs`` as a plain compiled call, for the cold paths (a first evaluation, the initial step).

    With an int model ``rhs`` is inlined into its callers at numba's level, typed again in each: callers
    outside the inner loops call this instead, so that the first compile types it once.
    """
    rhs(model, t, y, p, out)


@inline_kernel
def _taylor_any(model, p, Y, order, t):
    if model == TRACED:  # the traced equations' series (taylor_series)
        taylor_series.coefficients(p, Y, order, t)
    else:
        raise ValueError("this compiled model has no Taylor coefficients")


def taylor_coefficients(model, p, Y, order, t=0.0):
    """Fill Y[1..order] from Y[0] (``model`` as in ``rhs``). Compiled code only."""
    raise TypeError("models.taylor_coefficients is called from compiled kernels only")


@overload(taylor_coefficients, inline="never", jit_options={"error_model": "numpy"})
def _taylor_coefficients(model, p, Y, order, t=0.0):
    if isinstance(model, types.Integer):
        return lambda model, p, Y, order, t=0.0: _taylor_any(model, p, Y, order, t)
    return None


@overload(taylor_coefficients, inline="always")
def _taylor_coefficients_traced(model, p, Y, order, t=0.0):
    """The traced form: one call of its generated series kernel (``taylor_series``), inlined into the
    integrator's step (as a call of its own, with the arrays' reference counting, it cost ~30 ns a step:
    a sixth of the step of the reference scene)."""
    if isinstance(model, FormType) and model.id == TRACED:
        return lambda model, p, Y, order, t=0.0: taylor_series.coefficients(p, Y, order, t)
    return None
