"""The rigid body of a fixed-point scene, in SI or in the papers' nondimensional form.

Two equivalent ways to give a body (``body.units``):

* ``si``: principal moments of inertia ``inertia = [A, B, C]`` (kg m²),
  ``mass`` M (kg), centre of mass ``com = [x0, y0, z0]`` (m, body axes) and
  gravity ``g`` (m/s²). The model runs in SI: time in s, ω in rad/s.
* ``nondimensional`` (the papers' form, Ismail (2021) and Shaker et al.): ``a = A/C``,
  ``b = B/C``, unit centre-of-mass direction ``com_direction = [x0', y0', z0']``.
  Inertia is measured in units of C, time in units of 1/c with
  c² = M g ℓ / C (ℓ = |r_c|), angular velocity in units of c, torques in
  units of C c². The papers' p0, q0, r0 are then p/c, q/c, r/c.

Either way the system sees "model units": an inertia vector and the moment
of the weight M g r_c, in which the Euler–Poisson equations take one form.
An SI body also reports its nondimensional form (a, b, direction, c²); a
nondimensional body is scale-free, so its SI form is not determined.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.errors import ConfigError, as_number, as_vector3, choices

UNITS = ("si", "nondimensional")
_SI_KEYS = ("inertia", "mass", "com", "g")
_NONDIM_KEYS = ("a", "b", "com_direction")
UNIT_TOLERANCE = 1e-9


def _model_unit(si: str) -> property:
    """A CF unit that is ``si`` for an SI body and "1" in a nondimensional form."""
    return property(lambda self: si if self.units == "si" else "1", doc=f"{si!r} (SI) or '1' (nondimensional)")


class ModelUnits:
    """CF units of a body's model quantities: SI, or dimensionless ("1") in a nondimensional form.

    Subclasses say in ``time_label``/``rate_label`` what the nondimensional unit is (1/c, 1/Ω, ...).
    """

    units: str
    time_unit = _model_unit("s")
    rate_unit = _model_unit("rad s-1")
    torque_unit = _model_unit("N m")
    energy_unit = _model_unit("J")
    momentum_unit = _model_unit("kg m2 s-1")


@dataclass(frozen=True)
class Body(ModelUnits):
    """A rigid body in model units (see module docstring)."""

    units: str
    inertia: np.ndarray  # (A, B, C) in model units
    weight_moment: np.ndarray  # M g r_c in model units (torque units)
    g: float | None  # gravity in model units (SI only; None when scale-free)
    nonphysical: bool  # inertia violates the triangle inequality (allowed explicitly)
    source: dict[str, Any]  # the config values as given, for the dataset

    @property
    def time_label(self) -> str:
        return "s" if self.units == "si" else "1/c"

    @property
    def rate_label(self) -> str:
        return "rad/s" if self.units == "si" else "c"

    @classmethod
    def from_config(cls, cfg: Any) -> Body:
        """Validate a ``body`` config section and convert it to model units."""
        cfg = dict(cfg)
        units = cfg.get("units")
        if units not in UNITS:
            raise ConfigError(f"body.units={units!r} is not valid; valid choices: {choices(UNITS)}")
        given = {k for k, v in cfg.items() if v is not None}
        foreign = sorted(given & set(_NONDIM_KEYS if units == "si" else _SI_KEYS))
        if foreign:
            raise ConfigError(
                f"body.{foreign[0]} is a {'nondimensional' if units == 'si' else 'SI'} parameter but "
                f"body.units={units}; give {', '.join('body.' + k for k in (_SI_KEYS if units == 'si' else _NONDIM_KEYS))}"
            )
        allow_nonphysical = bool(cfg.get("allow_nonphysical", False))
        if units == "si":
            inertia = np.array(as_vector3(_required(cfg, "inertia"), "body.inertia"))
            mass = as_number(_required(cfg, "mass"), "body.mass", nonnegative=True)
            com = np.array(as_vector3(_required(cfg, "com"), "body.com"))
            g = as_number(_required(cfg, "g"), "body.g", nonnegative=True)
            weight_moment = mass * g * com
        else:
            a = as_number(_required(cfg, "a"), "body.a", positive=True)
            b = as_number(_required(cfg, "b"), "body.b", positive=True)
            direction = np.array(as_vector3(_required(cfg, "com_direction"), "body.com_direction"))
            length = float(np.linalg.norm(direction))
            if length != 0.0 and abs(length - 1.0) > UNIT_TOLERANCE:
                raise ConfigError(
                    f"body.com_direction={direction.tolist()} has norm {length:.12g}; it must be a unit vector "
                    f"(|r_c| = 1 within {UNIT_TOLERANCE:g}) or zero for a body balanced on its fixed point"
                )
            inertia = np.array([a, b, 1.0])
            weight_moment = direction  # c^2 = Mgl/C = 1 in model units
            g = None
        _check_inertia(inertia, allow_nonphysical)
        nonphysical = not _satisfies_triangle(inertia)
        source = {k: v for k, v in cfg.items() if v is not None}
        return cls(units, inertia, weight_moment, g, nonphysical, source)

    def nondimensional(self) -> dict[str, Any]:
        """The papers' form of this body: a, b, unit centre-of-mass direction, and c² (SI bodies)."""
        A, B, C = self.inertia
        out: dict[str, Any] = {"a": A / C, "b": B / C}
        moment = math.sqrt(self.weight_moment.dot(self.weight_moment))  # np.linalg.norm's value, 5× faster
        out["com_direction"] = (self.weight_moment / moment).tolist() if moment > 0 else [0.0, 0.0, 0.0]
        if self.units == "si":
            out["c2"] = moment / C  # M g l / C in 1/s^2
        return out

    def attributes(self) -> dict[str, Any]:
        """Dataset attributes describing the body in both forms (netCDF-safe types)."""
        attrs: dict[str, Any] = {"body_units": self.units, "body_nonphysical": int(self.nonphysical)}
        for key, value in self.source.items():
            if key != "units":
                attrs[f"body_{key}"] = _netcdf_safe(value)
        for key, value in self.nondimensional().items():
            attrs[f"body_nondim_{key}"] = _netcdf_safe(value)
        if self.units == "si":
            c2 = self.nondimensional()["c2"]
            attrs["body_time_scale_1_over_c"] = 1.0 / math.sqrt(c2) if c2 > 0 else float("inf")
        return attrs


def _required(cfg: dict[str, Any], key: str) -> Any:
    value = cfg.get(key)
    if value is None:
        raise ConfigError(f"body.{key} is missing; a body with units={cfg.get('units')} needs it")
    return value


def _satisfies_triangle(inertia: np.ndarray) -> bool:
    A, B, C = inertia
    scale = 1e-12 * (A + B + C)
    return A + B >= C - scale and B + C >= A - scale and C + A >= B - scale


def _check_inertia(inertia: np.ndarray, allow_nonphysical: bool) -> None:
    for name, value in zip("ABC", inertia):
        if value <= 0:
            raise ConfigError(f"moment of inertia {name}={value:g} must be positive")
    if not allow_nonphysical and not _satisfies_triangle(inertia):
        A, B, C = inertia
        raise ConfigError(
            f"inertia (A, B, C)=({A:g}, {B:g}, {C:g}) violates the triangle inequality "
            "(A+B≥C, B+C≥A, C+A≥B hold for every real body); set body.allow_nonphysical=true to study it anyway"
        )


def _netcdf_safe(value: Any) -> Any:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, (list, tuple)):
        return np.asarray(value, dtype=float)
    return value
