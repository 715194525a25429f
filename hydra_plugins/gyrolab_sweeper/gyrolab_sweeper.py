"""The sweeper gyrolab's config selects (``hydra/sweeper: gyrolab``); its logic is ``gyrolab.sweep.sweeper``."""

from gyrolab.sweep.sweeper import ResumingSweeper


class GyrolabSweeper(ResumingSweeper):
    """Hydra's basic sweeper that does not launch the jobs a previous run of the same sweep settled."""
