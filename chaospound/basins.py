"""Basins of attraction: a scan of initial conditions, its attractors, their basins.

A basin scan is a sweep (:func:`chaospound.sweep.run_sweep`) whose one or two
axes are initial conditions instead of parameters: components of the initial
state (``X_A``, ``dX_A``, ... of the scene's model, or a System's
``state_names``) and/or the forcing phase at the start (``initial_phase``, a
fraction of the period). Every grid point is run from its own initial state
for the target's transient and record windows and classified from its record
window, exactly as a sweep point; the points go into the same crash-safe
store (:mod:`chaospound.store`: journal, resume, workers, Dask).

Attractor identification (:func:`identify`) is a pure post-processing of the
stored points, so it is the same whatever the workers or interruptions:

* periodic responses (``periodic``, ``group-periodic``, and non-impacting
  ``none`` with a period) are the same attractor when they have the same
  regime, the same impacts and period n-P, the same corner sequence up to a
  cyclic shift, and the same P section states up to a cyclic shift, to within
  ``tol`` (relative to each state component's largest magnitude over the
  periodic points, max norm). Points are visited in grid order and join the
  nearest attractor within ``tol`` of its first point, or found a new one;
* aperiodic responses (``chaotic``, ``quasi-periodic``, ``unresolved``) of one
  regime are one attractor unless their section clouds are apart: clouds whose
  boxes, widened by ``tol``, overlap are merged;
* failed points (step budget, divergence) are an outcome of their own, label -1.

Attractors are numbered by decreasing basin size (ties: first grid point).

Basin entropy (Daza, Wagemakers, Georgeot, Guery-Odelin and Sanjuan, "Basin
entropy: a new tool to analyze uncertainty in dynamical systems", Sci. Rep.
6, 31416 (2016)): the grid is cut into boxes of ``box`` x ``box`` cells; in
box i the shares p_ij of the outcomes j give the Gibbs entropy
S_i = sum_j p_ij ln(1/p_ij); the basin entropy S_b is the mean of S_i over
all boxes, the boundary basin entropy S_bb the mean over the boxes with
S_i > 0 (those that hold a boundary). S_bb > ln 2 is a sufficient condition
for a fractal boundary.

The identification is stored in the output file as a group ``/basins``
(docs/store.md), written after the sweep is finished by an atomic copy and
rename under the output's lock; :func:`open_basins` reads it (or identifies
again when it is missing, e.g. after a kill between the two steps).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from .grid import Axis, initial_axis
from .store import SweepFile, open_sweep

__all__ = ["ATTRACTOR_TOL", "BOX", "Attractor", "BasinMap", "basin_entropy", "basins",
           "identify", "open_basins"]

ATTRACTOR_TOL = 0.05  #: default relative distance within which two attractors are one
BOX = 5  #: default box side of the basin entropy, in grid cells (Daza et al.: 5)
FAILED, PENDING = -1, -2  #: labels of failed and not yet computed points
PERIODIC = ("periodic", "group-periodic", "none")
GROUP = "basins"  #: the HDF5 group of the identification


@dataclass(frozen=True)
class Attractor:
    """One attractor found by a basin scan.

    Attributes
    ----------
    number : int
        Its label in :attr:`BasinMap.labels` (0 the largest basin).
    regime : str
        ``periodic``, ``group-periodic``, ``none`` (no impacts), ``chaotic``,
        ``quasi-periodic`` or ``unresolved``.
    impacts_per_period, period_cycles : int
        n and P of a periodic attractor (-1 where undefined).
    corner_sequence : str
        Corners of one period, e.g. "A+ A+" ("" without impacts or period).
    sections : ndarray (m, n)
        Section states of its first point: one period (P rows) of a periodic
        attractor, the record window's sections of an aperiodic one.
    count : int
        Grid points in its basin.
    share : float
        ``count`` over the points computed (failed ones included).
    first_point : int
        Grid index (row-major) of the first point of its basin.
    """

    number: int
    regime: str
    impacts_per_period: int
    period_cycles: int
    corner_sequence: str
    sections: np.ndarray
    count: int
    share: float
    first_point: int

    @property
    def label(self) -> str:
        """Short text: "periodic 1-1 (A+)", "none 0-1", "chaotic", ..."""
        if self.period_cycles > 0:
            text = f"{self.regime} {self.impacts_per_period}-{self.period_cycles}"
            return f"{text} ({self.corner_sequence})" if self.corner_sequence else text
        return self.regime


@dataclass
class BasinMap:
    """The basins of a scan: a label per grid point, the attractors, the basin entropy.

    Attributes
    ----------
    path : str
    axes : list of str
        The scanned initial conditions, in axis order.
    grid : dict of str to ndarray
        Their values.
    labels : ndarray of int, shape of the grid
        Attractor number per point; -1 failed, -2 pending.
    attractors : list of Attractor
    entropy, boundary_entropy : float
        S_b and S_bb (natural logarithm; NaN when no box fits the grid).
    boxes, boundary_boxes : int
        Boxes of the entropy, and those with S_i > 0.
    box : int
        Box side in cells.
    tol : float
        Relative identification tolerance.
    failed : int
        Failed points.
    """

    path: str
    axes: list[str]
    grid: dict[str, np.ndarray]
    labels: np.ndarray
    attractors: list[Attractor]
    entropy: float
    boundary_entropy: float
    boxes: int
    boundary_boxes: int
    box: int
    tol: float
    failed: int = 0
    messages: list[str] = field(default_factory=list)

    @property
    def shares(self) -> dict[str, float]:
        """Attractor label (numbered) -> share of the grid, failed points as "failed"."""
        out = {f"#{a.number} {a.label}": a.share for a in self.attractors}
        if self.failed:
            out["failed"] = self.failed / max(1, int(np.sum(self.labels != PENDING)))
        return out

    def format(self) -> str:
        """A few lines: the attractors and their shares, the basin entropy."""
        lines = [f"{len(self.attractors)} attractor(s) on {self.labels.size} initial "
                 f"conditions ({' x '.join(self.axes)}):"]
        for a in self.attractors:
            lines.append(f"  #{a.number} {a.label}: {a.count} points, {100 * a.share:.1f} %")
        if self.failed:
            lines.append(f"  failed: {self.failed} points")
        if self.boxes == 0:
            lines.append(f"basin entropy: none (no whole box of {self.box} cells a side "
                         f"fits the grid of {' x '.join(map(str, self.labels.shape))} cells)")
        else:
            lines.append(f"basin entropy S_b = {self.entropy:.4f}, boundary basin entropy "
                         f"S_bb = {self.boundary_entropy:.4f} ({self.boundary_boxes} of "
                         f"{self.boxes} boxes of {box_text(self.labels.shape, self.box)} on a "
                         "boundary; "
                         f"ln 2 = {math.log(2):.4f})")
        return "\n".join(lines)


# ==================================================================== the driver


def basins(system, axes: Sequence[Axis | str], path, *, workers: int = 1,
           resume: bool = False, overwrite: bool = False, progress: bool = True,
           chunk: int | None = None, client=None, lyapunov: int = 0,
           window_tol: float | None = None, tol: float = ATTRACTOR_TOL, box: int = BOX):
    """Scan initial conditions into a sweep store, identify the attractors, store them.

    Parameters
    ----------
    system : Scene or System
        The scene (its model's states), a System made from one, or any System
        (a user's, or a reference system such as ``duffing()``).
    axes : sequence of Axis or str
        One or two initial-condition axes, ``"X_A=-5:5#101"`` texts or Axes
        made by :func:`chaospound.grid.initial_axis`.
    path : str or Path
        Output file (a sweep store with a ``/basins`` group).
    workers, resume, overwrite, progress, chunk, client :
        As :func:`chaospound.sweep.run_sweep`.
    lyapunov : int
        Exponents per point (names aperiodic points chaotic or quasi-periodic).
    window_tol : float, optional
        Stroboscopic tolerance of the points' classification (default the sweep's).
    tol : float
        Relative distance within which two points' attractors are one.
    box : int
        Box side of the basin entropy, in cells.

    Returns
    -------
    (SweepSummary, BasinMap)

    Raises
    ------
    ValueError
        Bad axes (unknown names: the message lists the valid ones), tolerances
        or box; :class:`chaospound.store.SweepStoreError` for the output.
    chaospound.sweep.SweepInterrupted
        On Ctrl-C; ``resume=True`` finishes the scan.
    """
    from .sweep import WINDOW_TOL, SweepSpec, run_sweep

    _check_options(tol, box)
    parsed = tuple(a if isinstance(a, Axis) else initial_axis(a, system) for a in axes)
    if not 1 <= len(parsed) <= 2:
        raise ValueError(f"{len(parsed)} initial-condition axes: give one or two --grid")
    for a in parsed:
        if a.kind == "parameter":
            raise ValueError(f"{a.name} is a parameter, not an initial condition: fix it "
                             "with --set and scan state components or initial_phase")
    spec = SweepSpec(parsed, lyapunov=lyapunov,
                     window_tol=WINDOW_TOL if window_tol is None else window_tol)
    summary = run_sweep(system, spec, path, workers=workers, resume=resume,
                        overwrite=overwrite, progress=progress, chunk=chunk, client=client)
    result = identify(open_sweep(path), tol=tol, box=box)
    write_basins(path, result)
    return summary, result


def _check_options(tol: float, box: int) -> None:
    if not (isinstance(tol, int | float) and 0.0 < tol < 1.0):
        raise ValueError(f"tol = {tol}: must be in (0, 1)")
    if not (isinstance(box, int) and box >= 1):
        raise ValueError(f"box = {box}: must be an integer >= 1")


# ============================================================== identification


def identify(sweep: SweepFile, *, tol: float = ATTRACTOR_TOL, box: int = BOX) -> BasinMap:
    """Attractors and basins of a basin scan's store (see the module docstring).

    Parameters
    ----------
    sweep : SweepFile
        An opened basin scan (:func:`chaospound.store.open_sweep`).
    tol : float
        Relative identification tolerance.
    box : int
        Box side of the basin entropy, in cells.
    """
    _check_options(tol, box)
    kinds = sweep.sweep.get("axis_kinds")
    if not kinds or "parameter" in kinds:
        raise ValueError(f"{sweep.path}: not a scan of initial conditions (a sweep of "
                         f"{', '.join(sweep.parameters)}); run chaospound basins")
    n = int(np.prod(sweep.shape))
    status = sweep.array("status")
    regimes = sweep.regimes()
    npp = sweep.array("impacts_per_period").astype(int)
    period = sweep.array("period_cycles").astype(int)
    corners = [c.decode("ascii", errors="replace") for c in sweep.array("corner_sequence")]
    periodic_points = [i for i in range(n) if status[i] == 1 and regimes[i] in PERIODIC
                       and period[i] > 0]
    orbits = {i: sweep.strobe(i)[-period[i]:] for i in periodic_points}
    scale = _component_scale([orbits[i] for i in periodic_points]
                             or [sweep.strobe(i) for i in range(n) if status[i] == 1])
    for i in periodic_points:  # a P-cycle within tol of a shorter one is the shorter one
        orbits[i], period[i], npp[i], corners[i] = _reduced(orbits[i], int(npp[i]),
                                                            corners[i], scale, tol)

    labels = np.full(n, PENDING, dtype=np.int64)
    labels[status == 2] = FAILED
    clusters: list[dict] = []  # in order of foundation
    by_key: dict[tuple, list[int]] = {}  # key -> cluster numbers
    for i in range(n):
        if status[i] != 1:
            continue
        if i in orbits:
            key = ("periodic", regimes[i], int(npp[i]), int(period[i]),
                   _canonical_rotation(corners[i].split()))
            best, best_d = None, math.inf
            for c in by_key.get(key, []):
                d = _orbit_distance(orbits[i], clusters[c]["sections"], scale)
                if d < best_d:
                    best, best_d = c, d
            if best is None or best_d > tol:
                best = _new_cluster(clusters, by_key, key, i, regimes[i], npp[i], period[i],
                                    corners[i], orbits[i])
            else:
                clusters[best]["members"].append(i)
        else:
            cloud = sweep.strobe(i)
            low = cloud.min(axis=0) - tol * scale
            high = cloud.max(axis=0) + tol * scale
            key = ("aperiodic", regimes[i])
            hits = [c for c in by_key.get(key, []) if clusters[c]["alive"]
                    and np.all(low <= clusters[c]["high"]) and np.all(clusters[c]["low"] <= high)]
            if not hits:
                c = _new_cluster(clusters, by_key, key, i, regimes[i], -1, -1, "", cloud)
                clusters[c]["low"], clusters[c]["high"] = low, high
                continue
            keep = hits[0]
            clusters[keep]["members"].append(i)
            clusters[keep]["low"] = np.minimum(clusters[keep]["low"], low)
            clusters[keep]["high"] = np.maximum(clusters[keep]["high"], high)
            for c in hits[1:]:  # the new cloud bridges them: one attractor
                clusters[keep]["members"] += clusters[c]["members"]
                clusters[keep]["low"] = np.minimum(clusters[keep]["low"], clusters[c]["low"])
                clusters[keep]["high"] = np.maximum(clusters[keep]["high"],
                                                    clusters[c]["high"])
                clusters[c]["alive"] = False
                clusters[c]["members"] = []
    alive = [c for c in clusters if c["alive"] and c["members"]]
    for c in alive:
        c["first"] = min(c["members"])
    alive.sort(key=lambda c: (-len(c["members"]), c["first"]))
    computed = int(np.sum(status != 0))
    attractors = []
    for number, c in enumerate(alive):
        labels[np.array(c["members"], dtype=np.int64)] = number
        attractors.append(Attractor(
            number=number, regime=c["regime"], impacts_per_period=int(c["npp"]),
            period_cycles=int(c["period"]), corner_sequence=c["corners"],
            sections=np.asarray(c["sections"], dtype=np.float64),
            count=len(c["members"]), share=len(c["members"]) / max(1, computed),
            first_point=int(c["first"])))
    grid_labels = labels.reshape(sweep.shape)
    entropy, boundary, boxes, boundary_boxes = basin_entropy(grid_labels, box)
    return BasinMap(path=str(sweep.path), axes=list(sweep.parameters),
                    grid=dict(sweep.grid), labels=grid_labels, attractors=attractors,
                    entropy=entropy, boundary_entropy=boundary, boxes=boxes,
                    boundary_boxes=boundary_boxes, box=box, tol=tol,
                    failed=int(np.sum(labels == FAILED)))


def _new_cluster(clusters, by_key, key, i, regime, npp, period, corners, sections) -> int:
    clusters.append({"members": [i], "regime": regime, "npp": int(npp), "period": int(period),
                     "corners": corners, "sections": sections, "alive": True})
    by_key.setdefault(key, []).append(len(clusters) - 1)
    return len(clusters) - 1


def _component_scale(arrays: list[np.ndarray]) -> np.ndarray:
    """Largest magnitude of each state component over ``arrays`` (floored at 1e-6 of
    the largest, so that a component that is zero on every attractor adds no noise)."""
    if not arrays:
        return np.ones(1)
    stacked = np.abs(np.concatenate([np.atleast_2d(a) for a in arrays]))
    scale = np.nanmax(stacked, axis=0) if stacked.size else np.ones(stacked.shape[1])
    top = float(np.nanmax(scale)) if scale.size and np.isfinite(scale).any() else 1.0
    top = top if top > 0.0 else 1.0
    return np.maximum(np.nan_to_num(scale, nan=top), 1e-6 * top)


def _orbit_distance(a: np.ndarray, b: np.ndarray, scale: np.ndarray) -> float:
    """Max-norm distance of two P-cycles of section states, scaled per component,
    minimised over cyclic shifts (a period-P orbit has P equivalent starts)."""
    if a.shape != b.shape:
        return math.inf
    return min(float(np.max(np.abs(a - np.roll(b, s, axis=0)) / scale))
               for s in range(a.shape[0]))


def _reduced(orbit: np.ndarray, n: int, corners: str, scale: np.ndarray,
             tol: float) -> tuple[np.ndarray, int, int, str]:
    """The shortest period d dividing P whose orbit repeats within ``tol`` (and whose
    corner sequence repeats with it): a window classification may name a slowly
    converging period-1 response "0-4" (its transient beats); returns the last d
    sections, d, the impacts per d cycles and their corners."""
    period = orbit.shape[0]
    labels = corners.split()
    for d in range(1, period):
        if period % d or n * d % period:
            continue
        m = n * d // period
        if labels[:m] * (period // d) != labels:
            continue
        if float(np.max(np.abs(orbit - np.roll(orbit, d, axis=0)) / scale)) <= tol:
            return orbit[-d:], d, m, " ".join(labels[:m])
    return orbit, period, n, corners


def _canonical_rotation(items: list[str]) -> tuple[str, ...]:
    """The lexicographically least cyclic rotation: corner sequences equal up to shift."""
    if not items:
        return ()
    return min(tuple(items[k:] + items[:k]) for k in range(len(items)))


# ============================================================== basin entropy


def box_sides(shape: tuple[int, ...], box: int = BOX) -> tuple[int, int]:
    """The cells a side of the basin entropy's boxes on a grid of ``shape``: runs of
    ``box`` cells on a one-axis grid, ``box`` x ``box`` on a two-axis grid, each side
    clipped to the grid's (a 100 x 3 grid has boxes of 5 x 3 cells)."""
    if len(shape) == 1:
        return 1, box
    return min(box, shape[0]), min(box, shape[1])


def box_text(shape: tuple[int, ...], box: int = BOX) -> str:
    """The boxes of :func:`box_sides` in words: "5 cells", "5 x 5 cells", "5 x 3 cells"."""
    rows, cols = box_sides(shape, box)
    return f"{cols} cells" if len(shape) == 1 else f"{rows} x {cols} cells"


def basin_entropy(labels: np.ndarray, box: int = BOX) -> tuple[float, float, int, int]:
    """Basin entropy S_b and boundary basin entropy S_bb of a label grid (Daza et al. 2016).

    Parameters
    ----------
    labels : ndarray of int (1-D or 2-D)
        Outcome per cell (attractor number, -1 failed: an outcome too); pending
        cells (-2) are left out of their box.
    box : int
        Box side in cells; the boxes tile the grid from its first cell, the
        cells beyond the last whole box are left out.

    Returns
    -------
    (S_b, S_bb, boxes, boundary boxes)
        Natural logarithms; NaN when no whole box fits.
    """
    labels = np.asarray(labels)
    sides = box_sides(labels.shape, box)
    if labels.ndim == 1:
        labels = labels[None, :]
    rows, cols = labels.shape[0] // sides[0], labels.shape[1] // sides[1]
    entropies = []
    for r in range(rows):
        for c in range(cols):
            cell = labels[r * sides[0]:(r + 1) * sides[0], c * sides[1]:(c + 1) * sides[1]]
            cell = cell[cell != PENDING]
            if cell.size == 0:
                continue
            _, counts = np.unique(cell, return_counts=True)
            p = counts / cell.size
            entropies.append(float(-np.sum(p * np.log(p))) + 0.0)
    if not entropies:
        return math.nan, math.nan, 0, 0
    values = np.array(entropies)
    boundary = values[values > 0.0]
    return (float(values.mean()), float(boundary.mean()) if boundary.size else 0.0,
            int(values.size), int(boundary.size))


# ================================================================ the /basins group


def write_basins(path, result: BasinMap) -> None:
    """Store an identification as the group ``/basins`` of a finished basin scan.

    Written to a copy that is fsynced and renamed onto the file, under the
    output's lock, so a kill leaves either the old file or the new one.
    """
    from .journal import fsync_dir
    from .lock import OutputBusy, OutputLock
    from .store import StoreWriteError, SweepStoreError

    path = Path(path)
    try:
        lock = OutputLock(path)
    except OutputBusy as exc:
        raise SweepStoreError(str(exc)) from None
    tmp = path.with_name(f"{path.name}.tmp-{os.getpid()}")
    try:
        shutil.copyfile(path, tmp)
        with h5py.File(tmp, "a") as f:
            if GROUP in f:
                del f[GROUP]
            _write_group(f.create_group(GROUP), result)
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, path)
        fsync_dir(path.parent)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise StoreWriteError(f"{path}: cannot store the basins ({exc}); the scan is "
                              "safe: run again with --resume") from None
    finally:
        lock.release()


