"""The numerical core: models in the compiled kernels' form, the kernels generated from them, the integrators'
inner loops. Plain float arrays in, plain float arrays out: units, configs and files stay above it.

- ``model``: a system's equations written once (its numpy ``rhs`` traced, ``expression``) and the compiled
  model (``CompiledModel``) generated from them; ``taylor_series`` generates their Taylor coefficients
  (``recurrences``: those of functions of a series, shared with the batch lanes).
- ``fixed_point`` (with ``layout``): the fixed-point system's built-in torques packed as numbers (what the
  Lie–Poisson splitting, the regimes and the chaos kernels read).
- ``models``: the calls from a compiled model to its right-hand side and Taylor coefficients.
- the integrators' kernels: ``dop853``, ``rk4``, ``taylor`` (and ``taylor_dd`` in double-double,
  ``batch_*`` for many trajectories, ``lie_poisson``); ``tangent`` generates a model's tangent flow (the
  variational equations of the chaos indicators and ``auto``'s growth of perturbations).
- ``compiler``: numba's set-up (the decorators, the on-disk cache). Importing this package does not import
  numba: ``model`` traces equations with numpy alone.
"""
