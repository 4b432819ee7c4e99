"""Batch bifurcation scans over one or two parameters of a scene or a System, in HDF5.

A sweep is a grid over one or two parameters of a scene (``period_ratio``,
``gap``, ``ecc_y_A``, ``beta``, ...), or over the named parameters of a user's
own system (:func:`chaospound.custom_system` with ``params={"zeta": ...}``).
Every grid point is run to steady state (the scene's or system's transient and
record windows), its impacts, stroboscopic points and regime are stored,
optionally with Lyapunov exponents.

Branches and chains
    Without continuation every point starts from the scene's initial state
    (the paper's fresh start from rest): branch "fresh", one chain per point.
    With continuation each point starts from the previous point's last
    stroboscopic state (at the section, so the forcing phase is exact):
    branch "forward" visits the last axis upwards, "backward" downwards, "both"
    stores the two branches side by side (hysteresis, coexisting attractors).
    In 2-D, every row along the last axis is one chain.

Determinism
    A point's result depends only on its parameters and its starting state,
    never on the worker that ran it; results are committed to the sweep's
    journal as they arrive, each keyed by its grid index, and the file is
    written from the journal in the branch's visiting order, so files from 1
    or N workers, or from an interrupted and resumed run, are identical apart
    from the timing fields. (What an interrupted fresh branch holds need not
    be its first points; a continuation chain's are always its first.)

Interruption
    Finished points are committed to the file in batches (every
    ``COMMIT_INTERVAL`` seconds or ``COMMIT_POINTS`` points). A kill loses
    the points since the last commit; Ctrl-C commits the finished ones and
    raises :class:`SweepInterrupted`; ``resume=True`` computes the rest.
"""

from __future__ import annotations

import contextlib
import json
import math
import multiprocessing as mp
import os
import signal
import threading
import time
from collections import deque
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field

import numpy as np

from . import __version__
from .dynamics.system import System
from .grid import (  # noqa: F401 - re-exported: the grid parsing lives in chaospound.grid
    MAX_POINTS,
    Axis,
    axes_from_scene,
    make_axis,
    parse_axes,
    parse_axis,
)
from .point import run_point, run_task  # noqa: F401 - run_point re-exported
from .scene import Scene
from .store import PointResult, SweepWriter

__all__ = [
    "Axis",
    "SweepInterrupted",
    "SweepSpec",
    "SweepSummary",
    "parse_axis",
    "run_sweep",
]

CONTINUATIONS = ("none", "forward", "backward", "both")
CLASSIFY_MODES = ("converged", "paper", "window", "full")
WINDOW_TOL = 1e-2  #: default stroboscopic tolerance of the window classification
#: finished points are committed to the file at most this often (seconds) ...
COMMIT_INTERVAL = 1.0
#: ... or when this many wait: few HDF5 flushes (cheap, and a reader of the running
#: sweep's file rarely meets a write in progress), bounded memory, and a kill loses
#: at most about a second of work
COMMIT_POINTS = 256
POLL_S = 0.2  #: the longest wait for worker processes before looking at Ctrl-C
MANAGER_JOIN_S = 5.0  #: the longest wait for a broken pool's manager thread after an abort


