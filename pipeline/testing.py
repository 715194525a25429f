"""Contract checks for force-plugin authors: ``check_force(ForceClass, **params)`` in your own tests.

Like scikit-learn's ``check_estimator``: it builds the force on a triaxial test body and checks the
rules of ``gyrolab.contracts.Force`` one by one, raising ``AssertionError`` that names the first
violation:

1. the force builds with ``params``, declares ``preserves_area_integral`` (a bool) and
   ``required_axes`` within {0, 1, 2};
2. ``torque`` returns a finite float array of shape (3,) at random states, reading only the
   declared axes (the others are passed as None);
3. ``preserves_area_integral`` is right: True exactly when torque·γ = 0 at every random state
   (d(Iω·γ)/dt = torque·γ);
4. a ``potential`` belongs to the torque: torque = Σ e_i × ∂V/∂e_i, the derivative of V under
   small rotations of the body (central differences), and V is vectorised over (n, 3) axes;
5. ``attributes()`` are netCDF-safe (names of letters, digits and _; values str, int, float or
   non-empty lists of numbers, all finite);
6. every keyword parameter given a nonsense value ("abc") raises gyrolab's one-sentence
   ``ConfigError`` naming the parameter when gyrolab builds the force (parameters whose default
   is None only when ``params`` gives them);
7. the compiled torque (traced from ``torque``, see ``gyrolab.plugins.compiled.plugin_torque``)
   equals the Python torque; a torque that cannot be traced is reported as a warning, not a
   failure (it then runs with the Python integrators only).
"""

from __future__ import annotations

import inspect
import math
import re
import warnings
from typing import Any

import numpy as np

from gyrolab.contracts.claims import _rotation, axes_of as _axes, random_states, rotation_torque  # noqa: F401
from gyrolab.contracts.force import Force
from gyrolab.errors import ConfigError

__all__ = ["check_force", "random_states", "rotation_torque"]

#: Relative tolerance of the finite-difference potential check (central differences, h = 1e-5).
POTENTIAL_RTOL = 1e-6
#: torque·γ below this fraction of |torque| counts as "no component along the vertical".
AREA_RTOL = 1e-12
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def _test_body():
    from gyrolab.physics.body import Body

    return Body.from_config({"units": "nondimensional", "a": 0.7, "b": 0.9, "com_direction": [0.3, 0.4, 0.866025403784]})


def _call(force: Force, omega: np.ndarray, frame: np.ndarray, t: float) -> Any:
    axes = _axes(force, frame)
    return force.torque(omega, axes, t) if force.time_dependent else force.torque(omega, axes)


def _fail(cls: type, message: str) -> AssertionError:
    return AssertionError(f"{cls.__name__}: {message}")


def check_force(cls: type, body: Any = None, *, n_states: int = 20, **params: Any) -> None:
    """Check a force plugin class against the Force contract; AssertionError names the first violation.

    ``params`` are the plugin's keyword parameters for the checks (its defaults when omitted);
    ``body`` defaults to a triaxial nondimensional body with an off-axis centre of mass.
    """
    from gyrolab.engine.scene import build_force

    if not (isinstance(cls, type) and issubclass(cls, Force)):
        raise AssertionError(f"{cls!r} is not a subclass of gyrolab.contracts.Force")
    body = _test_body() if body is None else body
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not _NAME.match(name):
        raise _fail(cls, f"name={name!r} must be a string of letters, digits and _ (the config key force.NAME)")
    where = f"force.{name}"
    params = {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in params.items()}  # as a config gives them
    try:
        force = build_force(cls, dict(params), where, body)
    except ConfigError as exc:
        raise _fail(cls, f"building it with {params} raised ConfigError: {exc}") from None
    _check_declarations(cls, force)
    omegas, frames = random_states(n_states)
    torques = _check_torque(cls, force, omegas, frames)
    _check_area_flag(cls, force, torques, frames)
    if force.conservative:
        _check_potential(cls, force, frames)
    _check_attributes(cls, force)
    _check_bad_parameters(cls, body, where, params)
    _check_compiled(cls, force, body, omegas, frames)


