"""The compiled models integrator kernels can call, selected by an integer id.

numba caches a kernel only if the functions it calls are module globals
(a function passed as an argument or closed over is recompiled in every
process), hence one dispatch on ``model`` instead of a callback. A force
plugin's torque, compiled separately (``plugin_torque``), joins through its
address, stored in the parameter array: the call is indirect, the kernels that
make it are compiled and cached once for every plugin.

A scene with a plugin traces all its forces, built-ins included, so the plugin
models compute only the gyroscopic torque and the kinematics around that call,
one model per state size. Measured (benchmarks/plugin_speed.py): the
indirect call itself costs little; what made plugins 1.5–2× slower than the
built-ins was the built-in form's code (its zero-filled torque terms and the
run-time branch on α) inlined at every right-hand-side call of the kernels.

A kernel given the model as an int dispatches at run time, so every model's code
is typed and compiled into it. Given a ``Form`` (``form(compiled)``), the model is
part of the argument's type: numba compiles a specialisation of the kernel per form,
containing that form's code only (a built-in (ω, γ) scene compiles neither the plugin
models nor the α terms), and caches each on disk like any other signature.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.datamodel.models import OpaqueModel
from numba.core.imputils import lower_constant
from numba.extending import NativeValue, intrinsic, overload, register_model, unbox

from gyrolab.plugins.compiled.layout import CARRIES_ALPHA, INERTIA, INV_INERTIA
from gyrolab.plugins.compiled import fixed_point, inline_kernel, kernel, plugin_taylor
from gyrolab.plugins.compiled.plugin_torque import ADDRESS

FIXED_POINT = 0
#: The fixed-point system (state ω, γ) with all its torques traced and compiled.
FIXED_POINT_PLUGIN = 1
#: The same with the state ω, γ, α.
FIXED_POINT_PLUGIN_ALPHA = 2
#: Not a model id (``CompiledModel.model`` is FIXED_POINT): the form of FIXED_POINT with the state ω, γ, α.
FIXED_POINT_ALPHA = 3
#: Models whose Taylor coefficients ``taylor_coefficients`` computes (plugin torques: see plugin_taylor.ready).
TAYLOR_MODELS = (FIXED_POINT, FIXED_POINT_PLUGIN, FIXED_POINT_PLUGIN_ALPHA)


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
def _free(y, p, out):
    """The torque-free fixed-point system: I⁻¹ (Iω × ω) and γ̇ = γ × ω (p laid out as fixed_point.pack)."""
    w0, w1, w2 = y[0], y[1], y[2]
    g0, g1, g2 = y[3], y[4], y[5]
    out[0] = (p[INERTIA + 1] - p[INERTIA + 2]) * w1 * w2 * p[INV_INERTIA]
    out[1] = (p[INERTIA + 2] - p[INERTIA]) * w2 * w0 * p[INV_INERTIA + 1]
    out[2] = (p[INERTIA] - p[INERTIA + 1]) * w0 * w1 * p[INV_INERTIA + 2]
    out[3] = g1 * w2 - g2 * w1
    out[4] = g2 * w0 - g0 * w2
    out[5] = g0 * w1 - g1 * w0


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


FORMS = {i: Form(i) for i in (FIXED_POINT, FIXED_POINT_PLUGIN, FIXED_POINT_PLUGIN_ALPHA, FIXED_POINT_ALPHA)}


def form(compiled) -> Form:
    """The kernels' model argument for a ``CompiledModel``: compiles and runs its form's code only."""
    if compiled.model == FIXED_POINT and compiled.params[CARRIES_ALPHA] != 0.0:
        return FORMS[FIXED_POINT_ALPHA]
    return FORMS[compiled.model]


@inline_kernel
def _plugin(t, y, p, out):
    _free(y, p, out)
    _call_torque(int(p[ADDRESS]), t, y, p, out)


@inline_kernel
def _plugin_alpha(t, y, p, out):
    _free(y, p, out)
    w0, w1, w2 = y[0], y[1], y[2]
    x0, x1, x2 = y[6], y[7], y[8]
    out[6] = x1 * w2 - x2 * w1
    out[7] = x2 * w0 - x0 * w2
    out[8] = x0 * w1 - x1 * w0
    _call_torque(int(p[ADDRESS]), t, y, p, out)


_RHS = {FIXED_POINT: fixed_point.rhs_gamma, FIXED_POINT_ALPHA: fixed_point.rhs_alpha,
        FIXED_POINT_PLUGIN: _plugin, FIXED_POINT_PLUGIN_ALPHA: _plugin_alpha}


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


_GAMMA, _ALPHA = FORMS[FIXED_POINT], FORMS[FIXED_POINT_ALPHA]
_PLUGIN, _PLUGIN_ALPHA = FORMS[FIXED_POINT_PLUGIN], FORMS[FIXED_POINT_PLUGIN_ALPHA]


@inline_kernel
def _rhs_any(model, t, y, p, out):
    """The run-time dispatch: a branch per form, each the form's plain call."""
    if model == FIXED_POINT:
        if p[CARRIES_ALPHA] != 0.0:
            rhs(_ALPHA, t, y, p, out)
        else:
            rhs(_GAMMA, t, y, p, out)
    elif model == FIXED_POINT_PLUGIN:
        rhs(_PLUGIN, t, y, p, out)
    elif model == FIXED_POINT_PLUGIN_ALPHA:
        rhs(_PLUGIN_ALPHA, t, y, p, out)


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
def _taylor_any(model, p, Y, order, work, t):
    if model == FIXED_POINT:
        fixed_point.taylor_coefficients(p, Y, order, work)
    elif model == FIXED_POINT_PLUGIN or model == FIXED_POINT_PLUGIN_ALPHA:  # the traced torque's series (plugin_taylor)
        plugin_taylor.coefficients(p, Y, order, work, t)
    else:
        raise ValueError("this compiled model has no Taylor coefficients")


def taylor_coefficients(model, p, Y, order, work, t=0.0):
    """Fill Y[1..order] from Y[0] (``model`` as in ``rhs``). Compiled code only."""
    raise TypeError("models.taylor_coefficients is called from compiled kernels only")


@overload(taylor_coefficients, inline="never", jit_options={"error_model": "numpy"})
def _taylor_coefficients(model, p, Y, order, work, t=0.0):
    if isinstance(model, FormType):
        if model.id in (FIXED_POINT, FIXED_POINT_ALPHA):
            f = fixed_point.taylor_gamma if model.id == FIXED_POINT else fixed_point.taylor_alpha
            return lambda model, p, Y, order, work, t=0.0: f(p, Y, order, work)
        return None  # the plugin forms: below
    if isinstance(model, types.Integer):
        return lambda model, p, Y, order, work, t=0.0: _taylor_any(model, p, Y, order, work, t)
    return None


@overload(taylor_coefficients, inline="always")
def _taylor_coefficients_plugin(model, p, Y, order, work, t=0.0):
    """A traced torque's form: one call of its generated series kernel (``plugin_taylor``), inlined into the
    integrator's step (as a call of its own, with the arrays' reference counting, it cost ~30 ns a step:
    a sixth of the step of the reference scene)."""
    if isinstance(model, FormType) and model.id in (FIXED_POINT_PLUGIN, FIXED_POINT_PLUGIN_ALPHA):
        return lambda model, p, Y, order, work, t=0.0: plugin_taylor.coefficients(p, Y, order, work, t)
    return None
