"""Sweeps: many jobs of one multirun, resumable, aggregated into one ``sweep.nc`` (docs/sweeps.md).

A sweep directory (``hydra.sweep.dir``) holds ``multirun.yaml`` (Hydra's), one directory per job (``run.nc``,
``job.json``, the job's log) and, once the sweep ends, ``sweep.nc`` and ``figures/sweep_*.png``. ``slurm_local``
is a one-node SLURM on this machine to try the SLURM launcher on (docs/cluster.md).
"""
