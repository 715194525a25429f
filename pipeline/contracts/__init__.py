"""The contracts every plugin implements: forces, systems, integrators, regimes.

Each contract's docstring lists the rules an implementer follows; plugins in
``plugins/`` (and third-party packages, through entry points) subclass them.
"""

from pipeline.contracts.force import CompiledTerms, Force
from pipeline.contracts.integrator import CompiledModel, Integrator, IntegratorStats, Solution
from pipeline.contracts.regime import Regime
from pipeline.contracts.system import System

__all__ = ["CompiledModel", "CompiledTerms", "Force", "Integrator", "IntegratorStats", "Regime", "Solution", "System"]