class SweepInterrupted(Exception):
    """Raised after a Ctrl-C: the file is closed and valid, ``--resume`` finishes it."""

    def __init__(self, done: int, total: int, path: str) -> None:
        super().__init__(f"interrupted after {done} of {total} points; "
                         f"finish with: chaospound sweep ... -o {path} --resume")
        self.done = done
        self.total = total


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep and how.

    Attributes
    ----------
    axes : tuple of Axis
        One or two axes; the last one is the continuation direction.
    continuation : {"none", "forward", "backward", "both"}
    lyapunov : int
        Exponents per point: 0 none, -1 the full spectrum, k the k largest.
    lyapunov_cycles : int
        Periods averaged for the exponents (after 10 periods of alignment).
    classify : {"converged", "paper", "window", "full"}
        "converged" (default): :func:`chaospound.dynamics.converged.classify_converged`
        per point, from the scene's initial state (on a continuation branch
        from the previous point's attractor), periods
        confirmed by Newton's method and their Floquet multipliers, exponents
        only until the 3-sigma decision is clear. "paper" (alias "window"): the
        regime from the point's own record window (the scene's
        transient and record cycles, e.g. the paper's 40 + 8), with the
        stroboscopic tolerance ``window_tol``: what such a window can resolve
        (docs/model.md 11: 1-2 % of the transient is left after 40 cycles). Aperiodic
        points are chaotic or quasi-periodic only with exponents (``lyapunov``),
        else "unresolved". "full": the adaptive classifier
        (:func:`chaospound.dynamics.classify.classify`) per point: its own
        converged transient, tolerance 1e-5 and largest exponent; slower.
    window_tol : float
        Relative stroboscopic mismatch accepted as periodic in "window" mode.
    """

    axes: tuple[Axis, ...]
    continuation: str = "none"
    lyapunov: int = 0
    lyapunov_cycles: int = 100
    classify: str = "converged"
    window_tol: float = WINDOW_TOL

    def __post_init__(self) -> None:
        if not 1 <= len(self.axes) <= 2:
            raise ValueError(f"{len(self.axes)} swept parameters: give one or two --param")
        names = [a.name for a in self.axes]
        if len(set(names)) != len(names):
            raise ValueError(f"parameter {names[0]!r} swept twice")
        if self.continuation not in CONTINUATIONS:
            raise ValueError(f"continuation = {self.continuation!r}: must be one of "
                             f"{', '.join(CONTINUATIONS)}")
        if self.lyapunov_cycles < 10:
            raise ValueError(f"lyapunov_cycles = {self.lyapunov_cycles}: must be >= 10")
        if self.classify not in CLASSIFY_MODES:
            raise ValueError(f"classify = {self.classify!r}: must be one of "
                             f"{', '.join(CLASSIFY_MODES)}")
        if self.classify == "paper":  # one name in files and resume checks
            object.__setattr__(self, "classify", "window")
        if not 0.0 < self.window_tol < 1.0:
            raise ValueError(f"window_tol = {self.window_tol}: must be in (0, 1)")
        if self.initial_axes:  # a basin scan: every point starts from its own state
            if self.continuation != "none":
                raise ValueError("a scan of initial conditions has no continuation: each "
                                 "point starts from its own initial state")
            if self.classify == "converged":  # the default: a basin point is its own run
                object.__setattr__(self, "classify", "window")
            if self.classify != "window":
                raise ValueError(f"classify = {self.classify!r}: a scan of initial "
                                 "conditions classifies its points' own runs (\"window\")")

    @property
    def initial_axes(self) -> tuple[Axis, ...]:
        """The axes of initial conditions (state components, initial phase): basins."""
        return tuple(a for a in self.axes if getattr(a, "kind", "parameter") != "parameter")

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a) for a in self.axes)

    @property
    def n_points(self) -> int:
        return int(np.prod(self.shape))

    @property
    def branches(self) -> tuple[str, ...]:
        if self.continuation == "none":
            return ("fresh",)
        if self.continuation == "both":
            return ("forward", "backward")
        return (self.continuation,)

    def to_json(self) -> str:
        definition = {
            "parameters": [a.name for a in self.axes],
            "specs": [a.spec for a in self.axes],
            "values": [a.values.tolist() for a in self.axes],
            "continuation": self.continuation,
            "branches": list(self.branches),
            "lyapunov": self.lyapunov,
            "lyapunov_cycles": self.lyapunov_cycles,
            "classify": self.classify,
            "window_tol": self.window_tol,
        }
        if self.initial_axes:  # only basin scans carry it: parameter sweeps' text unchanged
            definition["axis_kinds"] = [getattr(a, "kind", "parameter") for a in self.axes]
        return json.dumps(definition)

    def point_values(self, index: int) -> dict[str, float]:
        """Parameter values of grid point ``index`` (row-major); initial-condition axes
        are in :meth:`initial_values`."""
        coords = np.unravel_index(index, self.shape)
        return {a.name: float(a.values[c]) for a, c in zip(self.axes, coords, strict=True)
                if getattr(a, "kind", "parameter") == "parameter"}

    def initial_values(self, index: int) -> dict[str, float]:
        """Values of the initial-condition axes (state components, initial phase) of grid
        point ``index``; empty for a parameter sweep."""
        if not self.initial_axes:
            return {}
        coords = np.unravel_index(index, self.shape)
        return {a.name: float(a.values[c]) for a, c in zip(self.axes, coords, strict=True)
                if getattr(a, "kind", "parameter") != "parameter"}

    def order(self, branch: str) -> np.ndarray:
        """Grid indices in the branch's visiting order: its chains, concatenated."""
        index = np.arange(self.n_points, dtype=np.int64)
        if branch == "backward":
            index = index.reshape(-1, self.shape[-1])[:, ::-1].ravel()
        return index

    def chains(self, branch: str) -> list[list[int]]:
        """Chains of grid indices in visiting order; points of a chain run in sequence."""
        n = self.n_points
        if branch == "fresh":
            return [[i] for i in range(n)]
        inner = self.shape[-1]
        rows = [list(range(r * inner, (r + 1) * inner)) for r in range(n // inner)]
        if branch == "backward":
            rows = [row[::-1] for row in rows]
        return rows


@dataclass
class SweepSummary:
    """What a sweep did: points computed in this run; regimes and failures of every
    point stored in the file (a resumed sweep counts the earlier runs' points too)."""

    path: str
    points: int
    computed: int
    regimes: dict[str, int]
    failed: int
    wall_s: float
    workers: int
    messages: list[str] = field(default_factory=list)
    stored: int = 0  #: points in the file, from this and earlier runs
    finished_before: bool = False  #: resume found the file finished
    notes: list[str] = field(default_factory=list)  #: said once, e.g. regimes not classified

    @property
    def all_failed(self) -> bool:
        """Every point stored failed (a step budget or tolerance no point could meet)."""
        return self.failed > 0 and self.failed >= self.stored

    @property
    def points_per_second(self) -> float:
        return self.computed / self.wall_s if self.wall_s > 0 else float("nan")

    def format(self) -> str:
        counts = ", ".join(f"{k} {v}" for k, v in sorted(self.regimes.items())
                           if v and k != "failed")
        if self.finished_before:
            return (f"{self.path}: finished already: all {self.points} points are stored, "
                    f"nothing to resume\nregimes: {counts or 'no point classified'}; "
                    f"failed: {self.failed}")
        lines = [
            f"{self.path}: {self.computed} points computed ({self.points} in the grid) "
            f"in {self.wall_s:.2f} s with {self.workers} worker(s), "
            f"{self.points_per_second:.1f} points/s"
            + ("" if self.stored == self.computed else f"; {self.stored} stored in all"),
            f"regimes: {counts or 'no point classified'}; failed: {self.failed}",
        ]
        lines += [f"  failed: {m}" for m in self.messages[:5]]
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)


# ----------------------------------------------------------------- the driver


def run_sweep(
    system: Scene | System,
    spec: SweepSpec,
    path,
    *,
    workers: int = 1,
    resume: bool = False,
    overwrite: bool = False,
    progress: bool = True,
    chunk: int | None = None,
    client=None,
) -> SweepSummary:
    """Run a sweep into an HDF5 store (see :mod:`chaospound.store` for the schema).

    Parameters
    ----------
    system : Scene or System
        The base scene, or a System: a user's own (:func:`chaospound.custom_system`),
        swept over its named parameters (``System.with_params``), or one made
        from a scene (its scene is swept, with the system's solver settings).
        Each point overrides the swept parameters.
    spec : SweepSpec
        Axes, continuation and Lyapunov settings.
    path : str or Path
        Output file; refused if it exists unless ``resume`` or ``overwrite``.
    workers : int
        Local worker processes (ignored with a Dask ``client``).
    resume : bool
        Finish an interrupted file of the same sweep, keeping its points.
    overwrite : bool
        Replace an existing file.
    progress : bool
        Show a progress bar (tqdm, on stderr).
    chunk : int, optional
        Points per task (default: sized from the number of points and workers).
    client : distributed.Client, optional
        Run the tasks on a Dask cluster (see :mod:`chaospound.distributed`).

    Returns
    -------
    SweepSummary

    Raises
    ------
    SweepInterrupted
        On Ctrl-C, after closing the file cleanly.
    """
    if workers < 1:
        raise ValueError(f"workers = {workers}: must be >= 1")
    scene = sweep_target(system, spec)
    notes: list[str] = []
    if isinstance(scene, Scene):
        model_id = scene.model_id()
        n_state = len(scene.initial_vector(model_id))
        model_name = scene.model_name
        from .scene import STATE_NAMES

        meta = {
            "chaospound_version": __version__,
            "scene": scene.to_toml(),
            "scene_resolved": json.dumps(scene.to_dict()),
            "sweep": spec.to_json(),
            "model": scene.model_name,
            "state_names": json.dumps(list(STATE_NAMES[model_id])),
        }
    else:
        n_state, model_name = scene.dim, "custom"
        meta = system_metadata(scene, spec)
        if not scene.has_gap:
            notes.append(f"system {scene.name!r} has no gap function: its points cannot be "
                         "classified (stored 'unresolved'); their sections, impacts and "
                         "statistics are stored")
    n_exponents = 0 if spec.lyapunov == 0 else (n_state if spec.lyapunov < 0 else spec.lyapunov)
    if n_exponents > n_state:
        raise ValueError(f"--lyapunov {spec.lyapunov}: the {model_name} model has only "
                         f"{n_state} exponents")
    grid = {a.name: a.values for a in spec.axes}
    orders = {b: spec.order(b) for b in spec.branches}
    if chunk is None and client is not None:  # sized from the cluster's threads
        from .distributed import default_chunk

        chunk = default_chunk(client, spec.n_points)
    if chunk is None:
        per_worker = max(1, spec.n_points // (max(workers, 1) * 8))
        chunk = int(min(32, per_worker))
    chunk = max(1, int(chunk))

    started = time.perf_counter()
    backend = _make_backend(client, workers, scene, spec)
    try:
        writer = SweepWriter(path, meta, grid, orders, n_state, n_exponents, resume=resume,
                             overwrite=overwrite)
    except BaseException:
        backend.close()
        raise
    try:
        if writer.finished:
            summary = SweepSummary(path=str(path), points=spec.n_points * len(spec.branches),
                                   computed=0, regimes={}, failed=0, wall_s=0.0, workers=0,
                                   finished_before=True)
        else:
            plan = _Plan(spec, orders, writer, chunk)
            summary = _execute(plan, backend, writer, progress, str(path))
        summary.regimes = writer.regime_counts()  # from the journal, before it goes
        writer.finish()
        summary.stored = sum(summary.regimes.values())
        summary.failed = summary.regimes.pop("failed", 0)
    finally:
        writer.close()
        backend.close()
    summary.wall_s = time.perf_counter() - started
    summary.workers = backend.workers
    summary.notes = notes
    return summary


def sweep_target(system: Scene | System, spec: SweepSpec | None = None) -> Scene | System:
    """What the workers run: a Scene, or a user's System.

    A System made from a scene is its scene with the system's solver and run
    settings (those that differ), so that it is stored and resumed as a scene.
    A reference system without named parameters (e.g. ``duffing()``) is run as
    it is when every axis of ``spec`` is an initial condition (a basin scan).
    """
    if isinstance(system, Scene):
        return system
    if not isinstance(system, System):
        raise TypeError(f"run_sweep needs a Scene or a System, got {type(system).__name__}")
    if system.scene is None:
        basins_only = spec is not None and len(spec.initial_axes) == len(spec.axes)
        if not system.is_custom and not basins_only:
            raise ValueError(f"system {system.name!r} has no named parameters to sweep: use a "
                             "scene or a custom_system with params={...}")
        return system
    flat = system.scene.to_dict()
    changed = {k: getattr(system, k) for k in ("method", "rtol", "atol", "steps_per_cycle",
                                                "max_steps", "restart_at_kinks", "transient",
                                                "record")
               if getattr(system, k) != flat[k]}
    return system.scene.with_params(**changed) if changed else system.scene


def system_identity(system: System) -> dict:
    """What identifies a user's System in a sweep store (the resume check compares it)."""
    user = system.user
    source = system.origin
    if not source and user is not None:
        source = f"{user.module or '__main__'}:{user.names[0]}"
    return {
        "model": "custom",
        "name": system.name,
        "source": source,
        "source_sha256": system.source_digest(),
        "functions": list(user.names) if user is not None else [],
        "has_gap": system.has_gap,
        "state_names": list(system.state_names),
        "initial_state": [float(v) for v in system.initial_state],
        "parameter_names": list(system.parameter_names),
        "parameter_values": system.parameter_values,
        "period": system.period,
        "transient": system.transient,
        "record": system.record,
        "method": system.method,
        "rtol": system.rtol,
        "atol": system.atol,
        "steps_per_cycle": system.steps_per_cycle,
        "max_steps": system.max_steps,
        "restart_at_kinks": system.restart_at_kinks,
        # a reference system (duffing, lorenz: basin scans) is its model and packed vector
        **({} if system.is_custom else {"model": system.model_name,
                                         "packed_params": system.params.tolist()}),
    }


def system_metadata(system: System, spec: SweepSpec) -> dict:
    """Root attributes of a sweep of a user's System (docs/store.md)."""
    identity = system_identity(system)
    return {
        "chaospound_version": __version__,
        "system": json.dumps(identity),
        "sweep": spec.to_json(),
        "model": identity["model"],
        "name": system.name,
        "state_names": json.dumps(list(system.state_names)),
        "parameter_names": json.dumps(identity["parameter_names"]),
        "parameter_values": json.dumps(identity["parameter_values"]),
        "source": identity["source"],
        "source_sha256": identity["source_sha256"],
        "classified": "yes" if system.has_gap else "no (no gap function)",
    }


# ---------------------------------------------------------------- scheduling


@dataclass
class _Task:
    branch: str
    key: tuple[int, int]  # (chain, segment)
    indices: np.ndarray  # grid indices, in visiting order
    start_state: np.ndarray | None
    continuation: bool
    last_of_chain: bool


class _Plan:
    """Which points remain, and their tasks.

    Bookkeeping is a few bytes per point (index arrays): the tasks of the
    "fresh" branch are cut lazily, continuation chains are rows of the
    branch's visiting order.
    """

    def __init__(self, spec: SweepSpec, orders: dict[str, np.ndarray], writer: SweepWriter,
                 chunk: int) -> None:
        self.spec = spec
        self.chunk = chunk
        self.branches: list[str] = list(orders)
        self._fresh_tasks = 0
        self.remaining: dict[tuple[str, int], np.ndarray] = {}
        self.total = 0
        self._chain_starts: list[_Task] = []
        self._fresh_todo = np.zeros(0, dtype=np.int64)
        for branch, order in orders.items():
            pending = writer.pending(branch)
            if branch == "fresh":
                self._fresh_todo = order[pending[order]]
                self._fresh_tasks = math.ceil(self._fresh_todo.size / chunk)
                self.total += int(self._fresh_todo.size)
                continue
            for c, chain in enumerate(order.reshape(-1, spec.shape[-1])):
                waiting = pending[chain]
                if not waiting.any():
                    continue
                first = int(np.flatnonzero(waiting)[0])
                todo = chain[first:]
                state = writer.final_state(branch, int(chain[first - 1])) if first > 0 else None
                self.remaining[(branch, c)] = todo
                self.total += int(todo.size)
                self._chain_starts.append(self._segment(branch, c, 0, state))

    def tasks(self) -> Iterator[_Task]:
        """The first task of every chain, then the fresh points' tasks, cut as needed."""
        yield from self._chain_starts
        todo, chunk = self._fresh_todo, self.chunk
        for k in range(self._fresh_tasks):
            yield _Task("fresh", (k, 0), todo[k * chunk:(k + 1) * chunk], None, False, True)

    def _segment(self, branch, chain, seg, state) -> _Task:
        todo = self.remaining[(branch, chain)]
        part = todo[seg * self.chunk:(seg + 1) * self.chunk]
        last = (seg + 1) * self.chunk >= len(todo)
        return _Task(branch, (chain, seg), part, state, True, last)

    def follow_up(self, task: _Task, results: list[PointResult]) -> _Task | None:
        """The next segment of a continuation chain, started from the last state."""
        if not task.continuation or task.last_of_chain:
            return None
        last = results[-1]
        state = last.final_state if last.status == 1 else None
        return self._segment(task.branch, task.key[0], task.key[1] + 1, state)


def _execute(plan: _Plan, backend, writer: SweepWriter, progress: bool, path: str):
    from .store import REGIMES

    regimes = dict.fromkeys(REGIMES[1:], 0)
    messages: list[str] = []
    failed = 0
    done = 0
    # finished points wait here for the next commit, in the order they arrive: the store
    # keys every point by its grid index (so the file does not depend on that order),
    # and a continuation chain's segments arrive in the chain's order, so what is
    # committed of a chain is always its first points (what --resume continues from)
    staged: dict[str, list[PointResult]] = {b: [] for b in plan.branches}
    committed = 0
    last_commit = time.monotonic()
    writing = False

    def commit() -> None:
        # a Ctrl-C during a write is held until the write is done: the journal's
        # transaction is atomic anyway, but the count of committed points stays exact
        nonlocal committed, last_commit, writing
        writing = True
        with ctrl_c.held():
            for branch in staged:
                batch, staged[branch] = staged[branch], []
                writer.write(branch, batch)
                committed += len(batch)
        writing = False
        last_commit = time.monotonic()

    # with worker processes the main thread only waits (in short slices): a Ctrl-C just
    # sets a flag, so it never lands inside the pool's finalizers; else it raises at once
    ctrl_c = _CtrlC(raise_at_once=not getattr(backend, "polls", False))
    bar = _progress_bar(plan.total, progress)
    follow_ups: deque[_Task] = deque()  # next segments of running chains go first
    new_tasks = plan.tasks()
    in_flight = {}
    try:
        ctrl_c.install()
        while True:
            ctrl_c.check()
            limit = 2 * backend.workers + 2  # a cluster may grow or shrink
            while len(in_flight) < limit:
                task = follow_ups.popleft() if follow_ups else next(new_tasks, None)
                if task is None:
                    break
                in_flight[backend.submit(task)] = task
            if not in_flight:
                break
            finished = backend.wait_some(list(in_flight))
            for fut in finished:
                task = in_flight.pop(fut)
                results = backend.result(fut)
                nxt = plan.follow_up(task, results)
                if nxt is not None:
                    follow_ups.appendleft(nxt)
                staged[task.branch] += results
                ctrl_c.check()
                for r in results:
                    regimes[r.regime] = regimes.get(r.regime, 0) + 1
                    if r.status == 2:
                        failed += 1
                        if len(messages) < 20:
                            messages.append(f"point {r.index}: {r.message}")
                done += len(results)
                if bar is not None:
                    bar.update(len(results))
                    bar.set_postfix_str(_postfix(regimes, failed), refresh=False)
            if (time.monotonic() - last_commit >= COMMIT_INTERVAL
                    or sum(map(len, staged.values())) >= COMMIT_POINTS):
                commit()
        commit()
    except KeyboardInterrupt:
        backend.abort()
        if not writing:  # keep the finished points; inside a write, resume repairs the file
            with contextlib.suppress(KeyboardInterrupt):
                commit()
        if bar is not None:
            bar.close()
        raise SweepInterrupted(committed, plan.total, path) from None
    except Exception:
        # e.g. the Dask cluster went away: keep every finished point, then report
        backend.abort()
        if not writing:
            with contextlib.suppress(Exception):
                commit()
        if bar is not None:
            bar.close()
        raise
    finally:
        ctrl_c.uninstall()
    if bar is not None:
        bar.close()
    return SweepSummary(path=path, points=plan.spec.n_points * len(plan.spec.branches),
                        computed=done, regimes={}, failed=0, wall_s=0.0, workers=0,
                        messages=messages)  # regimes and failures: of the store, by run_sweep


class _CtrlC:
    """SIGINT handler that remembers a Ctrl-C, and raises KeyboardInterrupt at once or not.

    Python drops an exception raised while a finalizer or weakref callback runs
    (printing "Exception ignored in ..."), so a Ctrl-C landing there would be lost;
    the sweep loop calls :meth:`check` to raise it (again).
    """

    def __init__(self, raise_at_once: bool = True) -> None:
        self.pressed = False
        self.raise_at_once = raise_at_once
        self._previous = None

    def install(self) -> None:
        if threading.current_thread() is not threading.main_thread():
            return
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            self._previous = signal.signal(signal.SIGINT, self._handle)

    def uninstall(self) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None

    def check(self) -> None:
        if self.pressed:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def held(self):
        """Remember a Ctrl-C inside the block; raise it at the end."""
        raise_at_once, self.raise_at_once = self.raise_at_once, False
        try:
            yield
        finally:
            self.raise_at_once = raise_at_once
        self.check()

    def _handle(self, signum, frame) -> None:
        self.pressed = True
        if self.raise_at_once:
            raise KeyboardInterrupt


def _postfix(regimes: dict, failed: int) -> str:
    short = {"periodic": "per", "group-periodic": "grp", "chaotic": "cha",
             "quasi-periodic": "qp", "none": "none", "unresolved": "?"}
    parts = [f"{short[k]} {v}" for k, v in regimes.items() if v and k in short]
    if failed:
        parts.append(f"failed {failed}")
    return " ".join(parts)


def _progress_bar(total: int, enabled: bool):
    if not enabled or total == 0:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="pt", desc="sweep", dynamic_ncols=True, smoothing=0.05)


# ------------------------------------------------------------------ backends


class _LocalBackend:
    """Worker processes on this machine (or in-process for one worker)."""

    def __init__(self, workers: int, scene: Scene, spec: SweepSpec) -> None:
        self.workers = workers
        self._scene = scene
        self._spec = spec
        self._pool = None
        # one worker computes in this process: its small matrices (Newton, Floquet, the
        # 0-1 test's principal direction) run faster without BLAS threads spinning
        # beside it (fig4's scan: docs/classification.md); restored by close/abort
        self._blas = set_blas_threads(1) if workers == 1 else []
        if workers > 1:
            ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
            self._pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                                             initializer=_init_worker,
                                             initargs=(scene, spec, os.getpid()))
            # start the workers now, before the store's files are opened (a forked worker
            # then holds none of them) and while only the main thread runs
            for fut in [self._pool.submit(os.getpid) for _ in range(workers)]:
                fut.result()

    def submit(self, task: _Task):
        if self._pool is None:
            return _Immediate(run_task(self._scene, self._spec, task.indices, task.start_state,
                                       task.continuation))
        return self._pool.submit(_run_in_worker, task.indices, task.start_state,
                                 task.continuation)

    @property
    def polls(self) -> bool:
        """True with worker processes: :meth:`wait_some` returns at least every POLL_S."""
        return self._pool is not None

    def wait_some(self, futures):
        if self._pool is None:
            return futures
        done, _ = wait(futures, timeout=POLL_S, return_when=FIRST_COMPLETED)
        return list(done)

    def result(self, fut):
        return fut.result()

    def abort(self) -> None:
        restore_blas_threads(self._blas)
        self._blas = []
        if self._pool is not None:
            for proc in list(getattr(self._pool, "_processes", {}).values()):
                proc.terminate()
            self._pool.shutdown(wait=False, cancel_futures=True)
            # let its manager thread see the dead workers and close its wake-up pipe now:
            # before CPython 3.12.8 / 3.13.1 (gh-125451) the interpreter's exit hook could
            # write to that pipe while the thread closed it, and print a traceback after
            # the sweep's one-line error (seen once in tests/test_store_crash.py's full disk)
            manager = getattr(self._pool, "_executor_manager_thread", None)
            if manager is not None:
                manager.join(timeout=MANAGER_JOIN_S)
            self._pool = None

    def close(self) -> None:
        restore_blas_threads(self._blas)
        self._blas = []
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None


