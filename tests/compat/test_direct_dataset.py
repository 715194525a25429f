"""``gyrolab.compat.direct_dataset``: xarray's direct constructor within the versions it was written for, the public
constructor otherwise, and the two give the same dataset (a run's variables and kept coordinates)."""

import pytest
import xarray as xr

from gyrolab import compat, compose_scene


@pytest.mark.parametrize("version, direct", [(xr.__version__, True), ("2023.12.0", False), ("2027.1.0", False)])
def test_the_direct_constructor_only_for_the_xarray_it_was_written_for(monkeypatch, version, direct):
    ds = compose_scene(["body=lagrange_top", "time.end=2", "time.n_output=21"]).run()
    variables = dict(ds.variables)
    called = []
    original = xr.Dataset.__init__

    def spy(self, *args, **kwargs):  # the public constructor's alignment and merge
        called.append(True)
        original(self, *args, **kwargs)

    monkeypatch.setattr(xr.Dataset, "__init__", spy)
    monkeypatch.setattr(xr, "__version__", version)
    built = compat.direct_dataset(variables, set(ds.coords), dict(ds.sizes), dict(ds.xindexes))
    assert bool(called) != direct
    assert built.identical(ds.drop_attrs(deep=False)) and set(built.variables) == set(ds.variables)
