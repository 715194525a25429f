"""From a config to a run: composition (``config``, ``schemas``), the checks before a run (``safety``, ``budget``,
``unread``), the scene that ties system, forces and integrator together (``scene``) and progress reporting.
"""