def _write_group(g: h5py.Group, result: BasinMap) -> None:
    attractors = result.attractors
    g.attrs["tol"] = result.tol
    g.attrs["box"] = result.box
    g.attrs["entropy"] = result.entropy
    g.attrs["boundary_entropy"] = result.boundary_entropy
    g.attrs["boxes"] = result.boxes
    g.attrs["boundary_boxes"] = result.boundary_boxes
    g.attrs["failed"] = result.failed
    g.attrs["reference"] = ("Daza et al., Sci. Rep. 6, 31416 (2016): S_b mean over boxes, "
                            "S_bb mean over boundary boxes, natural log")
    g.create_dataset("label", data=result.labels.ravel().astype(np.int32))
    a = g.create_group("attractors")
    a.create_dataset("regime", data=np.array([x.regime for x in attractors], dtype="S16"))
    a.create_dataset("label", data=np.array([x.label.encode() for x in attractors],
                                            dtype=f"S{_width([x.label for x in attractors])}"))
    a.create_dataset("impacts_per_period", data=np.array(
        [x.impacts_per_period for x in attractors], dtype=np.int16))
    a.create_dataset("period_cycles", data=np.array([x.period_cycles for x in attractors],
                                                    dtype=np.int16))
    a.create_dataset("corner_sequence", data=np.array(
        [x.corner_sequence.encode() for x in attractors],
        dtype=f"S{_width([x.corner_sequence for x in attractors])}"))
    a.create_dataset("count", data=np.array([x.count for x in attractors], dtype=np.int64))
    a.create_dataset("share", data=np.array([x.share for x in attractors], dtype=np.float64))
    a.create_dataset("first_point", data=np.array([x.first_point for x in attractors],
                                                  dtype=np.int64))
    counts = np.array([x.sections.shape[0] for x in attractors], dtype=np.int64)
    a.create_dataset("section_count", data=counts)
    a.create_dataset("section_start", data=np.concatenate(([0], np.cumsum(counts)[:-1]))
                     .astype(np.int64) if counts.size else counts)
    width = attractors[0].sections.shape[1] if attractors else 0
    a.create_dataset("sections", data=np.concatenate([x.sections for x in attractors])
                     if attractors else np.zeros((0, width)))


