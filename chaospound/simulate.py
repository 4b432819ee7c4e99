"""Steady-state runs: transient, record window, impacts, stroboscopic section.

The driver packs a :class:`~chaospound.scene.Scene`, picks the smallest exact
model (docs/model.md section 9), runs the jitted cycle integrator
(the composed engine of :mod:`chaospound.engine.compose`) and returns plain arrays in
dataclasses. Nothing here knows about files, plots or the command line.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .dynamics.system import SimulationError, System
from .dynamics.system import raise_on_failure as _raise_on_failure
from .engine import tables as kin
from .engine.compose import Composition, Engine, engine_for
from .kernels.params import (
    MODEL_DIMS,
    MODEL_NAMES,
    N_PARAMS,
    P_HALF_L,
    P_PERIOD,
    P_PERIOD_RATIO,
    P_PHASE0,
)
from .scene import STATE_NAMES, Scene

__all__ = [
    "ContactHistory",
    "Impacts",
    "RunStats",
    "Simulation",
    "SimulationError",
    "Strobe",
    "Trajectory",
    "contact_history",
    "simulate",
]

CORNER_LABELS = kin.CORNER_LABELS
_NO_TANGENT = np.zeros((0, 0))  #: tangent_log placeholder for plain runs


@dataclass(frozen=True)
class Impacts:
    """Impacts whose onset lies in the record window, one row each.

    Attributes
    ----------
    time : ndarray
        Onset times t (normalised time, t = tau omega_Ax).
    phase : ndarray
        ``(t mod T) / T`` in [0, 1).
    velocity : ndarray
        Relative impact velocity V (units of A_g omega_Ax), the rate of
        penetration at the contact point at onset.
    corner : ndarray of int
        Corner codes, see :data:`CORNER_LABELS` ("face", "A+", "A-", "B+", "B-").
    contact_y : ndarray
        Global y of the contact point (units of A_g).
    peak_penetration, peak_force, duration : ndarray
        Per contact episode: max of d_max (A_g), max of the resultant force on
        A along -x (A_g k_Ax), and the time until d_max falls back through 0.
    cycle : ndarray of int
        Excitation cycle index k of each onset.
    state : ndarray (n_impacts, n)
        Full model state at each onset.
    """

    time: np.ndarray
    phase: np.ndarray
    velocity: np.ndarray
    corner: np.ndarray
    contact_y: np.ndarray
    peak_penetration: np.ndarray
    peak_force: np.ndarray
    duration: np.ndarray
    cycle: np.ndarray
    state: np.ndarray

    def __len__(self) -> int:
        return int(self.time.shape[0])

    @property
    def labels(self) -> list[str]:
        """Corner labels as strings."""
        return [CORNER_LABELS[int(c)] for c in self.corner]


@dataclass(frozen=True)
class Strobe:
    """Stroboscopic Poincare section: states at t = t0 + k T, k = k_first .. k_last."""

    cycle: np.ndarray
    time: np.ndarray
    state: np.ndarray


@dataclass(frozen=True)
class Trajectory:
    """Dense samples of the record window (interpolated on the steps' dense output)."""

    time: np.ndarray
    state: np.ndarray


@dataclass(frozen=True)
class RunStats:
    """Work done by one run."""

    steps: int
    rejected: int
    rhs_evals: int
    events: int
    wall_s: float


@dataclass(frozen=True)
class Simulation:
    """Result of :func:`simulate`.

    Attributes
    ----------
    scene : Scene or None
        The scene as run (None for a custom system).
    model : str
        The reduction that ran ("wall", "tower-wall", "pair" or "towers"), or
        "custom".
    state_names : tuple of str
        Names of the state components, in order.
    impacts, strobe : Impacts, Strobe
    trajectory : Trajectory or None
        Present when samples were requested.
    stats : RunStats
    final_state : ndarray
        State at the end of the run (the last section, or the end of the last
        contact episode when one was running at the end of the window).
    """

    scene: Scene | None
    model: str
    state_names: tuple[str, ...]
    impacts: Impacts
    strobe: Strobe
    trajectory: Trajectory | None
    stats: RunStats
    final_state: np.ndarray
    transient: int = field(default=0)
    record: int = field(default=0)
    period: float = field(default=float("nan"))
    name: str = field(default="")

    def to_json_dict(self) -> dict:
        """JSON-ready summary (the ``--json`` output of ``chaospound simulate``)."""
        imp = self.impacts
        return {
            "model": self.model,
            "scene": self.scene.to_dict() if self.scene is not None else {"name": self.name},
            "state_names": list(self.state_names),
            "transient_cycles": self.transient,
            "record_cycles": self.record,
            "impacts": [
                {
                    "time": float(imp.time[i]),
                    "phase": float(imp.phase[i]),
                    "velocity": float(imp.velocity[i]),
                    "corner": CORNER_LABELS[int(imp.corner[i])],
                    "cycle": int(imp.cycle[i]),
                    "contact_y": float(imp.contact_y[i]),
                    "peak_penetration": float(imp.peak_penetration[i]),
                    "peak_force": float(imp.peak_force[i]),
                    "duration": float(imp.duration[i]),
                    "state": imp.state[i].tolist(),
                }
                for i in range(len(imp))
            ],
            "strobe": self.strobe.state.tolist(),
            "strobe_cycles": self.strobe.cycle.tolist(),
            "final_state": self.final_state.tolist(),
            "stats": {
                "steps": self.stats.steps,
                "rejected": self.stats.rejected,
                "rhs_evals": self.stats.rhs_evals,
                "events": self.stats.events,
                "wall_s": self.stats.wall_s,
            },
        }


@dataclass(frozen=True)
class _SceneRun:
    """What :func:`simulate` needs of a scene or a system."""

    model_id: int
    model: str
    n: int
    p: np.ndarray
    initial_state: np.ndarray
    state_names: tuple[str, ...]
    solver: object  #: anything with method, rtol, atol, steps_per_cycle, max_steps, ...
    period: float
    t0: float
    transient: int
    record: int
    name: str
    engine: Engine
    scene: Scene | None = None

    @classmethod
    def of_scene(cls, scene: Scene) -> _SceneRun:
        model_id = scene.model_id()
        return cls(model_id=model_id, model=MODEL_NAMES[model_id], n=MODEL_DIMS[model_id],
                   p=scene.pack(model_id), initial_state=scene.initial_vector(model_id),
                   state_names=STATE_NAMES[model_id], solver=scene.solver,
                   period=scene.period, t0=scene.run.phase * scene.period,
                   transient=scene.run.transient, record=scene.run.record, name=scene.name,
                   engine=engine_for(Composition(
                       model=MODEL_NAMES[model_id], law=scene.contact.contact_law,
                       ground=scene.excitation.ground, method=scene.solver.method)),
                   scene=scene)

    @classmethod
    def of_system(cls, system) -> _SceneRun:
        if not isinstance(system, System):
            raise TypeError(f"expected a Scene or a System, got {type(system).__name__}")
        if system.scene is not None:
            return cls.of_scene(system.scene.with_params(
                method=system.method, rtol=system.rtol, atol=system.atol,
                steps_per_cycle=system.steps_per_cycle, max_steps=system.max_steps,
                restart_at_kinks=system.restart_at_kinks))
        return cls(model_id=system.model_id, model=system.model_name, n=system.dim,
                   p=system.params, initial_state=np.asarray(system.initial_state, float),
                   state_names=tuple(system.state_names), solver=system,
                   period=system.period, t0=float(system.params[P_PHASE0]),
                   transient=system.transient, record=system.record, name=system.name,
                   engine=system.engine())


def simulate(
    scene: Scene | System,
    *,
    transient: int | None = None,
    record: int | None = None,
    samples_per_cycle: int = 0,
    initial_state: np.ndarray | None = None,
    start_at_section: bool = False,
    impact_capacity: int | None = None,
    start_phase: float | None = None,
) -> Simulation:
    """Run a scene to steady state and record impacts and the stroboscopic section.

    Parameters
    ----------
    scene : Scene or System
        The scene, with its solver and run settings; or a
        :class:`~chaospound.dynamics.system.System`, e.g. a user's own
        (:func:`~chaospound.dynamics.system.custom_system`), run with its
        solver settings (default record window: 8 periods).
    transient, record : int, optional
        Cycles discarded and recorded; default the scene's ``run`` settings
        (paper: 40 + 8).
    samples_per_cycle : int
        Dense trajectory samples per excitation cycle over the record window
        (0: none). Use a few hundred for phase diagrams.
    initial_state : ndarray, optional
        State in the model's order (``Simulation.state_names``) replacing the
        scene's initial state, e.g. the final state of a neighbouring point.
    start_at_section : bool
        Start at the section time t0 = phase T instead of t = 0 (continuation
        from a stroboscopic state).
    impact_capacity : int, optional
        Initial size of the impact table (grown automatically).
    start_phase : float, optional
        Start at forcing phase ``start_phase`` (a fraction of the period, in
        [0, 1)) instead of t = 0: at the time ``start_phase T`` minus the whole
        periods that put it within one period before the first section (the
        sections stay at the scene's phase); for basins over the initial phase.

    Returns
    -------
    Simulation

    Raises
    ------
    SimulationError
        When the step budget runs out, the step size underflows or the state
        becomes non-finite; the message carries the numbers.
    """
    if isinstance(scene, Scene):
        run = _SceneRun.of_scene(scene)
    else:
        run = _SceneRun.of_system(scene)
    transient = run.transient if transient is None else int(transient)
    record = run.record if record is None else int(record)
    if transient < 0 or record < 1:
        raise ValueError(f"transient = {transient}, record = {record}: need >= 0 and >= 1")
    n, p, solver, period, name = run.n, run.p, run.solver, run.period, run.name
    if initial_state is None:
        y_start = run.initial_state.copy()
    else:
        y_start = np.asarray(initial_state, dtype=np.float64).copy()
        if y_start.shape != (n,) or not np.all(np.isfinite(y_start)):
            raise ValueError(
                f"initial_state has shape {y_start.shape}: need {n} finite values "
                f"({', '.join(run.state_names)})"
            )
    t0 = run.t0
    tau_start = 0.0 if (start_at_section or t0 == 0.0) else -t0
    if start_phase is not None:  # t0 + tau_start = start_phase T (mod T), tau_start <= 0
        if not 0.0 <= start_phase < 1.0:
            raise ValueError(f"start_phase = {start_phase}: must be in [0, 1)")
        tau_start = -((t0 - start_phase * period) % period)
    h_fixed = period / solver.steps_per_cycle
    capacity = impact_capacity or max(64, 16 * (record + 1))
    n_rows_traj = samples_per_cycle * record + 1 if samples_per_cycle > 0 else 1

    warm_up(run.engine)
    start = time.perf_counter()
    while True:
        y = y_start.copy()
        clock = np.array([0.0, tau_start, 0.0])
        strobe = np.full((record + 1, n), np.nan)
        traj = np.full((n_rows_traj, n + 1), np.nan)
        imp = np.zeros((capacity, kin.N_IMP_FIELDS))
        imp_state = np.zeros((capacity, n))
        stats = np.zeros(kin.N_STATS, dtype=np.int64)
        n_imp = run.engine.run_cycles(
            p, y, clock, transient, transient + record,
            solver.rtol, solver.atol, h_fixed, solver.max_steps, solver.restart_at_kinks,
            samples_per_cycle, strobe, traj, imp, imp_state, stats, _NO_TANGENT,
        )
        status = int(stats[kin.ST_STATUS])
        if status != kin.STATUS_OVERFLOW:
            break
        capacity *= 4
    wall = time.perf_counter() - start
    _raise_on_failure(status, stats, clock, period, solver.max_steps, y)

    rows = imp[:n_imp]
    impacts = Impacts(
        time=rows[:, kin.IMP_TIME].copy(),
        phase=rows[:, kin.IMP_PHASE].copy(),
        velocity=rows[:, kin.IMP_VELOCITY].copy(),
        corner=rows[:, kin.IMP_CORNER].astype(np.int8),
        contact_y=rows[:, kin.IMP_Y].copy(),
        peak_penetration=rows[:, kin.IMP_PEAK_PEN].copy(),
        peak_force=rows[:, kin.IMP_PEAK_FORCE].copy(),
        duration=rows[:, kin.IMP_DURATION].copy(),
        cycle=rows[:, kin.IMP_CYCLE].astype(np.int64),
        state=imp_state[:n_imp].copy(),
    )
    cycles = np.arange(transient, transient + record + 1)
    strobe_obj = Strobe(cycle=cycles, time=t0 + cycles * period, state=strobe)
    trajectory = None
    if samples_per_cycle > 0:
        trajectory = Trajectory(time=traj[:, 0].copy(), state=traj[:, 1:].copy())
    stats_obj = RunStats(
        steps=int(stats[kin.ST_ACCEPTED]),
        rejected=int(stats[kin.ST_REJECTED]),
        rhs_evals=int(stats[kin.ST_RHS_EVALS]),
        events=int(stats[kin.ST_EVENTS]),
        wall_s=wall,
    )
    return Simulation(
        scene=run.scene,
        model=run.model,
        state_names=run.state_names,
        impacts=impacts,
        strobe=strobe_obj,
        trajectory=trajectory,
        stats=stats_obj,
        final_state=y,
        transient=transient,
        record=record,
        period=period,
        name=name,
    )


_WARM: set = set()


def warm_up(engine: Engine | None = None) -> None:
    """Load (or compile) an engine once per process, outside any timing.

    A tiny call makes later ``stats.wall_s`` measure the work alone. Without
    an argument: the engine of the default scene (fig3a's composition).
    """
    if engine is None:
        engine = engine_for(DEFAULT_COMPOSITION)
    if engine.composition in _WARM:
        return
    n = {"wall": 2, "tower-wall": 6, "pair": 4, "towers": 12}.get(engine.composition.model)
    if n is None:  # reference and user systems: compiled by their first real run
        return
    y = np.zeros(n)
    p = np.zeros(N_PARAMS)
    p[P_PERIOD] = 1.0
    p[P_PERIOD_RATIO] = 1.0
    p[P_HALF_L] = 0.5
    stats = np.zeros(kin.N_STATS, dtype=np.int64)
    engine.run_cycles(p, y, np.zeros(3), 0, 1, 1e-6, 1e-9, 0.1, 1, True, 0,
                      np.zeros((2, n)), np.zeros((1, n + 1)), np.zeros((0, kin.N_IMP_FIELDS)),
                      np.zeros((0, n)), stats, _NO_TANGENT)
    _WARM.add(engine.composition)


#: the composition of the default scene (the paper's towers, Hertz, sine, DOPRI5)
DEFAULT_COMPOSITION = Composition(model="towers")


def kernels_cached(composition: Composition | None = None) -> bool | None:
    """Whether an engine (default: the default scene's) loads from numba's disk cache
    (a first run compiles it: tens of seconds); None when unknown (see
    :func:`chaospound.kernels.jit.is_cached`)."""
    return engine_for(composition or DEFAULT_COMPOSITION).is_cached()


@dataclass(frozen=True)
class ContactHistory:
    """The contact along a run's dense trajectory (the time-history figure's data).

    Attributes
    ----------
    time : ndarray (n,)
        The trajectory's sample times t (normalised time, t = tau omega_Ax).
    penetration : ndarray (n,)
        d_max = max(d_lo, d_hi), the larger penetration of the contact line's two
        ends (units of A_g): > 0 in contact, < 0 apart.
    clearance : ndarray (n,)
        The gap left, -d_max (units of A_g): 0 at an impact's onset.
    force : ndarray (n,)
        The resultant compressive contact force on tower A along -x (units of
        A_g k_Ax): 0 wherever the clearance is positive.
    """

    time: np.ndarray
    penetration: np.ndarray
    clearance: np.ndarray
    force: np.ndarray


def contact_history(simulation: Simulation) -> ContactHistory:
    """Penetration, clearance and contact force at every sample of a run's trajectory.

    Evaluated with the model's own contact geometry and forces (the kernels'
    ``contact_ends`` and ``contact_forces``) at the dense samples.

    Parameters
    ----------
    simulation : Simulation
        A run of a scene with a dense trajectory (``samples_per_cycle`` > 0).

    Returns
    -------
    ContactHistory
    """
    traj, scene = simulation.trajectory, simulation.scene
    if traj is None:
        raise ValueError("the simulation has no trajectory: run simulate(scene, "
                         "samples_per_cycle=N) with N > 0")
    if scene is None:
        raise ValueError("contact histories need a scene's model (a custom system has its "
                         "own gap function)")
    system = System.from_scene(scene)
    kernels = system.engine().module
    p = system.params
    ends = np.empty(4)
    q = np.empty(6)
    n = traj.time.shape[0]
    penetration = np.empty(n)
    force = np.empty(n)
    for i in range(n):
        t, y = float(traj.time[i]), traj.state[i]
        kernels.model_ends(t, y, p, ends)
        penetration[i] = max(ends[0], ends[1])
        force[i] = kernels.model_forces(t, y, p, q)
    return ContactHistory(time=traj.time.copy(), penetration=penetration,
                          clearance=-penetration, force=force)