class _Immediate:
    """A finished 'future' for the in-process backend."""

    def __init__(self, value) -> None:
        self.value = value

    def result(self):
        return self.value


def _make_backend(client, workers: int, scene: Scene, spec: SweepSpec):
    if client is not None:
        from .distributed import DaskBackend

        return DaskBackend(client, scene, spec)
    return _LocalBackend(workers, scene, spec)


_WORKER: dict = {}


def _init_worker(scene: Scene, spec: SweepSpec, parent: int) -> None:
    # Ctrl-C at a terminal reaches the whole process group: only the parent handles it
    # (it terminates the workers), so that workers print no tracebacks
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent(parent)
    single_thread_blas()
    _WORKER["scene"] = scene
    _WORKER["spec"] = spec


#: the OpenBLAS builds numpy and scipy bundle name their thread setter one of these
_BLAS_SET_THREADS = ("openblas_set_num_threads", "openblas_set_num_threads64_",
                     "scipy_openblas_set_num_threads", "scipy_openblas_set_num_threads64_")


def single_thread_blas() -> list[str]:
    """Give every OpenBLAS loaded in this process (a sweep worker) one thread.

    numpy and scipy each load their own OpenBLAS with a thread per core. A worker's
    Newton steps and Floquet multipliers call it on 12 x 12 matrices, and its idle
    threads spin on the cores the other workers need: fig4's 1000-point scan took
    29.4 s on 2 workers instead of 22.8 s (`docs/classification.md`). The libraries
    are found in ``/proc/self/maps`` (Linux; elsewhere, and for processes started
    afresh, the ``*_NUM_THREADS`` variables set here apply). Returns the libraries set.
    """
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[name] = "1"
    return [path for path, _, _ in set_blas_threads(1)]


