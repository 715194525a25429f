"""How accurate a run is: the target (``auto``), the measurement (``amplification``, ``estimate``) and the recheck
(``promise``). ``Scene.run`` makes one call, ``measured_run``; integrators only declare capabilities (``more_accurate``,
their ``precision`` rung and ``climbed``); every tuned number sits in ``calibration.TABLE``.
"""

from gyrolab.accuracy.promise import measured_run

__all__ = ["measured_run"]
