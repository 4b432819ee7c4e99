"""Crash-safe store of bifurcation sweeps: a journal while running, one HDF5 file at the end.

Life of a sweep writing ``X.h5`` (see docs/store.md for the reasons)
    1. ``X.h5.lock`` is taken (:mod:`chaospound.lock`): one writer per output;
       a live holder is named and refused, a stale lock (its holder died) is
       taken over.
    2. Finished points are committed to the journal ``X.h5.journal``
       (:mod:`chaospound.journal`, SQLite in WAL mode): every batch is one
       atomic, fsynced transaction. A kill at any moment leaves every
       committed point intact and nothing half-written.
    3. When every point is done the journal is consolidated into
       ``X.h5.tmp-<pid>``, which is fsynced and renamed onto ``X.h5``
       atomically; only then is the journal removed. A kill during
       consolidation leaves the journal, and ``--resume`` consolidates again.

While the journal exists it is the truth: :func:`open_sweep` on ``X.h5``
reads the journal (the points done so far, the others pending), so a running
or interrupted sweep can be inspected and plotted; ``resume`` continues it.
An ``X.h5`` that is not yet finished (written by chaospound 0.1's in-place
store) is imported into a journal on resume.

Schema of the finished file (format "chaospound-sweep", version 1)::

    /                         attrs: format, format_version, chaospound_version,
                                     scene (TOML), scene_resolved (JSON), sweep (JSON),
                                     units (JSON), model, state_names (JSON),
                                     created, wall_s (timing fields)
                              a user's System instead of a scene (model "custom"):
                                     system (JSON: its identity), name, source
                                     (module:attr), source_sha256, parameter_names,
                                     parameter_values (JSON), classified
    /grid/<name>              values of each swept parameter (1 or 2 axes, in order)
    /<branch>/                "fresh", or "forward" / "backward" (continuation)
        order                 (N,) grid indices in the branch's visiting order
        status                (N,) int8: 0 pending, 1 done, 2 failed
        message               (N,) bytes: the failure message of failed points (and why
                              an unresolved point of a converged sweep is unresolved)
        regime                (N,) int8 code into the attribute REGIMES
        impacts_per_period, period_cycles   (N,) int16, -1 where undefined
        strobe_mismatch, zero_one, max_exponent, max_exponent_error   (N,) float64
        transient_used        (N,) int32: cycles run before the classified window
        corner_sequence       (N,) bytes: corners of one period, e.g. b"A+ B- A+"
        exponents             (N, k) float64 (only with Lyapunov exponents)
        final_state           (N, n) float64: state at the last section
        steps, rejected, rhs_evals   (N,) int64
        wall_s                (N,) float64 (timing field)
        impact_start, impact_count   (N,) int64: rows of the point's impacts
        impacts/{time, phase, velocity, corner, peak_penetration, peak_force, duration}
                              flat, in the branch's visiting order (corner: int8 code)
        strobe_start, strobe_count   (N,) int64
        strobe/state          (M, n) flat stroboscopic states
        attrs: impacts_committed, strobe_committed (the flat arrays' lengths), REGIMES
    /basins/                  only a basin scan (its sweep JSON has "axis_kinds": the axes
                              are initial conditions; chaospound.basins, docs/basins.md),
                              added once the points are consolidated
        label                 (N,) int32: attractor number per grid point, -1 failed
        attractors/           one row per attractor, by decreasing basin size:
            regime, label, corner_sequence (bytes), impacts_per_period, period_cycles,
            count, share, first_point, section_start, section_count, and
            sections (M, n): each attractor's section states
        attrs: tol, box, entropy, boundary_entropy, boxes, boundary_boxes, failed, reference

Per-point arrays are indexed by the grid index (row-major over the axes). The
file is a pure function of the sweep's definition and its points' results:
files from 1 or N workers, Dask, or any sequence of kills and resumes are
bitwise equal apart from the timing fields.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from .journal import SUFFIX as JOURNAL_SUFFIX
from .journal import Journal, JournalError, fsync_dir, journal_path
from .journal import remove as remove_journal
from .lock import OutputBusy, OutputLock
from .messages import shorten
from .units import UNITS

__all__ = ["FORMAT", "REGIMES", "StoreWriteError", "SweepFile", "SweepStoreError",
           "SweepWriter", "check_replaceable", "open_sweep"]

FORMAT = "chaospound-sweep"
FORMAT_VERSION = 1
REGIMES = ("pending", "none", "periodic", "group-periodic", "quasi-periodic", "chaotic",
           "unresolved", "failed")
STATUS_PENDING, STATUS_DONE, STATUS_FAILED = 0, 1, 2
IMPACT_FIELDS = ("time", "phase", "velocity", "corner", "peak_penetration", "peak_force",
                 "duration")
TIMING_FIELDS = ("wall_s", "created")
MESSAGE_LENGTH = 240
SEQUENCE_LENGTH = 160  #: room for 53 corner labels of one period
CHUNK = 4096
CONSOLIDATE_BATCH = 512  #: points decoded at a time while consolidating (bounded memory)
#: per-point scalar datasets: name -> (dtype, fill value)
SCALARS = {
    "status": (np.int8, STATUS_PENDING),
    "message": (f"S{MESSAGE_LENGTH}", b""),
    "regime": (np.int8, 0),
    "impacts_per_period": (np.int16, -1),
    "period_cycles": (np.int16, -1),
    "transient_used": (np.int32, -1),
    "corner_sequence": (f"S{SEQUENCE_LENGTH}", b""),
    "strobe_mismatch": (np.float64, np.nan),
    "zero_one": (np.float64, np.nan),
    "max_exponent": (np.float64, np.nan),
    "max_exponent_error": (np.float64, np.nan),
    "wall_s": (np.float64, np.nan),
    "steps": (np.int64, 0),
    "rejected": (np.int64, 0),
    "rhs_evals": (np.int64, 0),
    "impact_start": (np.int64, 0),
    "impact_count": (np.int64, 0),
    "strobe_start": (np.int64, 0),
    "strobe_count": (np.int64, 0),
}


#: the fixed part of a point's journal payload (little-endian, packed); the variable
#: parts follow it: final_state, exponents, the impacts' float fields, their corners,
#: the stroboscopic states, the message and the corner sequence (see :func:`_pack`)
RECORD = np.dtype([
    ("index", "<i8"), ("status", "i1"), ("regime", "i1"), ("impacts_per_period", "<i2"),
    ("period_cycles", "<i2"), ("transient_used", "<i4"), ("strobe_mismatch", "<f8"),
    ("zero_one", "<f8"), ("max_exponent", "<f8"), ("max_exponent_error", "<f8"),
    ("wall_s", "<f8"), ("steps", "<i8"), ("rejected", "<i8"), ("rhs_evals", "<i8"),
    ("impact_count", "<i8"), ("strobe_count", "<i8"), ("message_len", "<i4"),
    ("sequence_len", "<i4")])
FLOAT_IMPACTS = tuple(f for f in IMPACT_FIELDS if f != "corner")


class SweepStoreError(ValueError):
    """A file that is not a chaospound sweep store, or does not match the sweep (exit 2)."""


class StoreWriteError(OSError):
    """Storage failed (full disk, I/O error): committed points are safe (exit 1)."""


@dataclass
class PointResult:
    """Everything stored for one grid point (produced by the sweep workers)."""

    index: int
    status: int
    message: str
    regime: str
    impacts_per_period: int
    period_cycles: int
    strobe_mismatch: float
    zero_one: float
    max_exponent: float
    max_exponent_error: float
    transient_used: int
    corner_sequence: str
    exponents: np.ndarray | None
    final_state: np.ndarray
    steps: int
    rejected: int
    rhs_evals: int
    wall_s: float
    impacts: dict[str, np.ndarray]
    strobe: np.ndarray


class SweepWriter:
    """Create or resume a sweep, commit finished points, and consolidate the file.

    Parameters
    ----------
    path : str or Path
        The HDF5 file the finished sweep becomes.
    meta : dict
        Root attributes (scene TOML, resolved scene, sweep definition, ...).
    grid : dict[str, ndarray]
        Values of each swept parameter, in axis order.
    branches : dict[str, ndarray]
        Branch name -> visiting order of the grid indices.
    n_state : int
        State dimension of the model.
    n_exponents : int
        Number of Lyapunov exponents stored per point (0: none).
    resume : bool
        Continue the sweep's journal, or an unfinished file, keeping its points.
    overwrite : bool
        Start again; an existing file is replaced only when the new one is finished.

    Raises
    ------
    SweepStoreError
        Existing output without ``resume``/``overwrite``, a different sweep, a
        foreign file, or a live sweep holding the output.
    """

    def __init__(self, path, meta: dict, grid: dict, branches: dict, n_state: int,
                 n_exponents: int, *, resume: bool = False, overwrite: bool = False) -> None:
        self.path = Path(path)
        self.n_state = n_state
        self.n_exponents = n_exponents
        self.journal: Journal | None = None
        self.finished = False  #: resume found the file finished: nothing to do
        self._started = time.perf_counter()
        if self.path.is_dir():
            raise SweepStoreError(f"{self.path}: is a directory")
        if not self.path.parent.is_dir():
            raise SweepStoreError(f"{self.path}: directory {self.path.parent} does not exist")
        try:
            self.lock = OutputLock(self.path)
        except OutputBusy as exc:
            raise SweepStoreError(str(exc)) from None
        except OSError as exc:
            raise SweepStoreError(f"{self.path}: cannot create files in {self.path.parent} "
                                  f"({exc.strerror or exc})") from None
        self._pos = {}  #: branch -> position of each grid index in the visiting order
        for name, order in branches.items():
            pos = np.empty(len(order), dtype=np.int64)
            pos[np.asarray(order, dtype=np.int64)] = np.arange(len(order))
            self._pos[name] = pos
        try:
            self._open(meta, grid, branches, resume, overwrite)
        except BaseException:
            self.close()
            raise

    def _open(self, meta, grid, branches, resume: bool, overwrite: bool) -> None:
        jpath = journal_path(self.path)
        _remove_temporaries(self.path)
        attrs = _root_attributes(meta)
        create = {"attrs": attrs, "grid": grid, "orders": branches, "n_state": self.n_state,
                  "n_exponents": self.n_exponents}
        if jpath.exists() and not overwrite:
            if not resume:
                raise SweepStoreError(
                    f"{self.path}: an interrupted sweep's journal exists ({jpath.name}; use "
                    "--resume to finish it or --overwrite to replace it)")
            try:
                self.journal = Journal.open(jpath)
            except JournalError as exc:
                raise SweepStoreError(str(exc)) from None
            _check_same_sweep(self.journal.attrs, self.path, meta)
            return
        if self.path.exists() and not resume:  # (a resume checks it as it reads it)
            check_replaceable(self.path)  # a file of the user's own is never replaced
        if self.path.exists() and not overwrite:
            if not resume:
                raise SweepStoreError(f"{self.path}: file exists (use --resume to finish it or "
                                      "--overwrite to replace it)")
            with _open_readonly(self.path) as f:
                _check_same_sweep({k: _attr(v) for k, v in f.attrs.items()}, self.path, meta)
                if all(_is_finished(f[b]) for b in branches):
                    self.finished = True
                    return
                created = str(_attr(f.attrs.get("created", "")))
                self.journal = self._create_journal(jpath, create, created)
                _import_unfinished(f, self.journal, branches, self._pos)
            return
        self.journal = self._create_journal(jpath, create, time.strftime("%Y-%m-%dT%H:%M:%S"))

    def _create_journal(self, jpath: Path, create: dict, created: str) -> Journal:
        try:
            return Journal.create(jpath, created=created, **create)
        except sqlite3.Error as exc:
            remove_journal(jpath)
            raise StoreWriteError(f"{self.path}: cannot create the journal {jpath.name} "
                                  f"({_short(exc)})") from None

    # ------------------------------------------------------------- queries
    def pending(self, branch: str) -> np.ndarray:
        """Boolean mask over grid indices of the points still to compute."""
        if self.journal is None:
            return np.zeros(len(self._pos[branch]), dtype=bool)
        return self.journal.statuses(branch) == STATUS_PENDING

    def final_state(self, branch: str, index: int) -> np.ndarray | None:
        """The last stroboscopic state of a done point (continuation restarts from it)."""
        if self.journal is None:
            return None
        blob = self.journal.payload(branch, index)
        if blob is None:
            return None
        point = _unpack([blob], self.n_state, self.n_exponents)
        return point["final_state"][0] if point["status"][0] == STATUS_DONE else None

    def committed(self) -> int:
        """Finished points in the journal, over all branches."""
        if self.journal is None:
            return 0
        return sum(self.journal.counts(b)[0] for b in self.journal.branches)

    def regime_counts(self) -> dict[str, int]:
        """Regime name -> finished points, over all branches (including earlier runs)."""
        if self.journal is None:
            with _open_readonly(self.path) as f:
                codes = np.concatenate([f[b]["regime"][()] for b in self._pos])
            values, counts = np.unique(codes, return_counts=True)
            return {REGIMES[int(v)]: int(c) for v, c in zip(values, counts, strict=True)}
        return {REGIMES[code]: n for code, n in self.journal.regime_counts().items()}

    # -------------------------------------------------------------- writes
    def write(self, branch: str, results: list[PointResult]) -> None:
        """Commit a batch of finished points: one durable transaction.

        Raises
        ------
        StoreWriteError
            The journal could not be written (full disk, I/O error); the batch
            is rolled back, everything committed before stays.
        """
        if not results:
            return
        pos = self._pos[branch]
        rows = [_journal_row(*_pack_result(r, self.n_exponents), pos) for r in results]
        elapsed = time.perf_counter() - self._started
        try:
            self.journal.commit(branch, rows, elapsed)
        except sqlite3.Error as exc:
            with contextlib.suppress(sqlite3.Error):
                self.journal.conn.rollback()
            raise StoreWriteError(
                f"{self.path}: cannot commit to the journal ({_short(exc)}); the "
                f"{self.committed()} points committed before are safe: free space and finish "
                "with --resume") from None
        self._started = time.perf_counter()

    def finish(self) -> None:
        """Consolidate the journal into the HDF5 file (atomic rename), then remove it.

        Raises
        ------
        StoreWriteError
            Not enough space or a write error: the journal is kept, ``--resume``
            consolidates again.
        """
        if self.journal is None:
            return
        for b in self.journal.branches:
            missing = self.journal.orders[b].size - self.journal.counts(b)[0]
            if missing:
                raise RuntimeError(f"{self.path}: {missing} points of branch {b!r} are "
                                   "pending; the sweep is not finished")
        needed = int(1.2 * self.journal.payload_bytes()) + (1 << 20)
        free = shutil.disk_usage(self.path.parent).free
        if free < needed:
            raise StoreWriteError(
                f"{self.path}: not enough free space to write the file ({needed >> 20} MB "
                f"needed, {free >> 20} MB free); all points are safe in the journal: free "
                "space and run --resume")
        tmp = self.path.with_name(f"{self.path.name}.tmp-{os.getpid()}")
        try:
            with h5py.File(tmp, "w", track_order=True) as f:
                _consolidate(f, self.journal)
            _fsync_file(tmp)
            os.replace(tmp, self.path)
            fsync_dir(self.path.parent)
        except (OSError, RuntimeError, ValueError) as exc:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise StoreWriteError(f"{self.path}: cannot write the file ({_short(exc)}); all "
                                  "points are safe in the journal: run --resume") from None
        jpath = self.journal.path
        self.journal.close()
        self.journal = None
        remove_journal(jpath)
        fsync_dir(self.path.parent)

    def close(self) -> None:
        """Close the journal (kept for --resume unless finished) and release the lock."""
        if self.journal is not None:
            self.journal.close()
            self.journal = None
        lock = getattr(self, "lock", None)
        if lock is not None:
            lock.release()

    def __enter__(self) -> SweepWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# ====================================================================== reading


class SweepFile:
    """Read access to a sweep store (see :func:`open_sweep`)."""

    def __init__(self, path) -> None:
        self.path = Path(path)
        self.live = False  #: read from the journal of a running or interrupted sweep
        jpath = journal_path(self.path)
        if jpath.exists():
            try:
                journal = Journal.open(jpath, readonly=True)
            except JournalError as exc:
                if jpath.exists():
                    raise SweepStoreError(str(exc)) from None
            else:  # the journal is the truth while it exists
                try:
                    with h5py.File(f"{jpath}.view", "w", driver="core",
                                   backing_store=False) as f, journal.snapshot():
                        _consolidate(f, journal)
                        self._read(f)
                except sqlite3.Error as exc:
                    raise SweepStoreError(f"{jpath}: cannot read the journal "
                                          f"({_short(exc)})") from None
                finally:
                    journal.close()
                self.live = True
                return
        with _open_readonly(self.path) as f:
            try:
                self._read(f)
            except (OSError, KeyError, ValueError) as exc:
                raise SweepStoreError(f"{self.path}: cannot read the sweep store "
                                      f"({_short(exc)})") from None

    def _read(self, f: h5py.File) -> None:
        self.meta = {k: _attr(v) for k, v in f.attrs.items()}
        self.sweep = json.loads(self.meta["sweep"])
        self.parameters = list(self.sweep["parameters"])
        self.grid = {name: f["grid"][name][:] for name in self.parameters}
        self.branches = list(self.sweep["branches"])
        self._data = {}
        for b in self.branches:
            g = f[b]
            arrays = {name: g[name][:] for name in g if isinstance(g[name], h5py.Dataset)}
            arrays["impacts"] = {name: g["impacts"][name][:] for name in IMPACT_FIELDS}
            arrays["strobe"] = g["strobe"]["state"][:]
            self._data[b] = arrays

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(self.grid[name]) for name in self.parameters)

    @property
    def state_names(self) -> list[str]:
        return json.loads(self.meta["state_names"])

    def points(self) -> np.ndarray:
        """Parameter values of every grid point, (N, n_parameters), row-major."""
        axes = np.meshgrid(*[self.grid[n] for n in self.parameters], indexing="ij")
        return np.stack([a.ravel() for a in axes], axis=1)

    def array(self, name: str, branch: str | None = None) -> np.ndarray:
        """A per-point array (e.g. "max_exponent", "status", "steps"), by grid index."""
        data = self._data[self._branch(branch)]
        if name not in data or name in ("impacts", "strobe"):
            names = sorted(k for k in data if k not in ("impacts", "strobe"))
            raise SweepStoreError(f"no per-point array {shorten(name, quote=True)}; the store "
                                  f"has: {', '.join(names)}")
        return data[name]

    def to_xarray(self, branch: str | None = None):
        """One branch as an ``xarray.Dataset`` with named dimensions and units.

        Per-point arrays have the swept parameters as dimensions (coordinates:
        the grid values, exactly as stored, so ``.sel(period_ratio=0.9)``
        works), plus ``state`` or ``exponent`` for vectors; regimes, statuses,
        messages and corner sequences are strings. The flat impact and
        stroboscopic rows keep their own dimensions (``impact``, ``strobe_row``)
        and are addressed by ``impact_start``/``impact_count`` and
        ``strobe_start``/``strobe_count``. Attributes carry the scene, the sweep
        definition, the model and the units.
        """
        import xarray as xr

        name = self._branch(branch)
        data = self._data[name]
        dims = tuple(self.parameters)
        shape = self.shape
        coords = {p: (p, self.grid[p], {"long_name": AXIS_LABELS.get(p, p),
                                        "units": "1 (dimensionless)"})
                  for p in self.parameters}
        coords["state"] = ("state", np.array(self.state_names))
        variables = {}
        for key, values in data.items():
            if key in ("impacts", "strobe", "order"):
                continue
            values = np.asarray(values)
            if key == "regime":
                values = np.array([REGIMES[int(c)] for c in values])
            elif key == "status":
                values = np.array([("pending", "done", "failed")[int(c)] for c in values])
            elif values.dtype.kind == "S":
                values = np.char.decode(values, "utf-8", errors="replace")
            extra = {"final_state": ("state",), "exponents": ("exponent",)}.get(key, ())
            variables[key] = (dims + extra, values.reshape(shape + values.shape[1:]),
                              _var_attrs(key))
        variables["order"] = (("visit",), data["order"],
                              {"long_name": "grid indices (row-major) in visiting order"})
        for field, values in data["impacts"].items():
            if field == "corner":
                from .physics.corners import CORNER_LABELS

                values = np.array([CORNER_LABELS[int(c)] for c in values], dtype="U4")
            variables[f"impact_{field}"] = (("impact",), values, _var_attrs(field))
        variables["strobe_state"] = (("strobe_row", "state"), data["strobe"],
                                     _var_attrs("strobe_state"))
        attrs = {k: v for k, v in self.meta.items() if isinstance(v, str | int | float)}
        attrs["branch"] = name
        return xr.Dataset(variables, coords=coords, attrs=attrs)

    def close(self) -> None:
        """Nothing to release: the store is read whole when it is opened."""

    def __enter__(self) -> SweepFile:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        try:
            scene = json.loads(self.meta["scene_resolved"]).get("name", "?")
        except (KeyError, TypeError, ValueError):
            scene = self.meta.get("name", "?")
        axes = ", ".join(f"{p} {self.grid[p][0]:g}..{self.grid[p][-1]:g} "
                         f"({len(self.grid[p])})" for p in self.parameters)
        lines = [f"<chaospound sweep {self.path.name}{' (live journal)' if self.live else ''}: "
                 f"scene {scene!r}, {self.meta.get('model', '?')} model",
                 f"  grid: {axes}"]
        for b in self.branches:
            status = self._data[b]["status"]
            codes = self._data[b]["regime"][status != STATUS_PENDING]
            values, counts = np.unique(codes, return_counts=True)
            regimes = ", ".join(f"{REGIMES[int(v)]} {c}" for v, c in zip(values, counts,
                                                                          strict=True))
            lines.append(f"  {b}: {int((status != STATUS_PENDING).sum())} of {status.size} "
                         f"done; {regimes or 'no points yet'}")
        return "\n".join(lines) + ">"

    def regimes(self, branch: str | None = None) -> list[str]:
        return [REGIMES[int(c)] for c in self.array("regime", branch)]

    def status(self, branch: str | None = None) -> list[str]:
        names = ("pending", "done", "failed")
        return [names[int(s)] for s in self.array("status", branch)]

    def messages(self, branch: str | None = None) -> list[str]:
        return [m.decode("utf-8", errors="replace") for m in self.array("message", branch)]

    def impacts(self, index: int, branch: str | None = None) -> dict[str, np.ndarray]:
        """The impacts of one grid point: time, phase, velocity, corner (labels), ..."""
        data = self._data[self._branch(branch)]
        start = int(data["impact_start"][index])
        count = int(data["impact_count"][index])
        out = {name: data["impacts"][name][start:start + count] for name in IMPACT_FIELDS}
        from .physics.corners import CORNER_LABELS

        out["corner"] = np.array([CORNER_LABELS[int(c)] for c in out["corner"]])
        return out

    def strobe(self, index: int, branch: str | None = None) -> np.ndarray:
        data = self._data[self._branch(branch)]
        start = int(data["strobe_start"][index])
        return data["strobe"][start:start + int(data["strobe_count"][index])]

    def impact_velocities(self, branch: str | None = None) -> list[np.ndarray]:
        """Per grid point, the relative impact velocities (for bifurcation diagrams)."""
        return [self.impacts(i, branch)["velocity"] for i in range(int(np.prod(self.shape)))]

    def _branch(self, branch: str | None) -> str:
        if branch is None:
            return self.branches[0]
        if branch not in self.branches:
            raise SweepStoreError(f"branch {branch!r}: the file has {', '.join(self.branches)}")
        return branch


#: axis labels of the usual swept parameters (symbols, dimensionless)
AXIS_LABELS = {"period_ratio": "T/T_Ax", "gap": "a/A_g", "freq_ratio": "T_Ax/T_Bx",
               "mass_ratio": "m_A/m_B", "beta": "beta", "chi": "chi"}
#: units of stored quantities (per-point and flat)
_UNIT_OF = {
    "time": UNITS["time"], "duration": UNITS["time"], "phase": UNITS["phase"],
    "velocity": UNITS["velocity"], "peak_penetration": UNITS["length"],
    "peak_force": UNITS["force"], "max_exponent": UNITS["exponents"],
    "max_exponent_error": UNITS["exponents"], "exponents": UNITS["exponents"],
    "wall_s": "s", "transient_used": "excitation cycles", "period_cycles": "excitation cycles",
    "final_state": "A_g, A_g omega_Ax, rad, rad omega_Ax (by state)",
    "strobe_state": "A_g, A_g omega_Ax, rad, rad omega_Ax (by state)",
}


def _var_attrs(name: str) -> dict:
    return {"units": _UNIT_OF[name]} if name in _UNIT_OF else {}


def open_sweep(path) -> SweepFile:
    """Open a sweep store for reading: a finished file, or a running or interrupted sweep.

    While a sweep's journal exists (the sweep runs, or was interrupted and not
    yet resumed) its committed points are read from it, the others read as
    pending.
    """
    path = Path(path)
    if path.name.endswith(JOURNAL_SUFFIX):  # the journal itself: read its sweep
        path = path.with_name(path.name[: -len(JOURNAL_SUFFIX)])
    return SweepFile(path)


def sweep_progress(path) -> tuple[int, int]:
    """(points finished, points in the grid) of a sweep, cheaply (no data is read)."""
    path = Path(path)
    jpath = journal_path(path)
    if jpath.exists():
        with contextlib.suppress(JournalError, sqlite3.Error):
            journal = Journal.open(jpath, readonly=True)
            try:
                with journal.snapshot():
                    done = sum(journal.counts(b)[0] for b in journal.branches)
                return done, sum(journal.orders[b].size for b in journal.branches)
            finally:
                journal.close()
    with _open_readonly(path) as f:
        branches = json.loads(_attr(f.attrs["sweep"]))["branches"]
        status = [f[b]["status"][()] for b in branches]
        return (int(sum((s != STATUS_PENDING).sum() for s in status)),
                int(sum(s.size for s in status)))


# ================================================================ consolidation


def _root_attributes(meta: dict) -> dict:
    attrs = {"format": FORMAT, "format_version": FORMAT_VERSION, "units": json.dumps(UNITS)}
    attrs.update(meta)
    return attrs


def _journal_row(record: np.ndarray, blob: bytes, pos: np.ndarray) -> tuple:
    """The journal's row of a packed point: (idx, pos, status, regime, impact and
    stroboscopic row counts, payload), the columns read from its record."""
    idx = int(record["index"])
    return (idx, int(pos[idx]), int(record["status"]), int(record["regime"]),
            int(record["impact_count"]), int(record["strobe_count"]), blob)


def _pack_result(r: PointResult, n_exponents: int) -> tuple[np.ndarray, bytes]:
    """A point's fixed record and its journal payload, from the worker's result."""
    record = np.zeros((), dtype=RECORD)
    message = r.message.encode("utf-8")[:MESSAGE_LENGTH]
    sequence = r.corner_sequence.encode("ascii")[:SEQUENCE_LENGTH]
    for name in RECORD.names:
        if name == "message_len":
            record[name] = len(message)
        elif name == "sequence_len":
            record[name] = len(sequence)
        elif name == "regime":
            record[name] = REGIMES.index(r.regime)
        elif name == "impact_count":
            record[name] = len(r.impacts["time"])
        elif name == "strobe_count":
            record[name] = r.strobe.shape[0]
        else:
            record[name] = getattr(r, name)
    exponents = None
    if n_exponents:
        exponents = r.exponents if r.exponents is not None else np.full(n_exponents, np.nan)
    return record, _pack(record, r.final_state, exponents, r.impacts, r.strobe, message,
                         sequence)


def _pack(record: np.ndarray, final_state, exponents, impacts: dict, strobe, message: bytes,
          sequence: bytes) -> bytes:
    """Concatenate a point's fixed record and its variable parts (see :data:`RECORD`)."""
    parts = [record.tobytes(), np.asarray(final_state, dtype="<f8").tobytes()]
    if exponents is not None:
        parts.append(np.asarray(exponents, dtype="<f8").tobytes())
    parts += [np.asarray(impacts[f], dtype="<f8").tobytes() for f in FLOAT_IMPACTS]
    parts += [np.asarray(impacts["corner"], dtype="i1").tobytes(),
              np.asarray(strobe, dtype="<f8").tobytes(), message, sequence]
    return b"".join(parts)


