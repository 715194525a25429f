"""From a config to a run: Hydra composition (``config``), the plugin registry
(``registry``), the scene that ties system, forces and integrator together
(``scene``), batch integration (``batch``) and progress reporting (``progress``).
"""
