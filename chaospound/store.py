"""HDF5 store of bifurcation sweeps: schema, incremental writes, resume, reading.

Schema (format "chaospound-sweep", version 1)::

    /                         attrs: format, format_version, chaospound_version,
                                     scene (TOML), scene_resolved (JSON), sweep (JSON),
                                     units (JSON), model, state_names (JSON),
                                     created, wall_s (timing fields)
    /grid/<name>              values of each swept parameter (1 or 2 axes, in order)
    /<branch>/                "fresh", or "forward" / "backward" (continuation)
        order                 (N,) grid indices in the branch's visiting order
        status                (N,) int8: 0 pending, 1 done, 2 failed
        message               (N,) bytes: the failure message of failed points
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
                              flat, appended in the branch's order (corner: int8 code)
        strobe_start, strobe_count   (N,) int64
        strobe/state          (M, n) flat stroboscopic states

Per-point arrays are indexed by the grid index (row-major over the axes).
Crash safety: every batch is written, flushed, and only then are the points'
statuses set to done and flushed; the flat arrays' committed lengths are
branch attributes (impacts_committed, strobe_committed). A killed run
therefore leaves a file that opens and in which every point marked done is
complete; :func:`SweepWriter` on resume truncates the flat arrays to the rows
of the points marked done or failed, so the resumed file equals an
uninterrupted run's (timing fields aside). A file that a running sweep holds
open can be read (:func:`open_sweep`) but not resumed.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

__all__ = ["FORMAT", "REGIMES", "SweepFile", "SweepStoreError", "SweepWriter", "open_sweep"]

FORMAT = "chaospound-sweep"
FORMAT_VERSION = 1
REGIMES = ("pending", "none", "periodic", "group-periodic", "quasi-periodic", "chaotic",
           "unresolved", "failed")
STATUS_PENDING, STATUS_DONE, STATUS_FAILED = 0, 1, 2
UNITS = {
    "time": "normalised, t = tau omega_Ax",
    "length": "A_g (ground displacement amplitude)",
    "velocity": "A_g omega_Ax",
    "force": "A_g k_Ax",
    "exponents": "per unit normalised time (multiply by the period T for per cycle)",
    "phase": "fraction of the excitation period, in [0, 1)",
}
IMPACT_FIELDS = ("time", "phase", "velocity", "corner", "peak_penetration", "peak_force",
                 "duration")
TIMING_FIELDS = ("wall_s", "created")
MESSAGE_LENGTH = 240
SEQUENCE_LENGTH = 160  #: room for 53 corner labels of one period
LIVE_READ_ATTEMPTS = 20  #: reads of a file that a running sweep is writing ...
LIVE_READ_PAUSE = 0.05  #: ... this many seconds apart
CHUNK = 4096


class SweepStoreError(ValueError):
    """A file that is not a chaospound sweep store, or does not match the sweep."""


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
    """Create or resume a sweep file and append finished points to it.

    Parameters
    ----------
    path : str or Path
        The HDF5 file.
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
        Open an existing file of the same sweep and keep its finished points.
    overwrite : bool
        Replace an existing file.
    """

    def __init__(self, path, meta: dict, grid: dict, branches: dict, n_state: int,
                 n_exponents: int, *, resume: bool = False, overwrite: bool = False) -> None:
        self.path = Path(path)
        self.n_state = n_state
        self.n_exponents = n_exponents
        self._started = time.perf_counter()
        if self.path.exists() and not (resume or overwrite):
            raise SweepStoreError(f"{self.path}: file exists (use --resume to finish it or "
                                  "--overwrite to replace it)")
        if resume and self.path.exists():
            with _open_readonly(self.path) as f:  # never open a foreign file for writing
                _check_same_sweep(f, self.path, meta, grid, branches)
            self.file = _open_for_append(self.path)
            for name in branches:
                _truncate_uncommitted(self.file[name])
            self.file.flush()
        else:
            if not self.path.parent.exists():
                raise SweepStoreError(f"{self.path}: directory {self.path.parent} does not exist")
            tmp = self.path.with_name(self.path.name + ".part")
            with h5py.File(tmp, "w", track_order=True) as f:
                _create_layout(f, meta, grid, branches, n_state, n_exponents)
            os.replace(tmp, self.path)
            self.file = h5py.File(self.path, "r+")

    # ------------------------------------------------------------- queries
    def pending(self, branch: str) -> np.ndarray:
        """Boolean mask over grid indices of the points still to compute."""
        return self.file[branch]["status"][:] == STATUS_PENDING

    def final_state(self, branch: str, index: int) -> np.ndarray | None:
        group = self.file[branch]
        if group["status"][index] != STATUS_DONE:
            return None
        return group["final_state"][index]

    # -------------------------------------------------------------- writes
    def write(self, branch: str, results: list[PointResult]) -> None:
        """Append a batch of finished points (in the branch's order) and commit it."""
        if not results:
            return
        group = self.file[branch]
        imp_rows = group.attrs["impacts_committed"]
        strobe_rows = group.attrs["strobe_committed"]
        new_imp = sum(len(r.impacts["time"]) for r in results)
        new_strobe = sum(r.strobe.shape[0] for r in results)
        impacts = group["impacts"]
        for field in IMPACT_FIELDS:
            data = np.concatenate([r.impacts[field] for r in results]) if new_imp else None
            ds = impacts[field]
            ds.resize((imp_rows + new_imp,))
            if new_imp:
                ds[imp_rows:] = data
        ds = group["strobe"]["state"]
        ds.resize((strobe_rows + new_strobe, self.n_state))
        if new_strobe:
            ds[strobe_rows:] = np.concatenate([r.strobe for r in results])
        idx = np.array([r.index for r in results])
        order = np.argsort(idx)
        idx_sorted = idx[order]
        contiguous = int(idx_sorted[-1]) - int(idx_sorted[0]) + 1 == len(idx_sorted)
        where = slice(int(idx_sorted[0]), int(idx_sorted[-1]) + 1) if contiguous else idx_sorted

        def put(name, values, dtype=None):
            arr = np.asarray(values, dtype=dtype)[order]
            group[name][where] = arr

        counts = np.array([len(r.impacts["time"]) for r in results], dtype=np.int64)
        starts = imp_rows + np.concatenate(([0], np.cumsum(counts)[:-1]))
        s_counts = np.array([r.strobe.shape[0] for r in results], dtype=np.int64)
        s_starts = strobe_rows + np.concatenate(([0], np.cumsum(s_counts)[:-1]))
        put("impact_start", starts)
        put("impact_count", counts)
        put("strobe_start", s_starts)
        put("strobe_count", s_counts)
        put("message", [r.message.encode("utf-8")[:MESSAGE_LENGTH] for r in results],
            dtype=f"S{MESSAGE_LENGTH}")
        put("regime", [REGIMES.index(r.regime) for r in results], dtype=np.int8)
        for name in ("impacts_per_period", "period_cycles"):
            put(name, [getattr(r, name) for r in results], dtype=np.int16)
        put("transient_used", [r.transient_used for r in results], dtype=np.int32)
        put("corner_sequence", [r.corner_sequence.encode("ascii")[:SEQUENCE_LENGTH]
                                for r in results], dtype=f"S{SEQUENCE_LENGTH}")
        for name in ("strobe_mismatch", "zero_one", "max_exponent", "max_exponent_error",
                     "wall_s"):
            put(name, [getattr(r, name) for r in results], dtype=np.float64)
        for name in ("steps", "rejected", "rhs_evals"):
            put(name, [getattr(r, name) for r in results], dtype=np.int64)
        put("final_state", np.stack([r.final_state for r in results]))
        if self.n_exponents:
            put("exponents", np.stack([
                r.exponents if r.exponents is not None else np.full(self.n_exponents, np.nan)
                for r in results]))
        self.file.flush()
        # commit: statuses and the flat arrays' lengths, after the data is on disk
        put("status", [r.status for r in results], dtype=np.int8)
        group.attrs["impacts_committed"] = imp_rows + new_imp
        group.attrs["strobe_committed"] = strobe_rows + new_strobe
        self.file.attrs["wall_s"] = (float(self.file.attrs.get("wall_s", 0.0))
                                     + time.perf_counter() - self._started)
        self._started = time.perf_counter()
        self.file.flush()

    def close(self) -> None:
        if getattr(self, "file", None) is not None:
            self.file.close()
            self.file = None

    def __enter__(self) -> SweepWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# ====================================================================== reading


class SweepFile:
    """Read access to a sweep store (see :func:`open_sweep`)."""

    def __init__(self, path) -> None:
        self.path = Path(path)
        for attempt in range(LIVE_READ_ATTEMPTS):
            f, live = _open_for_reading(self.path)
            try:
                with f:
                    self._read(f)
                return
            except (OSError, KeyError, ValueError) as exc:
                if isinstance(exc, SweepStoreError):
                    raise
                # a running sweep may be writing what we read: read again, a moment later
                if not live or attempt == LIVE_READ_ATTEMPTS - 1:
                    what = "while a sweep writes it " if live else ""
                    raise SweepStoreError(f"{self.path}: cannot read the sweep store {what}"
                                          f"({_short(exc)})") from None
                time.sleep(LIVE_READ_PAUSE)

    def _read(self, f: h5py.File) -> None:
        self.meta = {k: _attr(v) for k, v in f.attrs.items()}
        self.sweep = json.loads(self.meta["sweep"])
        self.parameters = list(self.sweep["parameters"])
        self.grid = {name: f["grid"][name][:] for name in self.parameters}
        self.branches = list(self.sweep["branches"])
        self._data = {}
        for b in self.branches:
            g = f[b]
            # statuses first: in a file still being written, the data of every point
            # seen as done was flushed before its status
            arrays = {"status": g["status"][:]}
            arrays.update({name: g[name][:] for name in g
                           if name != "status" and isinstance(g[name], h5py.Dataset)})
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
        """A per-point array (e.g. "max_exponent", "status", "steps")."""
        return self._data[self._branch(branch)][name]

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
        from .kernels.integrate import CORNER_LABELS

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


def open_sweep(path) -> SweepFile:
    """Open a sweep store for reading (also a partially written one).

    A file that a running sweep holds open is read without HDF5's file lock:
    the points it shows as done are complete, later ones read as pending.
    """
    return SweepFile(path)


# ====================================================================== helpers


def _attr(value):
    return value.decode("utf-8") if isinstance(value, bytes) else value


def _open_readonly(path: Path) -> h5py.File:
    return _open_for_reading(path)[0]


def _open_for_reading(path: Path) -> tuple[h5py.File, bool]:
    """The store opened read-only, and whether a running sweep holds it (live)."""
    if not path.exists():
        raise SweepStoreError(f"{path}: no such file")
    live = False
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        if "lock" not in str(exc):
            raise SweepStoreError(f"{path}: not a readable HDF5 file ({_short(exc)})") from None
        try:  # a running sweep holds the write lock: read its committed points anyway
            f = h5py.File(path, "r", locking=False)
            live = True
        except OSError as again:
            raise SweepStoreError(f"{path}: not a readable HDF5 file ({_short(again)})") from None
    if _attr(f.attrs.get("format", "")) != FORMAT:
        f.close()
        raise SweepStoreError(f"{path}: not a chaospound sweep store (no format={FORMAT!r})")
    if int(f.attrs.get("format_version", 0)) > FORMAT_VERSION:
        f.close()
        raise SweepStoreError(f"{path}: store format version is newer than this chaospound")
    return f, live


def _open_for_append(path: Path) -> h5py.File:
    try:
        return h5py.File(path, "r+")
    except OSError as exc:
        hint = "; is a sweep still writing it?" if "lock" in str(exc) else ""
        raise SweepStoreError(f"{path}: cannot open for writing ({_short(exc)}){hint}") from None


def _short(exc: Exception) -> str:
    return str(exc).splitlines()[0][:120]


def _create_layout(f, meta, grid, branches, n_state, n_exponents) -> None:
    f.attrs["format"] = FORMAT
    f.attrs["format_version"] = FORMAT_VERSION
    f.attrs["units"] = json.dumps(UNITS)
    for key, value in meta.items():
        f.attrs[key] = value
    f.attrs["created"] = time.strftime("%Y-%m-%dT%H:%M:%S")
    f.attrs["wall_s"] = 0.0
    g = f.create_group("grid")
    for name, values in grid.items():
        g.create_dataset(name, data=np.asarray(values, dtype=np.float64))
    n_points = int(np.prod([len(v) for v in grid.values()]))
    for name, order in branches.items():
        b = f.create_group(name)
        b.attrs["impacts_committed"] = 0
        b.attrs["strobe_committed"] = 0
        b.attrs["REGIMES"] = json.dumps(REGIMES)
        b.create_dataset("order", data=np.asarray(order, dtype=np.int64))

        def per_point(ds_name, dtype, fill, extra=(), group=b):
            shape = (n_points,) + tuple(extra)
            group.create_dataset(ds_name, shape=shape, dtype=dtype, fillvalue=fill,
                                 chunks=(min(n_points, CHUNK),) + tuple(extra),
                                 compression="gzip", shuffle=True)

        per_point("status", np.int8, STATUS_PENDING)
        per_point("message", f"S{MESSAGE_LENGTH}", b"")
        per_point("regime", np.int8, 0)
        per_point("impacts_per_period", np.int16, -1)
        per_point("period_cycles", np.int16, -1)
        per_point("transient_used", np.int32, -1)
        per_point("corner_sequence", f"S{SEQUENCE_LENGTH}", b"")
        for ds_name in ("strobe_mismatch", "zero_one", "max_exponent", "max_exponent_error",
                        "wall_s"):
            per_point(ds_name, np.float64, np.nan)
        for ds_name in ("steps", "rejected", "rhs_evals", "impact_start", "impact_count",
                        "strobe_start", "strobe_count"):
            per_point(ds_name, np.int64, 0)
        per_point("final_state", np.float64, np.nan, (n_state,))
        if n_exponents:
            per_point("exponents", np.float64, np.nan, (n_exponents,))
        imp = b.create_group("impacts")
        for field in IMPACT_FIELDS:
            dtype = np.int8 if field == "corner" else np.float64
            imp.create_dataset(field, shape=(0,), maxshape=(None,), dtype=dtype,
                               chunks=(CHUNK,), compression="gzip", shuffle=True)
        s = b.create_group("strobe")
        s.create_dataset("state", shape=(0, n_state), maxshape=(None, n_state),
                         dtype=np.float64, chunks=(CHUNK // 4, n_state), compression="gzip",
                         shuffle=True)


def _check_same_sweep(f, path, meta, grid, branches) -> None:
    stored = json.loads(_attr(f.attrs["sweep"]))
    wanted = json.loads(meta["sweep"])
    if stored != wanted or _attr(f.attrs["scene"]) != meta["scene"]:
        raise SweepStoreError(
            f"{path}: holds a different sweep or scene; resume needs the same definition "
            "(use --overwrite to start again)")


def _truncate_uncommitted(group) -> None:
    """Drop flat rows written after the last commit (a run killed mid-batch).

    The committed lengths are recomputed from the points marked done or
    failed (their rows are a prefix of the flat arrays, which are appended in
    the branch's order), not taken from the length attributes: a run killed
    between setting the statuses and the attributes leaves them stale.
    """
    status = group["status"][:]
    committed = status != STATUS_PENDING
    for name, fields, key in (("impact", IMPACT_FIELDS, "impacts_committed"),
                              ("strobe", ("state",), "strobe_committed")):
        ends = group[f"{name}_start"][:] + group[f"{name}_count"][:]
        rows = int(ends[committed].max()) if committed.any() else 0
        folder = group["impacts" if name == "impact" else "strobe"]
        for field in fields:
            ds = folder[field]
            if ds.shape[0] != rows:
                ds.resize((rows,) + ds.shape[1:])
        group.attrs[key] = rows
