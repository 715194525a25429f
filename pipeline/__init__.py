"""gyrolab: reproducible experiments on rigid-body and satellite attitude dynamics.

The package's folders are its architecture: ``physics`` (rigid-body mechanics,
no configs or files), ``contracts`` (what a plugin must do), ``engine`` (config
to scene to run), ``output`` (datasets, provenance, figures), ``sweep``
(multiruns), ``experiments`` (the papers' tables and figures), ``plugins``
(systems, forces, integrators, regimes) and ``conf`` (the Hydra YAML).

Python API::

    from gyrolab import compose_scene, run
    scene = compose_scene(["integrator=rk4", "integrator.step=0.005"])
    ds = scene.run()          # xarray.Dataset; writes nothing
"""

from gyrolab.engine.scene import Scene, compose_scene, run
from gyrolab.errors import ConfigError, GyrolabError
from gyrolab.output.provenance import gyrolab_version

__version__ = gyrolab_version()
__all__ = ["ConfigError", "GyrolabError", "Scene", "__version__", "compose_scene", "run"]
