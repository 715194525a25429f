"""The compiled models integrator kernels can call, selected by an integer id.

numba caches a kernel only if the functions it calls are module globals
(a function passed as an argument or closed over is recompiled in every
process), hence one dispatch on ``model`` instead of a callback.
"""

from __future__ import annotations


from gyrolab.plugins.compiled import fixed_point, inline_kernel

FIXED_POINT = 0


@inline_kernel
def rhs(model, t, y, p, out):
    if model == FIXED_POINT:
        fixed_point.rhs(t, y, p, out)


@inline_kernel
def taylor_coefficients(model, p, Y, order, work):
    if model == FIXED_POINT:
        fixed_point.taylor_coefficients(p, Y, order, work)
