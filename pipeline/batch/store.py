"""A batch's dataset on disk, written chunk by chunk to ``NAME.part`` (journaled in ``NAME.chunks``), resumable after
a kill (docs/batch.md, "The file" and "Resume"). A ``NAME.part`` that no longer opens is replaced, with a warning
naming the chunks lost.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
from pathlib import Path
from typing import Any

import netCDF4
import numpy as np
from omegaconf import OmegaConf

from gyrolab.batch.outputs import output_times
from gyrolab.batch.plan import POINT
from gyrolab.engine.scene import Scene
from gyrolab.errors import ConfigError, OutputError
from gyrolab.output.atomic import TEMP_SUFFIX, _fsync, _fsync_directory, _library_failure, diagnose, reason
from gyrolab.output.cf import CONVENTIONS, now_iso
from gyrolab.output.dataset import time_attributes
from gyrolab.output.provenance import gyrolab_version, provenance
from gyrolab.output.trust import check_output_target, open_own_file
from gyrolab.output.units import quantity_units
from gyrolab.sweep import record
from gyrolab.sweep.aggregate import STATUS_ATTRS, STATUS_FLAGS

log = logging.getLogger("gyrolab.batch")

FINISHED, FAILED = STATUS_FLAGS[record.FINISHED], STATUS_FLAGS[record.FAILED]
STATUS_LONG_NAME = "how the point ended: 0 not run, 1 finished, 2 failed"
ERROR_ATTRS = {"long_name": "the point's error: index into error_message, -1 for none", "units": "1"}


class Store:
    def __init__(self, path: Path, plan: Any, identity: str, settings: Any, messages: list[str]) -> None:
        self.path = Path(path)
        self.part = self.path.with_name(self.path.name + ".part")
        self.journal = self.path.with_name(self.path.name + ".chunks")
        self.plan, self.identity, self.settings, self.messages = plan, identity, settings, messages
        self.nc: netCDF4.Dataset | None = None
        #: the integrator's settings every chunk ran with (``auto``: its choice for the batch), as attributes
        self.integrator_attributes: dict[str, Any] = {}

    def open(self) -> set[int] | None:
        """The chunks already stored (a resumed run), or None when ``path`` holds this batch complete."""
        if self.path.exists():
            found = _identity_of(self.path)
            if found == self.identity:
                log.info("batch: %s holds this batch complete already; nothing to run", self.path)
                return None
            raise ConfigError(f"{self.path} holds another batch (identity {found}, this one is {self.identity}); "
                              "choose another output directory (hydra.sweep.dir, or hydra.run.dir for an experiment) "
                              "or remove it")
        if not self.part.exists():
            self.journal.unlink(missing_ok=True)
            return set()
        try:
            found = _identity_of(self.part)
        except OutputError:
            self._replace_unreadable_part()
            return set()
        if found != self.identity:
            raise ConfigError(f"{self.part} is an unfinished batch of another command or gyrolab version (identity "
                              f"{found}, this one is {self.identity}); rerun that command to finish it, or give "
                              "another directory")
        done = _read_journal(self.journal, self.identity)
        try:
            if not done:   # killed before its first chunk was journaled: the journal starts again
                _write_journal(self.journal, "w", f"identity {self.identity}\n")
            else:          # a write that failed mid-line leaves a torn last line: cut it before appending
                _cut_torn_line(self.journal)
            check_output_target(self.part)  # netCDF follows links: a planted one is refused first
            self.nc = _open(self.part, "a")
        except OutputError:
            raise
        except OSError as error:
            raise self._failed(error, done) from None
        log.info("batch: resuming %s (%d chunks stored)", self.part, len(done))
        return done

    def _replace_unreadable_part(self) -> None:
        """A ``.part`` that no longer opens holds nothing recoverable: start it again (saying what is lost)."""
        lost = _read_journal(self.journal, self.identity)
        if lost:
            log.warning("batch: %s cannot be read any more (a write to it failed); its %d stored chunks are run "
                        "again", self.part, len(lost))
        else:
            log.info("batch: %s was left unfinished before its first chunk; starting it again", self.part)
        self.part.unlink(missing_ok=True)
        self.journal.unlink(missing_ok=True)

    def _failed(self, error: BaseException, done: set[int] | None = None) -> OutputError:
        """The sentence of a failed write (the file closed; the journaled chunks kept for the rerun)."""
        # the reason is probed beside the file, never in it (a probe write must not touch the stored chunks)
        probe = self.part.with_name(f".{self.part.name}.probe{TEMP_SUFFIX}")
        try:
            size = self.part.stat().st_size
        except OSError:
            size = None
        try:
            why = diagnose(error, probe, size)
        finally:
            probe.unlink(missing_ok=True)
        self._close_quietly()
        kept = len(_read_journal(self.journal, self.identity)) if done is None else len(done)
        keep = (f"the {kept} chunks already stored are kept: rerun the same command to continue once there is room"
                if kept else "nothing was finished yet: rerun the same command once there is room")
        return OutputError(f"could not write {self.part}: {why}; {keep}")

    def _close_quietly(self) -> None:
        nc, self.nc = self.nc, None
        if nc is not None:
            with contextlib.suppress(OSError, RuntimeError):   # the write failed; the journal says what is whole
                nc.close()

    def chunk_done(self, index: int, chunk: Any, result: Any) -> None:
        """Store a chunk's result (None: a chunk without a valid point) and journal it; OutputError (the
        journaled chunks kept) when a write fails."""
        self._guarded(self._store_chunk, index, chunk, result)

    def _store_chunk(self, index: int, chunk: Any, result: Any) -> None:
        if self.nc is None:
            self._create(result)
        if result is not None:
            valid = self.plan.valid[chunk.start:chunk.stop]
            status = np.where(valid, FINISHED, FAILED).astype(np.int8)
            error = self.plan.error[chunk.start:chunk.stop].copy()
            status[result.failed] = FAILED
            error[result.failed] = len(self.messages) - 1   # the integration failure's sentence
            self._write("job_status", chunk, status)
            self._write("job_error", chunk, error)
            for name, out in result.outputs.items():
                if name in self.nc.variables:
                    self._write(name, chunk, out.data)
        self.nc.sync()
        _fsync(self.part)
        _write_journal(self.journal, "a", f"{index}\n")

    def finish(self) -> None:
        """Close the complete file and give it its final name (OutputError, the chunks kept, if that fails)."""
        self._guarded(self._finish)

    def _guarded(self, write: Any, *args: Any) -> None:
        """``write(*args)``; a failed write (an OSError, or the netCDF library's RuntimeError for one) becomes
        one OutputError sentence with the journaled chunks kept, and the file is closed."""
        try:
            write(*args)
        except OutputError:
            self._close_quietly()
            raise
        except (OSError, RuntimeError) as error:
            if not isinstance(error, OSError) and not _library_failure(error):
                raise
            raise self._failed(error) from None

    def _finish(self) -> None:
        if self.nc is None:
            self._create(None)
        status = np.asarray(self.nc["job_status"][:])   # auto-masking is off (_open, _create_file)
        counts = {f"n_{name}": np.int64(np.count_nonzero(status == code)) for name, code in STATUS_FLAGS.items()}
        self.nc.setncatts(counts)
        if counts["n_failed"]:
            log.info("batch: %d of %d points failed; their errors are error_message[job_error] where job_status is 2",
                     counts["n_failed"], status.size)
        self.nc.close()
        self.nc = None
        _fsync(self.part)
        os.replace(self.part, self.path)
        _fsync_directory(self.path.parent)
        self.journal.unlink(missing_ok=True)

    def _write(self, name: str, chunk: Any, data: np.ndarray) -> None:
        data = np.asarray(data)
        self.nc[name][chunk.slab] = data.reshape(chunk.shape + data.shape[1:])

    def _create(self, result: Any) -> None:
        """Create ``.part`` whole (every variable's storage allocated); a failure leaves neither it nor a journal
        (nothing was finished), so the rerun starts cleanly."""
        try:
            self._guarded(self._create_file, result)
        except OutputError:
            self.part.unlink(missing_ok=True)
            self.journal.unlink(missing_ok=True)
            raise

    def _create_file(self, result: Any) -> None:
        plan = self.plan
        self.part.parent.mkdir(parents=True, exist_ok=True)
        nc = netCDF4.Dataset(self.part, "w", format="NETCDF4")
        self.nc = nc
        nc.set_auto_mask(False)
        # the base point's system: the title, the time's attributes, the units of the swept keys (gyrolab knows those
        # of every key of a nondimensional body and the known keys of an SI one: gyrolab.output.units)
        system = Scene.from_config(OmegaConf.create(plan.base)).system if plan.base is not None else None
        if plan.points is not None:
            nc.createDimension(POINT, plan.size)
            _variable(nc, POINT, POINT, np.arange(plan.size, dtype=np.int32),
                      {"long_name": "index of the point in the batch's list (a points file's data row, from 0)",
                       "units": "1"})
        for name, dim in zip(plan.names, plan.dims):
            if plan.points is None:
                nc.createDimension(name, len(dim.values))
            values = dim.coordinate()
            if values.dtype.kind in "iu":
                values = values.astype(np.int32) if np.abs(values).max() < 2**31 else values.astype(np.float64)
            units = quantity_units(dim.key, system.body.units if system is not None else None)
            attrs = {"long_name": f"swept parameter {dim.key}" + (" of each point" if plan.points else ""),
                     "override_key": dim.key, **({"units": units} if units else {})}
            (_text_variable if values.dtype.kind == "O" else _variable)(
                nc, name, POINT if plan.points is not None else name, values, attrs)
        nc.createDimension("error_kind", len(self.messages))
        _text_variable(nc, "error_message", "error_kind", self.messages,
                       {"long_name": "the one-sentence errors of the failed points (job_error indexes them)"})
        grid = plan.grid_dims
        # no fill value: every point's code is written below (a fill value would make readers mask the codes)
        status = nc.createVariable("job_status", "i1", grid, contiguous=True, fill_value=False)
        status.setncatts({"long_name": STATUS_LONG_NAME, **STATUS_ATTRS, **self._coordinates_attr()})
        error = nc.createVariable("job_error", "i4", grid, contiguous=True, fill_value=False)
        error.setncatts({**ERROR_ATTRS, **self._coordinates_attr()})
        shape = plan.shape
        # every point's validation outcome now (so a failed point's error is there whatever happens next)
        status[:] = np.where(plan.valid, 0, FAILED).astype(np.int8).reshape(shape)
        error[:] = plan.error.reshape(shape)
        if result is not None:
            self._create_variables(result, system)
        # the counts ``finish`` stores, created (as 0) with the file so that finishing overwrites them in place
        nc.setncatts({**self._attributes(system), **{f"n_{name}": np.int64(0) for name in STATUS_FLAGS}})
        nc.sync()
        _fsync(self.part)
        _write_journal(self.journal, "w", f"identity {self.identity}\n")

    def _create_variables(self, result: Any, system: Any) -> None:
        nc, plan = self.nc, self.plan
        for name, out in result.outputs.items():
            for dim, size in zip(out.dims, out.data.shape[1:]):
                if dim not in nc.dimensions:
                    nc.createDimension(dim, size)
                    self._coordinate(dim, size, system)
            var = nc.createVariable(name, "f8", plan.grid_dims + tuple(out.dims), contiguous=True,
                                    fill_value=np.nan)
            var.setncatts({k: (v if not isinstance(v, (list, tuple)) else np.asarray(v)) for k, v in out.attrs.items()
                           if k != "_FillValue"})
            var.setncatts(self._coordinates_attr())
            var[(0,) * var.ndim] = np.nan   # allocates the variable's storage now, not at a later chunk's write

    def _coordinates_attr(self) -> dict[str, str]:
        """A list of points: each per-point variable names the keys' values along ``point`` as its (CF auxiliary)
        coordinates, so readers show them with it."""
        return {"coordinates": " ".join(self.plan.names)} if self.plan.points is not None else {}

    def _coordinate(self, dim: str, size: int, system: Any) -> None:

        if dim == "time":
            times = output_times(self.plan.times, self.settings.output, self.settings.decimate)
            _variable(self.nc, "time", "time", times,
                      time_attributes(system.body) if system is not None else {"long_name": "time", "axis": "T"})
        elif dim == "axis" and size == 3:
            _text_variable(self.nc, "axis", "axis", ["x", "y", "z"], {"units": "1", "long_name": "principal body axis"})

    def _attributes(self, system: Any) -> dict[str, Any]:
        plan, settings = self.plan, self.settings
        created = now_iso()
        attrs: dict[str, Any] = {
            "Conventions": CONVENTIONS,
            "title": (f"gyrolab batch of {plan.size} points over {' × '.join(plan.names)}" if plan.points is None
                      else f"gyrolab batch of a list of {plan.size} points ({plan.points['kind']}) of "
                           f"{', '.join(plan.names)}")
                     + (f": {system.title()}" if system is not None else ""),
            "date_created": created,
            "history": f"{created} written by gyrolab {gyrolab_version()}: batch ({settings.output})",
            "config": OmegaConf.to_yaml(OmegaConf.create(plan.plain)),
            "batch_grid": json.dumps([[d.key, list(d.labels)] for d in plan.dims]) if plan.points is None
            else json.dumps([d.key for d in plan.dims]),
            "batch_identity": self.identity,
            "batch_output": settings.output,
            "n_points": plan.size,
            "error_kind_description": "dimension error_kind: one entry per distinct error message of the failed "
                                      "points; job_error holds each point's entry (-1: no error)",
            "sweep_launcher": "batch",
            "integrator": str((plan.plain.get("integrator") or {}).get("_target_", "")).rsplit(".", 1)[-1],
        }
        if settings.output == "decimated":
            attrs["batch_decimate"] = settings.decimate
        for key, value in (plan.points or {}).items():   # kind (zip, points_file), the file and its SHA-256
            attrs[f"batch_points_{key}" if key == "kind" else f"batch_{key}"] = value
        for key, value in {**plan.attributes, **self.integrator_attributes, **provenance()}.items():
            if value is not None:
                attrs[key] = int(value) if isinstance(value, (bool, np.bool_)) else value
        return attrs


def _variable(nc: netCDF4.Dataset, name: str, dim: str, values: np.ndarray, attrs: dict[str, Any]) -> None:
    var = nc.createVariable(name, values.dtype, (dim,))
    var[:] = values
    var.setncatts(attrs)


def _text_variable(nc: netCDF4.Dataset, name: str, dim: str, values: Any, attrs: dict[str, Any]) -> None:
    """Text along ``dim`` as a UTF-8 char array (as xarray writes text, so CF checkers read it)."""
    texts = [str(v) for v in values]
    width = max([len(t.encode("utf-8")) for t in texts] + [1])
    nc.createDimension(f"{name}_strlen", width)
    var = nc.createVariable(name, "S1", (dim, f"{name}_strlen"))
    var._Encoding = "utf-8"
    var[:] = np.array(texts, dtype=f"U{width}")
    var.setncatts(attrs)


def _open(path: Path, mode: str) -> netCDF4.Dataset:
    try:
        nc = netCDF4.Dataset(path, mode)
    except OSError as error:
        raise OutputError(f"could not open {path}: {reason(error)}") from None
    nc.set_auto_mask(False)
    return nc


def _identity_of(path: Path) -> str:
    with _open(path, "r") as nc:
        return str(getattr(nc, "batch_identity", "none (not a gyrolab batch)"))


def _write_journal(path: Path, mode: str, text: str) -> None:
    """Write (``mode`` "w") or append ("a") ``text`` to a journal, on the disk when this returns."""
    with open(path, mode, encoding="utf-8", opener=open_own_file) as journal:
        journal.write(text)
        journal.flush()
        os.fsync(journal.fileno())


def _read_journal(path: Path, identity: str) -> set[int]:
    """The chunks a journal records (none if it is missing or belongs to another identity)."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        return set()
    lines = text.splitlines()
    if not lines or lines[0] != f"identity {identity}":
        return set()
    complete = lines[1:] if text.endswith("\n") else lines[1:-1]   # a torn last line is not a journaled chunk
    return {int(line) for line in complete if line.strip().isdigit()}


def _cut_torn_line(path: Path) -> None:
    """Cut a journal's unterminated last line (a write that failed half-way), so that appending stays exact."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with open(path, "r+b", opener=open_own_file) as journal:
            journal.truncate(data.rfind(b"\n") + 1)
            journal.flush()
            os.fsync(journal.fileno())

