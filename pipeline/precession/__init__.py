"""Regular precessions of the orbiting satellite-gyrostat (seed 002): motion and residuals, stability,
classification, numerical finder, the paper's case catalogue and printed closed forms."""

from pipeline.precession.classify import Classification, classify
from pipeline.precession.motion import Precession, build_system, euler_residual, theta_deviation, vector_residual
from pipeline.precession.stability import Floquet, floquet

__all__ = ["Classification", "Floquet", "Precession", "build_system", "classify", "euler_residual", "floquet",
           "theta_deviation", "vector_residual"]
