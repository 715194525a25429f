"""Regular precessions of the orbiting satellite-gyrostat (Yehia & El-kenani (2021)): motion and residuals, stability,
classification, numerical finder, the paper's case catalogue and printed closed forms."""

from gyrolab.analysis.precession.classify import Classification, classify
from gyrolab.analysis.precession.motion import Precession, build_system, euler_residual, theta_deviation, vector_residual
from gyrolab.analysis.precession.stability import Floquet, floquet

__all__ = ["Classification", "Floquet", "Precession", "build_system", "classify", "euler_residual", "floquet",
           "theta_deviation", "vector_residual"]
