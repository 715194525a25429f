"""Rigid-body mechanics that knows nothing of configs, files, plugins or compiled kernels.

The body and its units (``body``), attitude and Euler angles (``attitude``, ``vectors``), initial
states (``initial``), the pendulum's closed forms (``pendulum``), Lindstedt series (``lindstedt``),
extended-precision reference solutions (``reference``) and the satellite-gyrostat's body and Lagrange
equations (``gyrostat_body``, ``gyrostat_euler``). Everything above builds on these; this layer imports
nothing of ``gyrolab`` but ``errors`` (``tests/package/test_layers.py``). Periodic orbits, continuation, chaos
and precessions, which integrate the plugins' systems, are in ``gyrolab.analysis``.
"""
