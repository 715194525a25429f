"""gyrolab's sweeper as a Hydra plugin (``hydra/sweeper: gyrolab``, ``conf/hydra/sweeper/gyrolab.yaml``).

Hydra instantiates a sweeper or launcher only from the ``hydra_plugins`` namespace package, which it scans
for plugin classes: this folder is installed there (pyproject's package list; ``hydra_plugins`` itself has
no ``__init__.py``, so that every plugin distribution adds its own folder to it). The sweeper's code is
``gyrolab.sweep.sweeper``; the class here only gives it the name Hydra looks for.
"""

from gyrolab.sweep import sweeper as _sweeper  # the module, not its classes: Hydra registers every plugin class here


class GyrolabSweeper(_sweeper.ResumingSweeper):
    """The sweeper gyrolab's config selects (``hydra/sweeper: gyrolab``): Hydra's basic sweeper that does not
    launch the jobs a previous run of the same sweep already settled (``gyrolab.sweep.sweeper``)."""
