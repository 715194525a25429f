"""More accurate runs of a fixed-step method, for ``Integrator.more_accurate`` (rule 9, ``output.error_estimate``)."""

from __future__ import annotations

from typing import Any

import numpy as np


def half_step(method: Any, order: int, /, **kwargs: Any):
    """``more_accurate`` of a fixed-step method of ``order``: the same method at half the step, and Richardson's
    factor 2^p / (2^p − 1) that turns the two runs' difference into the coarse run's error. ``kwargs``: the finer
    method's other settings (positional-only ``method`` and ``order``: lie_poisson passes its own ``order=``)."""
    finer = type(method)(step=method.step / 2, **kwargs)
    finer.halvings = getattr(method, "halvings", 0) + 1  # every interval's steps doubled (``interval_steps``)
    return finer, 2.0 ** order / (2.0 ** order - 1.0), (f"{method.name} at half the step ({method.step / 2:.3g}), "
                                                         f"Richardson's estimate for order {order}")


def interval_steps(method: Any, t_out: np.ndarray) -> np.ndarray:
    """Equal steps per output interval of a fixed-step method: the fewest no longer than ``method.step``; for a
    companion made by ``half_step``, exactly twice its coarse method's in every interval. (Halving the step alone
    left an interval shorter than half the step with one step in both runs: identical runs, an estimate of 0.)"""
    halvings = getattr(method, "halvings", 0)
    return steps_per_interval(t_out, method.step * 2 ** halvings) * 2 ** halvings


def steps_per_interval(t_out: np.ndarray, step: float) -> np.ndarray:
    """Fewest equal steps no longer than ``step`` in each output interval (lands on every output time)."""
    return np.maximum(1, np.ceil(np.diff(np.asarray(t_out, dtype=float)) / step * (1.0 - 1e-12))).astype(np.int64)
