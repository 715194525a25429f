"""gyrolab: reproducible experiments on rigid-body and satellite attitude dynamics.

The package's folders are its architecture, in layers: each imports only the
layers below it (``tests/package/test_layers.py`` checks it, function-level imports
included):

1. ``errors``       the one-sentence errors every layer raises
2. ``physics``      rigid-body mechanics: no configs, files, plugins or kernels
3. ``kernels``      the numerical core: a system's equations traced once, the
                    kernels generated from them, the integrators' inner loops
4. ``contracts``    what a plugin must do (enforced by the base classes) and the
                    registry that finds plugins by name
5. ``plugins``      forces, systems, integrators, then ``accuracy``: the target
                    (``auto``), the error's measurement and the recheck
6. ``analysis``     periodic orbits, continuation, chaos indicators, precessions
                    (numerical analysis on the plugins), then ``plugins.regimes``
7. ``output``, ``figures``   the self-describing dataset, provenance, drawing
8. ``engine``       config → scene → run
9. ``sweep``, ``batch``, ``experiments``, ``app``   multiruns, batches, the
                    papers' tables and figures, the command line

``conf`` holds the Hydra YAML.

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
