"""Sweeps: many jobs of one multirun, resumable, aggregated into one ``sweep.nc``.

A sweep directory (``hydra.sweep.dir``) holds ``multirun.yaml`` (Hydra's),
one directory per job (``run.nc``, ``job.json``, the job's log) and, once the
sweep ends, ``sweep.nc`` and ``figures/sweep_*.png``.

Modules, one job each:

* ``identity``  -- a job's identity: hash of its resolved config and the code version
* ``record``    -- ``job.json``: how a job ended, written atomically after ``run.nc``
* ``job``       -- run one job: skip it if done, else run it and record success or failure
* ``grid``      -- the sweep's grid (one dimension per swept parameter) from its overrides
* ``aggregate`` -- assemble the jobs into ``sweep.nc`` (layout documented there)
* ``figures``   -- summary figures against the swept parameters
* ``watch``     -- progress of a running sweep
* ``callbacks`` -- the Hydra callback that aggregates at the end of a multirun
* ``reproduce`` -- rerun a ``run.nc`` from its stored config and compare bit for bit
* ``slurm_local`` -- a one-node SLURM on this machine to try the SLURM launcher on
  (``python -m gyrolab.sweep.slurm_local start|status|stop``; tests/sweep/test_slurm.py's cluster)
"""
