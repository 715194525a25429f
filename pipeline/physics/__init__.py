"""Rigid-body mechanics that knows nothing of configs or files.

The body and its units (``body``), attitude and Euler angles (``attitude``,
``vectors``), initial states (``initial``), exact periodic orbits and their
Floquet multipliers (``periodic``), extended-precision reference solutions
(``reference``) and the regular precessions of the satellite-gyrostat
(``precession``). The engine builds scenes from these; plugins use them.
"""
