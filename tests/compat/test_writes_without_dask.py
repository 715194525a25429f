"""Writing run.nc and sweep.nc imports no Dask (gyrolab.compat), and changes nothing written.

With Dask installed, xarray imported ``dask.array`` and ``distributed`` for the first file a process wrote
(~0.43 CPU s: a fifth of a 20-job sweep's overhead). The guards answer as xarray and Dask do where the
answer cannot depend on Dask, and ask them otherwise; checked here from outside: which modules a fresh
``gyrolab`` process has imported when it ends, the files against those plain xarray writes, and each
guard's answer against the function it guards once Dask is in use.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from gyrolab.compat import install_dask_free_writes

pytest.importorskip("dask.array")   # without Dask installed there is nothing to skip
DASK_MODULES = ("dask", "dask.array", "distributed")

RUN_AND_REPORT = """
import atexit, json, sys
atexit.register(lambda: print("IMPORTED " + json.dumps([m for m in {modules!r} if m in sys.modules])))
sys.argv = ["gyrolab", *{args!r}]
from gyrolab.app import main
main()
"""


def gyrolab_reporting_imports(tmp_path, *args):
    script = RUN_AND_REPORT.format(modules=DASK_MODULES, args=list(args))
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    line = next(line for line in done.stdout.splitlines() if line.startswith("IMPORTED "))
    return json.loads(line.removeprefix("IMPORTED "))


def test_a_sweep_imports_no_dask(tmp_path):
    sweep = tmp_path / "sweep"
    imported = gyrolab_reporting_imports(tmp_path, "-m", "time.end=1", "time.n_output=11", "initial.r0=1,2",
                                         "output.figures=false", f"hydra.sweep.dir={sweep}")
    assert imported == []
    assert (sweep / "0" / "run.nc").is_file() and (sweep / "sweep.nc").is_file()


WRITE = """
import sys
import xarray
if not {guarded}:  # an xarray the guards were not written for: xarray's own path
    xarray.__version__ = "2099.1.0"
from gyrolab import compose_scene
from gyrolab.compat import install_dask_free_writes
assert install_dask_free_writes() is {guarded}
ds = compose_scene(["time.end=1", "time.n_output=11"]).run()
for key in [k for k in ds.attrs if "wall" in k or k in ("date_created", "history")]:
    del ds.attrs[key]   # what differs between two runs
ds = ds.drop_vars(["integrator_wall_time"], errors="ignore")
ds.to_netcdf({path!r}, engine="netcdf4")
print("DASK", [m for m in {modules!r} if m in sys.modules])
"""


@pytest.mark.parametrize("version, installed", [("2023.12.0", False), ("2024.1.0", True), ("2026.9.0", True),
                                                 ("2027.1.0", False), ("not.a.version", False)])
def test_the_guards_are_installed_for_the_xarray_versions_they_were_written_for(version, installed):
    from gyrolab.compat import XARRAY_SUPPORTED, supported

    assert supported(version, XARRAY_SUPPORTED) is installed


def test_the_written_file_is_the_file_xarray_writes(tmp_path):
    """Under a supported xarray (the guards installed, no Dask imported) and an unsupported one (xarray's own
    path, which imports Dask): the same file."""
    printed = {}
    for guarded in (True, False):
        path = str(tmp_path / f"{guarded}.nc")
        done = subprocess.run([sys.executable, "-c", WRITE.format(guarded=guarded, path=path, modules=DASK_MODULES)],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        printed[guarded] = done.stdout.strip().splitlines()[-1]
    assert printed[True] == "DASK []"
    assert "dask.array" in printed[False]            # plain xarray imports it for the same dataset
    with xr.open_dataset(tmp_path / "True.nc") as ours, xr.open_dataset(tmp_path / "False.nc") as plain:
        xr.testing.assert_identical(ours.load(), plain.load())
        assert {k: v.encoding.get("dtype") for k, v in ours.variables.items()} == \
            {k: v.encoding.get("dtype") for k, v in plain.variables.items()}


def test_once_dask_is_in_use_each_guard_answers_as_xarray():
    import dask
    import dask.array as da
    from xarray.backends import netCDF4_, writers
    from xarray.namedarray import pycompat, utils

    assert install_dask_free_writes()
    assert pycompat.array_type("dask") == (da.Array,)
    chunked = xr.Dataset({"x": ("t", da.arange(4.0, chunks=2))})
    plain = xr.Dataset({"x": ("t", np.arange(4.0))})
    assert utils.is_dask_collection(chunked["x"].data) and not utils.is_dask_collection(plain["x"].data)
    autoclose, lock = writers._get_netcdf_autoclose, netCDF4_.get_write_lock
    for scheduler in ("threads", "processes", "synchronous"):
        with dask.config.set(scheduler=scheduler):
            for ds in (chunked, plain):
                assert autoclose(ds, "netcdf4") == autoclose.__wrapped__(ds, "netcdf4"), scheduler
            assert type(lock("some.nc")) is type(lock.__wrapped__("some.nc")), scheduler
    with dask.config.set(scheduler="processes"):
        assert autoclose(chunked, "netcdf4") is True   # a case where the answer is not the shortcut's


def test_installing_twice_guards_once():
    from xarray.backends import writers

    assert install_dask_free_writes() and install_dask_free_writes()
    guarded = writers._get_netcdf_autoclose
    assert not hasattr(guarded.__wrapped__, "__wrapped__")
