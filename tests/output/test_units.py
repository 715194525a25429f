"""Every numeric variable and coordinate of every dataset kind has ``units`` and ``long_name`` (issue 25, item 4).

The dataset kinds are the ones tests/output/test_cf.py checks (tests/helpers/datasets.py: run.nc of both systems,
multirun and --batch sweep.nc, regime.nc, every experiment's dataset, the stability map), small and fast, plus the
orbiting gyrostat's experiment. Units follow CF: a UDUNITS string, ``"1"`` for a dimensionless number (counts, ratios,
the nondimensional model quantities). Text variables carry a long_name only. A dimension without a
coordinate must be explained by some variable along it (its long_name says what the index counts)
or a global attribute ``<dim>_description``.
"""

from __future__ import annotations

import pytest

from tests.helpers.datasets import KINDS, assembled_sweep, run_dataset



def _batch_output(output):
    """A --batch sweep.nc with another ``batch.output`` (the CF test covers the default reductions)."""
    def build(tmp_path, monkeypatch):
        import xarray as xr

        from gyrolab.batch.sweep import run_batch_sweep

        path = run_batch_sweep(["integrator=rk4", "integrator.step=0.01", "body.a=1.5,2", f"batch.output={output}",
                                "time.end=1", "time.n_output=11", "output.figures=false"], tmp_path)
        return xr.load_dataset(path, decode_times=False), path
    return build


#: the gyrostat experiment is a scene: its dataset is a run.nc of the orbiting gyrostat with its own options
ALL_KINDS = {**KINDS, "gyrostat": run_dataset(["experiment=gyrostat"]),
             **{f"sweep_batch_{output}": _batch_output(output) for output in ("decimated", "final")}}


def _numeric(variable) -> bool:
    return variable.dtype.kind in "iufb"


@pytest.mark.parametrize("kind", list(ALL_KINDS))
def test_every_numeric_variable_and_coordinate_has_units_and_long_name(kind, tmp_path, monkeypatch):
    ds, _ = ALL_KINDS[kind](tmp_path, monkeypatch)
    missing = []
    for name, variable in ds.variables.items():
        if not str(variable.attrs.get("long_name", "")).strip():
            missing.append(f"{name}: no long_name")
        if _numeric(variable) and not str(variable.attrs.get("units", "")).strip():
            missing.append(f"{name}: no units")
    for dim in ds.dims:
        if dim not in ds.variables and f"{dim}_description" not in ds.attrs:
            missing.append(f"dimension {dim}: neither a coordinate nor a {dim}_description attribute")
    assert not missing, f"{kind}:\n" + "\n".join(missing)


SI_TOP = ["body.units=si", "body.a=null", "body.b=null", "body.com_direction=null", "body.inertia=[0.03,0.025,0.02]",
          "body.mass=0.5", "body.com=[0,0,0.1]", "body.g=9.81", "force=[uniform_gravity]"]


def _sweep_of(overrides, tail=("time.end=0.5", "time.n_output=5")):
    return assembled_sweep([*overrides, "output.euler_angles=false", *tail, "output.figures=false"])


def test_sweep_of_an_si_top_gives_swept_keys_and_per_job_attributes_their_physical_units():
    """r0 is an angular velocity (rad s-1 for an SI top), rtol a pure number; the per-job initial ω is a vector
    whose component dimension has a coordinate saying what it counts."""
    ds = _sweep_of([*SI_TOP, "initial.r0=4,5", "integrator.rtol=1e-8,1e-9", "integrator.atol=1e-12"])
    assert ds["r0"].attrs["units"] == "rad s-1" and ds["rtol"].attrs["units"] == "1"
    assert ds["initial_omega"].attrs["units"] == "rad s-1"
    assert ds["integrator_rtol"].attrs["units"] == "1"
    index = ds["initial_omega"].dims[-1]
    assert index == "initial_omega_index" and list(ds[index].values) == [0, 1, 2]
    assert "initial_omega" in ds[index].attrs["long_name"] and ds[index].attrs["units"] == "1"
    assert ds["sampling_fastest_rate"].attrs["units"] == "rad s-1"
    assert ds["energy_max_abs_drift"].attrs["units"] == "J"


def test_sweep_of_the_nondimensional_body_is_in_pure_numbers():
    ds = _sweep_of(["body.a=1.5,2", "initial.theta0=0.5,1"])
    assert ds["a"].attrs["units"] == "1" and ds["theta0"].attrs["units"] == "rad"
    assert ds["body_a"].attrs["units"] == "1" and ds["body_nondim_a"].attrs["units"] == "1"


@pytest.mark.parametrize("key, si, nondimensional", [
    ("initial.r0", "rad s-1", "1"),            # an angular velocity
    ("initial.theta0", "rad", "rad"),          # an angle, in either form
    ("time.end", "s", "1"),
    ("body.inertia", "kg m2", "1"),
    ("body.a", "1", "1"),                      # A/C: a ratio in either form
    ("integrator.rtol", "1", "1"),
    ("integrator.atol", None, "1"),            # on a state of mixed SI units: no one unit
    ("integrator_wall_time", "s", "s"),        # wall-clock time is seconds even for a nondimensional body
    ("force.my_plugin.strength", None, "1"),   # unknown: every nondimensional quantity is a pure number
])
def test_quantity_units(key, si, nondimensional):
    from gyrolab.output.units import quantity_units

    assert quantity_units(key, "si") == si
    assert quantity_units(key, "nondimensional") == nondimensional


def test_sweep_whose_jobs_differ_in_output_times_explains_its_sample_dimension():
    ds = _sweep_of(["time.end=0.5,1"], tail=("time.n_output=5",))
    assert "sample" in ds.dims and "sample" not in ds.coords
    assert "output times" in ds.attrs["sample_description"]
    assert ds["time"].dims[-1] == "sample" and ds["time"].attrs["units"] == "1"
    assert ds["end"].attrs["units"] == "1"                 # time.end of a nondimensional body
    assert "axis" not in ds["time"].attrs                   # a variable over the jobs, not the T coordinate
