"""gyrolab: reproducible experiments on rigid-body and satellite attitude dynamics.

The package's folders are its architecture, in layers: each imports only the
layers below it (``tests/test_layers.py`` checks it, function-level imports
included):

1. ``errors``       the one-sentence errors every layer raises
2. ``physics``      rigid-body mechanics: no configs, files, plugins or kernels
3. ``kernels``      the numerical core: a system's equations traced once, the
                    kernels generated from them, the integrators' inner loops
4. ``contracts``    what a plugin must do (enforced by the base classes) and the
                    registry that finds plugins by name
5. ``plugins``      forces, systems, integrators
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

import importlib
import importlib.abc
import importlib.machinery
import sys

#: module paths of earlier gyrolab versions -> where the module lives now (both spellings keep working)
MOVED_MODULES = {
    "gyrolab.physics.periodic": "gyrolab.analysis.periodic",
    "gyrolab.physics.continuation": "gyrolab.analysis.continuation",
    "gyrolab.physics.chaos": "gyrolab.analysis.chaos",
    "gyrolab.physics.precession": "gyrolab.analysis.precession",
    "gyrolab.physics.precession.cases": "gyrolab.analysis.precession.cases",
    "gyrolab.physics.precession.classify": "gyrolab.analysis.precession.classify",
    "gyrolab.physics.precession.closed_forms": "gyrolab.analysis.precession.closed_forms",
    "gyrolab.physics.precession.finder": "gyrolab.analysis.precession.finder",
    "gyrolab.physics.precession.motion": "gyrolab.analysis.precession.motion",
    "gyrolab.physics.precession.stability": "gyrolab.analysis.precession.stability",
    "gyrolab.plugins.systems.gyrostat_euler": "gyrolab.physics.gyrostat_euler",
    "gyrolab.plugins.systems.gyrostat_body": "gyrolab.physics.gyrostat_body",
    "gyrolab.engine.batch": "gyrolab.batch.integrate",
    "gyrolab.sweep.batch": "gyrolab.batch.sweep",
    "gyrolab.engine.registry": "gyrolab.contracts.registry",
    "gyrolab.output.figures": "gyrolab.figures.run",
    "gyrolab.engine.user_yaml": "gyrolab.output.user_yaml",
}


class _MovedModuleFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports a moved module under its old name as the very same module object (no copy, no shim file
    that would import upwards across the layers)."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname in MOVED_MODULES:
            return importlib.machinery.ModuleSpec(fullname, self)
        return None

    def create_module(self, spec):
        return None

    def exec_module(self, module):
        # importlib reads sys.modules again after exec_module, so the alias becomes the real module
        sys.modules[module.__name__] = importlib.import_module(MOVED_MODULES[module.__name__])


if not any(isinstance(finder, _MovedModuleFinder) for finder in sys.meta_path):
    sys.meta_path.insert(0, _MovedModuleFinder())  # before the path finder, which would load a copy

from gyrolab.engine.scene import Scene, compose_scene, run  # noqa: E402
from gyrolab.errors import ConfigError, GyrolabError  # noqa: E402
from gyrolab.output.provenance import gyrolab_version  # noqa: E402

__version__ = gyrolab_version()
__all__ = ["ConfigError", "GyrolabError", "Scene", "__version__", "compose_scene", "run"]
