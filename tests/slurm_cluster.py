"""tests/test_slurm.py's single-node SLURM: ``gyrolab.sweep.slurm_local`` (the user's
``python -m gyrolab.sweep.slurm_local start|stop``, docs/cluster.md), under the name the tests import."""

from gyrolab.sweep.slurm_local import (  # noqa: F401 - re-exported for tests/test_slurm.py
    PARTITION,
    PREFIX,
    Cluster,
    Unavailable,
    alive,
    clean_leftovers,
    install,
    slurm_conf,
    start,
)