def _width(texts: list[str]) -> int:
    return max([1, *(len(t.encode()) for t in texts)])


def open_basins(path, *, tol: float | None = None, box: int | None = None) -> BasinMap:
    """The basins of a basin scan's file: its ``/basins`` group, or a fresh
    identification when the group is missing (or another ``tol``/``box`` is asked).

    A running or interrupted scan (its journal exists) is identified from the
    points done so far (the others are labelled -2, pending).
    """
    sweep = open_sweep(path)
    stored = None if sweep.live else _read_group(Path(path), sweep)
    if stored is not None and (tol is None or tol == stored.tol) and (
            box is None or box == stored.box):
        return stored
    return identify(sweep, tol=ATTRACTOR_TOL if tol is None else tol,
                    box=BOX if box is None else box)


def _read_group(path: Path, sweep: SweepFile) -> BasinMap | None:
    with h5py.File(path, "r", locking=False) as f:
        if GROUP not in f:
            return None
        g = f[GROUP]
        a = g["attractors"]
        sections = a["sections"][()]
        starts, counts = a["section_start"][()], a["section_count"][()]
        attractors = [
            Attractor(number=k, regime=a["regime"][k].decode(),
                      impacts_per_period=int(a["impacts_per_period"][k]),
                      period_cycles=int(a["period_cycles"][k]),
                      corner_sequence=a["corner_sequence"][k].decode(),
                      sections=sections[starts[k]:starts[k] + counts[k]],
                      count=int(a["count"][k]), share=float(a["share"][k]),
                      first_point=int(a["first_point"][k]))
            for k in range(a["regime"].shape[0])]
        return BasinMap(path=str(path), axes=list(sweep.parameters), grid=dict(sweep.grid),
                        labels=g["label"][()].astype(np.int64).reshape(sweep.shape),
                        attractors=attractors, entropy=float(g.attrs["entropy"]),
                        boundary_entropy=float(g.attrs["boundary_entropy"]),
                        boxes=int(g.attrs["boxes"]), boundary_boxes=int(g.attrs["boundary_boxes"]),
                        box=int(g.attrs["box"]), tol=float(g.attrs["tol"]),
                        failed=int(g.attrs["failed"]))


def describe(result: BasinMap) -> str:
    """JSON of the identification (attractors, shares, entropy) for reports."""
    return json.dumps({
        "axes": result.axes,
        "attractors": [{"number": a.number, "label": a.label, "count": a.count,
                        "share": a.share} for a in result.attractors],
        "failed": result.failed,
        "entropy": result.entropy,
        "boundary_entropy": result.boundary_entropy,
        "box": result.box,
    })
