"""gyrolab's sweeper as a Hydra plugin (``hydra/sweeper: gyrolab``, ``conf/hydra/sweeper/gyrolab.yaml``).

Hydra instantiates a sweeper or launcher only from the ``hydra_plugins`` namespace package, which it scans
for plugin classes: this folder is installed there (pyproject's package list; ``hydra_plugins`` itself has
no ``__init__.py``, so that every plugin distribution adds its own folder to it). The sweeper's code is
``gyrolab.sweep.sweeper.ResumingSweeper``; the class here gives it the name Hydra looks for and imports gyrolab
only when Hydra instantiates it, because Hydra imports every plugin module of the environment whenever any
Hydra app starts (importing gyrolab costs ~2 s that an unrelated app should not pay).
"""

from typing import Any

from hydra.plugins.sweeper import Sweeper


class GyrolabSweeper(Sweeper):
    """The sweeper gyrolab's config selects (``hydra/sweeper: gyrolab``): Hydra's basic sweeper that does not
    launch the jobs a previous run of the same sweep already settled (``gyrolab.sweep.sweeper.ResumingSweeper``,
    which does the work)."""

    def __init__(self, max_batch_size: int | None = None, params: dict[str, str] | None = None) -> None:
        from gyrolab.sweep.sweeper import ResumingSweeper

        super().__init__()
        self.sweeper = ResumingSweeper(max_batch_size=max_batch_size, params=params)

    def setup(self, **kwargs: Any) -> None:
        self.sweeper.setup(**kwargs)

    def sweep(self, arguments: list[str]) -> Any:
        return self.sweeper.sweep(arguments)
