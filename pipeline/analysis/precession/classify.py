"""Classification of a regular precession ψ = nt + ψ0, θ = θ0, φ = mt (definitions in docs/gyrostat.md).

Angular velocity relative to the orbital frame: ω′ = n γ + m e3; absolute: ω = (n + Ω) γ + m e3
(the orbital frame turns about the inertially fixed γ at Ω), so in the inertial frame the same
motion has precession rate n + Ω. In a frame, with precession rate ν about γ and spin m:

* **rest** if ν γ + m e3 = 0;
* **permanent rotation** if the angular velocity is constant in the body and in the frame:
  e3 ∥ γ (θ0 ∈ {0, π}) or ν = 0 or m = 0;
* **regular precession** otherwise (both rates non-zero, e3 ∦ γ).

Geometric type, defined when e3 is fixed in the orbital frame (n = 0 or θ0 ∈ {0, π}), from the
surface the body's z axis (a line through the centre of mass) sweeps in inertial space as the
orbital frame turns about the orbit normal through the Earth's centre: **cylindrical** if e3 ∥ γ;
**conical** if e3 lies in the radial–normal plane (α, γ) (the line meets the orbit-normal axis);
**hyperboloidal** if e3 has an along-track component (one-sheet hyperboloid). e3 in orbital
components is (sin ψ0 sin θ0, −cos ψ0 sin θ0, cos θ0). With these definitions the paper's labels
"conical" (17) and "hyperboloidal" (19), (24) are interchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gyrolab.analysis.precession.motion import Precession

TOL = 1e-10


@dataclass(frozen=True)
class Classification:
    orbital: str
    inertial: str
    geometric: str

    def __str__(self) -> str:
        return f"orbital frame: {self.orbital}; inertial frame: {self.inertial}; axis: {self.geometric}"


def body_axis_orbital(motion: Precession) -> np.ndarray:
    """e3 in orbital components at t = 0 (fixed in the orbital frame when n = 0)."""
    s, c = np.sin(motion.theta0), np.cos(motion.theta0)
    return np.array([np.sin(motion.psi0) * s, -np.cos(motion.psi0) * s, c])


def _kind(rate: float, motion: Precession, along_normal: bool) -> str:
    e3 = body_axis_orbital(motion)
    w = rate * np.array([0.0, 0.0, 1.0]) + motion.m * e3
    size = float(np.linalg.norm(w))
    if size < TOL:
        return "rest"
    if along_normal or abs(rate) < TOL or abs(motion.m) < TOL:
        return f"permanent rotation (|ω| = {size:.4g})"
    return f"regular precession (precession {rate:.4g}, spin {motion.m:.4g})"


def classify(motion: Precession, Omega: float) -> Classification:
    """Classify a regular precession of the satellite-gyrostat (Yehia & El-kenani 2021).

    Parameters
    ----------
    motion : Precession
        The precession (its rates ``n`` about the orbit normal and ``m`` about the body axis).
    Omega : float
        The orbit rate Ω (> 0), which turns the orbital-frame rate n into the inertial one n + Ω.

    Returns
    -------
    Classification
        The kind of motion in the orbital frame and in the inertial frame (permanent rotation or
        regular precession) and the geometric class of the body axis' path: ``"cylindrical"``
        (along the orbit normal), ``"conical"``, ``"hyperboloidal"``, or ``"axis moves in the
        orbital frame"``.
    """
    e3 = body_axis_orbital(motion)
    along_normal = bool(np.hypot(e3[0], e3[1]) < TOL)
    if along_normal:
        geometric = "cylindrical"
    elif abs(motion.n) > TOL:
        geometric = "axis moves in the orbital frame"
    elif abs(e3[1]) < TOL:
        geometric = "conical"
    else:
        geometric = "hyperboloidal"
    return Classification(_kind(motion.n, motion, along_normal), _kind(motion.n + Omega, motion, along_normal),
                          geometric)