def _unpack(blobs: list[bytes], n_state: int, n_exponents: int) -> dict:
    """Columns of a batch of payloads, in the batch's order: the record's fields, plus
    final_state, exponents, message, corner_sequence, and the flat impacts/strobe rows."""
    size = RECORD.itemsize
    records = np.frombuffer(b"".join(blob[:size] for blob in blobs), dtype=RECORD)
    n = len(blobs)
    out = {name: records[name] for name in RECORD.names}
    final = np.empty((n, n_state))
    exponents = np.empty((n, n_exponents))
    flat = {f: [] for f in IMPACT_FIELDS}
    strobe, messages, sequences = [], [], []

    def take(blob, dtype, count, offset):
        return (np.frombuffer(blob, dtype=dtype, count=count, offset=offset) if count
                else np.zeros(0, dtype=dtype))

    for j, blob in enumerate(blobs):
        n_imp, n_strobe = int(records["impact_count"][j]), int(records["strobe_count"][j])
        at = size
        final[j] = take(blob, "<f8", n_state, at)
        at += 8 * n_state
        if n_exponents:
            exponents[j] = take(blob, "<f8", n_exponents, at)
            at += 8 * n_exponents
        for f in FLOAT_IMPACTS:
            flat[f].append(take(blob, "<f8", n_imp, at))
            at += 8 * n_imp
        flat["corner"].append(take(blob, "i1", n_imp, at))
        at += n_imp
        strobe.append(take(blob, "<f8", n_strobe * n_state, at).reshape(n_strobe, n_state))
        at += 8 * n_strobe * n_state
        m, q = int(records["message_len"][j]), int(records["sequence_len"][j])
        messages.append(blob[at:at + m])
        sequences.append(blob[at + m:at + m + q])
    out["final_state"] = final
    if n_exponents:
        out["exponents"] = exponents
    out["message"] = np.array(messages, dtype=f"S{MESSAGE_LENGTH}")
    out["corner_sequence"] = np.array(sequences, dtype=f"S{SEQUENCE_LENGTH}")
    out["impacts"] = {f: np.concatenate(flat[f]) for f in IMPACT_FIELDS}
    out["strobe"] = np.concatenate(strobe) if strobe else np.zeros((0, n_state))
    return out