def _check_declarations(cls: type, force: Force) -> None:
    axes = force.required_axes
    if not isinstance(axes, (set, frozenset)) or not set(axes) <= {0, 1, 2}:
        raise _fail(cls, f"required_axes={axes!r} must be a frozenset of axis indices 0, 1, 2")


def _check_torque(cls: type, force: Force, omegas: np.ndarray, frames: np.ndarray) -> np.ndarray:
    torques = np.empty_like(omegas)
    for k, (omega, frame) in enumerate(zip(omegas, frames)):
        try:
            value = _call(force, omega.copy(), frame, 0.7 * k)
        except TypeError as exc:
            if "NoneType" in str(exc):
                raise _fail(cls, f"torque reads a reference axis not in required_axes={set(force.required_axes)} "
                                 f"({exc}); declare every axis it reads") from None
            raise
        value = np.asarray(value)
        if value.shape != (3,) or not np.issubdtype(value.dtype, np.floating):
            raise _fail(cls, f"torque returned shape {value.shape} and dtype {value.dtype}; it must be a float "
                             "array of shape (3,) (body components)")
        if not np.all(np.isfinite(value)):
            raise _fail(cls, f"torque is not finite at ω={omega.tolist()}: {value.tolist()}")
        torques[k] = value
    return torques


def _check_area_flag(cls: type, force: Force, torques: np.ndarray, frames: np.ndarray) -> None:
    along = np.abs(np.einsum("ij,ij->i", torques, frames[:, 2, :]))
    scale = np.maximum(np.linalg.norm(torques, axis=1), 1e-300)
    worst = int(np.argmax(along / scale))
    preserved = bool(np.all(along <= AREA_RTOL * scale))
    if force.preserves_area_integral and not preserved:
        raise _fail(cls, f"preserves_area_integral is True, but the torque has a component {along[worst]:.3g} along "
                         f"the vertical γ (|torque| = {scale[worst]:.3g}), so the area integral Iω·γ is not "
                         "conserved; declare False")
    if not force.preserves_area_integral and preserved and np.any(np.linalg.norm(torques, axis=1) > 0):
        raise _fail(cls, "preserves_area_integral is False, but torque·γ = 0 at every random state, so the area "
                         "integral Iω·γ is conserved; declare True (or check with parameters that break the symmetry)")


def _check_potential(cls: type, force: Force, frames: np.ndarray) -> None:
    values = np.asarray(force.potential(_axes(force, frames)), dtype=float)
    if values.shape != (len(frames),) or not np.all(np.isfinite(values)):
        raise _fail(cls, f"potential for axes of shape ({len(frames)}, 3) returned shape {values.shape}"
                         f"{'' if np.all(np.isfinite(values)) else ' with non-finite values'}; it must be "
                         "vectorised over a trajectory, one finite energy per state")
    omega = np.zeros(3)
    for frame in frames:
        expected = rotation_torque(force, frame)
        actual = np.asarray(_call(force, omega, frame, 0.0), dtype=float)
        scale = max(np.max(np.abs(expected)), np.max(np.abs(actual)), 1e-300)
        if np.max(np.abs(actual - expected)) > POTENTIAL_RTOL * scale + 1e-12:
            raise _fail(cls, f"potential does not belong to the torque: at ω = 0 the torque is "
                             f"{np.round(actual, 9).tolist()} but Σ e_i × ∂V/∂e_i of the potential (finite "
                             f"differences) is {np.round(expected, 9).tolist()}; fix potential or torque")


def _netcdf_safe(value: Any) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, str):
        return True
    if isinstance(value, (int, float, np.integer, np.floating)):
        return math.isfinite(float(value))
    if isinstance(value, (list, tuple, np.ndarray)):
        items = list(np.asarray(value, dtype=object).reshape(-1))
        return bool(items) and all(not isinstance(v, (bool, np.bool_, str)) and _netcdf_safe(v) for v in items)
    return False