def set_blas_threads(threads: int) -> list[tuple[str, object, int]]:
    """Set the threads of every OpenBLAS loaded in this process (Linux).

    Returns ``(library, setter, previous threads)`` for each library set, for
    :func:`restore_blas_threads` (previous is 0 where the library cannot tell).
    scipy's own OpenBLAS is loaded first, so that it is set too.
    """
    import scipy.linalg  # noqa: F401

    try:
        with open("/proc/self/maps") as fh:
            paths = sorted({line.split()[-1] for line in fh
                            if "openblas" in line.rsplit("/", 1)[-1].lower()})
    except OSError:
        return []
    import ctypes

    done = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for symbol in _BLAS_SET_THREADS:
            setter = getattr(lib, symbol, None)
            if setter is not None:
                getter = getattr(lib, symbol.replace("_set_", "_get_"), None)
                previous = int(getter()) if getter is not None else 0
                setter(threads)
                done.append((path, setter, previous))
                break
    return done


def restore_blas_threads(changed: list[tuple[str, object, int]]) -> None:
    """Undo :func:`set_blas_threads`."""
    for _, setter, previous in changed:
        if previous > 0:
            setter(previous)


def die_with_parent(parent: int) -> None:
    """Make this worker process end when ``parent`` dies, however it dies; detach stdio.

    Linux's parent-death signal (prctl PR_SET_PDEATHSIG) kills the worker when the
    process that forked it exits, even by SIGKILL; a parent that died before the
    call is caught by the check that follows it. The worker's standard streams
    are pointed at /dev/null, so that it never holds the parent's terminal or
    pipe (``chaospound sweep ... | tee log`` ends with the sweep); its results and
    errors travel back through the pool.
    """
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:
        os._exit(1)
    with contextlib.suppress(OSError):
        devnull = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(devnull, fd)
        os.close(devnull)


def _run_in_worker(indices, start_state, continuation):
    return run_task(_WORKER["scene"], _WORKER["spec"], indices, start_state, continuation)