def _consolidate(f: h5py.File, journal: Journal) -> None:
    """Write the whole store from a journal (pending points keep their fill values)."""
    attrs = dict(journal.attrs)
    attrs["created"] = journal.created
    attrs["wall_s"] = journal.wall_s
    for key, value in attrs.items():
        f.attrs[key] = value
    g = f.create_group("grid")
    for name, values in journal.grid.items():
        g.create_dataset(name, data=values)
    for branch in journal.branches:
        _write_branch(f.create_group(branch), journal, branch)


def _write_branch(b: h5py.Group, journal: Journal, branch: str) -> None:
    order = journal.orders[branch]
    n_points, n_state, k = order.size, journal.n_state, journal.n_exponents
    _, n_impacts, n_strobe = journal.counts(branch)
    b.attrs["impacts_committed"] = n_impacts
    b.attrs["strobe_committed"] = n_strobe
    b.attrs["REGIMES"] = json.dumps(REGIMES)
    b.create_dataset("order", data=order)
    # every dataset is opened once (h5py drops a dataset's chunk cache with the object:
    # re-opening per batch would recompress each gzip chunk once per batch), with a
    # cache of two chunks (the one being filled and the next: points and rows are
    # written in order), not HDF5's 1 MiB per dataset (30 MiB for a large sweep)
    def dataset(group, name, shape, dtype, chunks, **options):
        nbytes = 2 * int(np.prod(chunks)) * np.dtype(dtype).itemsize
        return group.create_dataset(name, shape=shape, dtype=dtype, chunks=chunks,
                                    compression="gzip", shuffle=True, rdcc_nbytes=nbytes,
                                    rdcc_w0=1.0, **options)

    rows = min(n_points, CHUNK)
    per_point = {name: dataset(b, name, (n_points,), dtype, (rows,), fillvalue=fill)
                 for name, (dtype, fill) in SCALARS.items()}
    widths = {"final_state": n_state, **({"exponents": k} if k else {})}
    for name, width in widths.items():
        per_point[name] = dataset(b, name, (n_points, width), np.float64, (rows, width),
                                  fillvalue=np.nan)
    group = b.create_group("impacts")
    imp = {field: dataset(group, field, (n_impacts,), np.int8 if field == "corner"
                          else np.float64, (CHUNK,), maxshape=(None,))
           for field in IMPACT_FIELDS}
    strobe = dataset(b.create_group("strobe"), "state", (n_strobe, n_state), np.float64,
                     (CHUNK // 4, n_state), maxshape=(None, n_state))
    imp_row = strobe_row = 0
    for batch in journal.rows_in_order(branch, CONSOLIDATE_BATCH):
        point = _unpack(batch, n_state, k)
        counts, s_counts = point["impact_count"], point["strobe_count"]
        point["impact_start"] = imp_row + np.concatenate(([0], np.cumsum(counts)[:-1]))
        point["strobe_start"] = strobe_row + np.concatenate(([0], np.cumsum(s_counts)[:-1]))
        idx = point["index"]
        sort = np.argsort(idx)
        where = _index(idx[sort])
        for name, ds in per_point.items():
            ds[where] = np.asarray(point[name], dtype=ds.dtype)[sort]
        new_imp, new_strobe = int(counts.sum()), int(s_counts.sum())
        if new_imp:
            for field, ds in imp.items():
                ds[imp_row:imp_row + new_imp] = point["impacts"][field]
        if new_strobe:
            strobe[strobe_row:strobe_row + new_strobe] = point["strobe"]
        imp_row += new_imp
        strobe_row += new_strobe


def _index(sorted_idx: np.ndarray):
    """A slice when the sorted indices are contiguous (fast h5py writes), else the array."""
    first, last = int(sorted_idx[0]), int(sorted_idx[-1])
    return slice(first, last + 1) if last - first + 1 == sorted_idx.size else sorted_idx


def _is_finished(g: h5py.Group) -> bool:
    """Every point done or failed, and the flat arrays' lengths consistent with them."""
    return bool(np.all(g["status"][()] != STATUS_PENDING)
                and int(g.attrs.get("impacts_committed", -1)) == int(g["impact_count"][()].sum())
                and int(g.attrs.get("strobe_committed", -1)) == int(g["strobe_count"][()].sum()))


def _import_unfinished(f: h5py.File, journal: Journal, branches: dict,
                       positions: dict[str, np.ndarray]) -> None:
    """Copy the finished points of an unfinished in-place (version 0.1) file into a journal.

    The flat rows of the points marked done or failed are a prefix of the flat
    arrays (they were appended in the branch's visiting order), so each point
    is read back exactly as it was written.
    """
    for branch, order in branches.items():
        g = f[branch]
        status = g["status"][()]
        pos = positions[branch]
        arrays = {name: g[name][()] for name in (*SCALARS, "final_state",
                                                  *(("exponents",) if "exponents" in g else ()))}
        impacts = {name: g["impacts"][name][()] for name in IMPACT_FIELDS}
        states = g["strobe"]["state"][()]
        rows = []
        for i in np.asarray(order)[status[np.asarray(order)] != STATUS_PENDING]:
            i = int(i)
            record = np.zeros((), dtype=RECORD)
            message, sequence = bytes(arrays["message"][i]), bytes(arrays["corner_sequence"][i])
            for name in RECORD.names:
                if name == "index":
                    record[name] = i
                elif name == "message_len":
                    record[name] = len(message)
                elif name == "sequence_len":
                    record[name] = len(sequence)
                else:
                    record[name] = arrays[name][i]
            s, c = int(arrays["impact_start"][i]), int(arrays["impact_count"][i])
            point_impacts = {name: impacts[name][s:s + c] for name in IMPACT_FIELDS}
            s, c = int(arrays["strobe_start"][i]), int(arrays["strobe_count"][i])
            exponents = arrays["exponents"][i] if "exponents" in arrays else None
            blob = _pack(record, arrays["final_state"][i], exponents, point_impacts,
                         states[s:s + c], message, sequence)
            rows.append(_journal_row(record, blob, pos))
        journal.commit(branch, rows, 0.0)
    journal.conn.execute("UPDATE meta SET value = ? WHERE key = 'wall_s'",
                         (float(f.attrs.get("wall_s", 0.0)),))


# ====================================================================== helpers


def _attr(value):
    return value.decode("utf-8") if isinstance(value, bytes) else value


def _open_readonly(path: Path) -> h5py.File:
    """A finished (or version 0.1) store opened read-only, checked to be a sweep store."""
    if not path.exists():
        raise SweepStoreError(f"{path}: no such file")
    if path.is_dir():
        raise SweepStoreError(f"{path}: is a directory, not a sweep store")
    try:
        f = h5py.File(path, "r", locking=False)
    except OSError as exc:
        raise SweepStoreError(f"{path}: not a readable HDF5 file ({_short(exc)})") from None
    if _attr(f.attrs.get("format", "")) != FORMAT:
        f.close()
        raise SweepStoreError(f"{path}: not a chaospound sweep store (no format={FORMAT!r})")
    if int(f.attrs.get("format_version", 0)) > FORMAT_VERSION:
        f.close()
        raise SweepStoreError(f"{path}: store format version is newer than this chaospound")
    return f


def check_replaceable(path) -> None:
    """Refuse an output path that holds something other than a chaospound store: neither
    ``--resume`` nor ``--overwrite`` may touch a scene file, a record or a foreign HDF5
    file that an ``-o`` happens to name."""
    try:
        with _open_readonly(Path(path)):
            pass
    except SweepStoreError as exc:
        raise SweepStoreError(f"{exc}; it is left as it is: choose another output, or remove "
                              "the file first") from None


def _short(exc: Exception) -> str:
    text = str(exc).splitlines()
    return text[0][:120] if text else type(exc).__name__


def _check_same_sweep(stored: dict, path, meta) -> None:
    if "system" in meta or "system" in stored:
        _check_same_system(stored, path, meta)
        return
    try:  # the same code wrote both: equal text (parsing 1e5 grid values costs memory)
        same = stored["scene"] == meta["scene"] and (
            stored["sweep"] == meta["sweep"]
            or json.loads(stored["sweep"]) == json.loads(meta["sweep"]))
    except (KeyError, TypeError, ValueError):
        same = False
    if not same:
        raise SweepStoreError(
            f"{path}: holds a different sweep or scene ({_what_differs(stored, meta)}); resume "
            "needs the same definition (use --overwrite to start again)")


def _what_differs(stored: dict, meta: dict) -> str:
    """The first setting that differs between the stored and the new definition, as
    ``name: <in the file> in the file, <now> now`` (the scene's TOML tables and keys,
    then the sweep's axes and options)."""
    from .scene import tomllib  # tomli before Python 3.11

    def flat(value, prefix=""):
        if isinstance(value, dict):
            out = {}
            for key, item in value.items():
                out.update(flat(item, f"{prefix}{key}."))
            return out
        return {prefix.rstrip("."): value}

    for field, parse in (("scene", tomllib.loads), ("sweep", json.loads)):
        try:
            was, now = flat(parse(stored[field])), flat(parse(meta[field]))
        except (KeyError, TypeError, ValueError):
            continue
        for key in dict.fromkeys([*now, *was]):
            if was.get(key) != now.get(key):
                name = key if field == "scene" else f"sweep {key}"
                return (f"{name}: {shorten(json.dumps(was.get(key)), 40)} in the file, "
                        f"{shorten(json.dumps(now.get(key)), 40)} now")
    return "its definition"


def _check_same_system(stored: dict, path, meta) -> None:
    """A sweep of a user's System resumes only the same system (its ``system`` attribute:
    source file's sha256, ``module:attr``, parameters, states, solver) and sweep."""
    if "system" not in stored:
        raise SweepStoreError(f"{path}: holds a sweep of a scene, not of a system; resume "
                              "needs the same system (use --overwrite to start again)")
    if "system" not in meta:
        raise SweepStoreError(f"{path}: holds a sweep of a system, not of a scene; resume "
                              "needs the same scene (use --overwrite to start again)")
    try:
        was, now = json.loads(stored["system"]), json.loads(meta["system"])
        same_sweep = (stored["sweep"] == meta["sweep"]
                      or json.loads(stored["sweep"]) == json.loads(meta["sweep"]))
    except (KeyError, TypeError, ValueError):
        was, now, same_sweep = {}, {"?": 1}, False
    if was != now:
        keys = [k for k in dict.fromkeys([*now, *was]) if was.get(k) != now.get(k)]
        key = keys[0]
        raise SweepStoreError(
            f"{path}: holds a sweep of a different system ({key}: "
            f"{shorten(json.dumps(was.get(key)), 60)} in the file, "
            f"{shorten(json.dumps(now.get(key)), 60)} now); resume needs the same system "
            "(use --overwrite to start again)")
    if not same_sweep:
        raise SweepStoreError(f"{path}: holds a different sweep of this system; resume needs "
                              "the same definition (use --overwrite to start again)")


def _remove_temporaries(path: Path) -> None:
    """Half-written consolidations and journals of killed sweeps (the lock is held: none is
    live)."""
    name = _glob_escape(path.name)
    for tmp in [*path.parent.glob(f"{name}.tmp-*"), *path.parent.glob(f"{name}.journal.new-*")]:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _glob_escape(name: str) -> str:
    return "".join(f"[{c}]" if c in "*?[" else c for c in name)


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


__all__ += ["PointResult", "sweep_progress"]
