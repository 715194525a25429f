"""Numerical analysis of the equations of motion, built on the plugins' systems and compiled kernels.

Exact periodic orbits by Newton shooting and their Floquet multipliers (``periodic``), their families
by pseudo-arclength continuation (``continuation``), chaos indicators from the variational equations
(``chaos``) and the regular precessions of the satellite-gyrostat (``precession``). It sits above
``plugins`` (it integrates their systems) and below the regimes, the engine and the experiments.
"""
