"""gyrolab's engine: contracts, registry, scene composition, datasets and figures.

Python API::

    from pipeline import compose_scene, run
    scene = compose_scene(["integrator=rk4", "integrator.step=0.005"])
    ds = scene.run()          # xarray.Dataset; writes nothing
"""

from pipeline.scene import Scene, compose_scene, run

__all__ = ["Scene", "compose_scene", "run"]
