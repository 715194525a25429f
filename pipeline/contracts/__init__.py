"""The contracts every plugin implements: forces, systems, integrators, regimes.

Each contract's docstring lists the rules an implementer follows; plugins in
``plugins/`` (and third-party packages, through entry points) subclass them.
"""

from pipeline.contracts.force import Force
from pipeline.contracts.integrator import Integrator, IntegratorStats, Solution
from pipeline.contracts.regime import Regime
from pipeline.contracts.system import System

__all__ = ["Force", "Integrator", "IntegratorStats", "Regime", "Solution", "System"]
