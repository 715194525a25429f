"""How accurate a run is, in one place: the target, the measurement and the recheck.

* the target: ``auto`` (``gyrolab.accuracy.auto``) chooses the cheapest method predicted to reach ``accuracy``,
  climbing the precision ladder (double, then double-double) where the scene needs it, or refuses in one sentence
  whose advice is a target the scene reaches;
* the measurement: the growth of perturbations along the run (``amplification``) and the error of the stored
  trajectory at every output time (``estimate``: a companion run made more accurate by the integrator's own
  ``more_accurate``, or one rung up, ``climbed``);
* the recheck (``promise``): the run's promise held against that measurement at every output time.

``Scene.run`` makes one call, ``measured_run``. Integrators only declare capabilities (``more_accurate``, their
``precision`` rung and ``climbed``); every tuned number sits in ``calibration.TABLE``, naming the benchmark that
regenerates and checks it.
"""

from gyrolab.accuracy.promise import measured_run

__all__ = ["measured_run"]
