"""More accurate runs of a fixed-step method, for ``Integrator.more_accurate`` (rule 9, ``output.error_estimate``)."""

from __future__ import annotations

from typing import Any


def half_step(method: Any, order: int, /, **kwargs: Any):
    """``more_accurate`` of a fixed-step method of ``order``: the same method at half the step, and Richardson's
    factor 2^p / (2^p − 1) that turns the two runs' difference into the coarse run's error. ``kwargs``: the finer
    method's other settings; ``method`` and ``order`` are positional-only, so that a method with an ``order`` setting
    of its own (lie_poisson) passes it as ``order=`` (it raised TypeError, a traceback, before)."""
    finer = type(method)(step=method.step / 2, **kwargs)
    return finer, 2.0 ** order / (2.0 ** order - 1.0), (f"{method.name} at half the step ({method.step / 2:.3g}), "
                                                         f"Richardson's estimate for order {order}")