def _check_attributes(cls: type, force: Force) -> None:
    attrs = force.attributes()
    if not isinstance(attrs, dict):
        raise _fail(cls, f"attributes() returned {type(attrs).__name__}, not a dict")
    for key, value in attrs.items():
        if not isinstance(key, str) or not _NAME.match(key):
            raise _fail(cls, f"attributes() key {key!r} is not a netCDF-safe name (letters, digits, _)")
        if not _netcdf_safe(value):
            raise _fail(cls, f"attributes()[{key!r}] = {value!r} is not netCDF-safe; use str, int, float or a "
                             "non-empty list of finite numbers (no bool, None or dict)")


def _check_bad_parameters(cls: type, body: Any, where: str, params: dict[str, Any]) -> None:
    from gyrolab.engine.scene import build_force

    for key, param in inspect.signature(cls.__init__).parameters.items():
        if param.kind is not inspect.Parameter.KEYWORD_ONLY or (param.default is None and key not in params):
            continue  # a parameter off by default is checked when the caller gives it
        for bad in ("abc",):  # NaN and inf never reach a plugin: the scene refuses non-finite config values
            try:
                build_force(cls, {**params, key: bad}, where, body)
            except ConfigError as exc:
                message = str(exc)
                if key not in message or "\n" in message.strip():
                    raise _fail(cls, f"{key}={bad!r} raised a ConfigError that does not name the parameter in one "
                                     f"line: {message!r}") from None
                continue
            except Exception as exc:  # noqa: BLE001  (anything but ConfigError is the violation)
                raise _fail(cls, f"{key}={bad!r} raised {type(exc).__name__}: {exc}; raise gyrolab.errors."
                                 "ConfigError naming the parameter (gyrolab.errors.as_number validates numbers)") \
                    from None
            raise _fail(cls, f"{key}={bad!r} was accepted; validate the parameter and raise gyrolab.errors."
                             "ConfigError (gyrolab.errors.as_number does it for numbers)")


def _check_compiled(cls: type, force: Force, body: Any, omegas: np.ndarray, frames: np.ndarray) -> None:
    if force.compiled_terms() is not None:
        return  # a built-in form; the system's tests compare it with the Python right-hand side
    from gyrolab.plugins.compiled import plugin_torque

    try:
        traced = plugin_torque.compile_trace(plugin_torque.trace([force]), [force.name])
    except plugin_torque.NotCompilable as exc:
        warnings.warn(f"{cls.__name__} runs with the Python integrators only: {exc}", stacklevel=3)
        return
    import ctypes

    kernel = ctypes.CFUNCTYPE(None, ctypes.c_double, *[ctypes.POINTER(ctypes.c_double)] * 3)(traced.address)
    p = np.zeros(plugin_torque.FIRST_CONSTANT + len(traced.constants))
    p[plugin_torque.INV_INERTIA:plugin_torque.INV_INERTIA + 3] = 1.0  # read back the torque itself, not I⁻¹ T
    p[plugin_torque.FIRST_CONSTANT:] = traced.constants
    ptr = ctypes.POINTER(ctypes.c_double)
    for k, (omega, frame) in enumerate(zip(omegas, frames)):
        y = np.concatenate([omega, frame[2], frame[0]])
        out = np.zeros(3)
        kernel(0.7 * k, y.ctypes.data_as(ptr), p.ctypes.data_as(ptr), out.ctypes.data_as(ptr))
        expected = np.asarray(_call(force, omega.copy(), frame, 0.7 * k), dtype=float)
        if not np.allclose(out, expected, rtol=1e-12, atol=1e-14 * max(1.0, np.max(np.abs(expected)))):
            raise _fail(cls, f"the compiled torque {out.tolist()} differs from the Python torque {expected.tolist()} "
                             f"at ω={omega.tolist()}; report this to gyrolab with the plugin's torque")
