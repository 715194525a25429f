"""The contracts every plugin implements: forces, systems, integrators, regimes.

Each contract's docstring lists the rules an implementer follows; plugins in
``plugins/`` (and third-party packages, through entry points) subclass them.
"""

from gyrolab.contracts.force import CompiledTerms, Force
from gyrolab.contracts.integrator import CompiledModel, Integrator, IntegratorStats, Solution
from gyrolab.contracts.regime import Regime
from gyrolab.contracts.system import System

__all__ = ["CompiledModel", "CompiledTerms", "Force", "Integrator", "IntegratorStats", "Regime", "Solution", "System"]
