"""Sweeps: many jobs of one multirun, resumable, aggregated into one ``sweep.nc`` (docs/sweeps.md); ``slurm_local``:
a one-node SLURM on this machine to try the SLURM launcher on (docs/cluster.md).
"""
