"""Classification of a regular precession ψ = nt + ψ0, θ = θ0, φ = mt: rest, permanent rotation or regular
precession in the orbital and inertial frames (ω = (n + Ω) γ + m e3), and the geometric type of the surface the body
z axis sweeps (definitions, and why the paper's "conical" and "hyperboloidal" are interchanged: docs/gyrostat.md,
"Classification").
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
