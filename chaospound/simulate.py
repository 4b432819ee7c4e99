"""Steady-state runs: transient, record window, impacts, stroboscopic section.

The driver packs a :class:`~chaospound.scene.Scene`, picks the smallest exact
model (docs/model.md section 9), runs the jitted cycle integrator
(the composed engine of :mod:`chaospound.engine.compose`) and returns plain arrays in
dataclasses. Nothing here knows about files, plots or the command line.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .dynamics.system import (  # noqa: F401  (warm_up, DEFAULT_COMPOSITION re-exported)
    DEFAULT_COMPOSITION,
    SimulationError,
    System,
    as_system,
    evolve,
    warm_up,
)
from .engine import tables as kin
from .engine.compose import Composition, engine_for
from .scene import Scene

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


def run_stats(run) -> RunStats:
    """The :class:`RunStats` of an :class:`~chaospound.dynamics.system.Evolution`."""
    stats = run.stats
    return RunStats(
        steps=int(stats[kin.ST_ACCEPTED]),
        rejected=int(stats[kin.ST_REJECTED]),
        rhs_evals=int(stats[kin.ST_RHS_EVALS]),
        events=int(stats[kin.ST_EVENTS]),
        wall_s=run.wall_s,
    )


def simulate(
    scene: Scene | System,
    *,
    transient: int | None = None,
    cycles: int | None = None,
    samples_per_cycle: int = 0,
    initial_state: np.ndarray | None = None,
    start_at_section: bool = False,
    impact_capacity: int | None = None,
    start_phase: float | None = None,
    record: int | None = None,
) -> Simulation:
    """Run a scene to steady state and record impacts and the stroboscopic section.

    Parameters
    ----------
    scene : Scene or System
        The scene, with its solver and run settings; or a
        :class:`~chaospound.dynamics.system.System`, e.g. a user's own
        (:func:`~chaospound.dynamics.system.custom_system`), run with its
        solver settings (default record window: 8 periods).
    transient, cycles : int, optional
        Cycles discarded and recorded; default the scene's ``run`` settings
        (paper: 40 + 8). ``record`` is an accepted alias of ``cycles``.
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
    record : int, optional
        The former name of ``cycles`` (give one of them).

    Returns
    -------
    Simulation

    Raises
    ------
    SimulationError
        When the step budget runs out, the step size underflows or the state
        becomes non-finite; the message carries the numbers.
    """
    system = as_system(scene)
    if record is not None and cycles is not None and int(record) != int(cycles):
        raise ValueError(f"record = {record}, cycles = {cycles}: give one of them")
    cycles = record if cycles is None else cycles
    transient = system.transient if transient is None else int(transient)
    cycles = system.record if cycles is None else int(cycles)
    if transient < 0 or cycles < 1:
        raise ValueError(f"transient = {transient}, record = {cycles}: need >= 0 and >= 1")
    n = system.dim
    if initial_state is not None:
        y_start = np.asarray(initial_state, dtype=np.float64)
        if y_start.shape != (n,) or not np.all(np.isfinite(y_start)):
            raise ValueError(
                f"initial_state has shape {y_start.shape}: need {n} finite values "
                f"({', '.join(system.state_names)})"
            )
    # every simulation starts with the packed vector as packed: a contact law's
    # per-episode memory does not leak from one simulation into the next
    run = evolve(replace(system, params=system.params.copy()), initial_state,
                 transient=transient, cycles=cycles, start_at_section=start_at_section,
                 start_phase=start_phase, impacts=True, impact_capacity=impact_capacity,
                 samples_per_cycle=samples_per_cycle)
    rows, states = run.impacts, run.impact_states
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
        state=states.copy(),
    )
    strobe = Strobe(cycle=run.cycles, time=run.section_times, state=run.sections)
    trajectory = None
    if run.samples is not None:
        trajectory = Trajectory(time=run.samples[:, 0].copy(), state=run.samples[:, 1:].copy())
    stats_obj = run_stats(run)
    return Simulation(
        scene=_scene_as_run(system),
        model=system.model_name,
        state_names=tuple(system.state_names),
        impacts=impacts,
        strobe=strobe,
        trajectory=trajectory,
        stats=stats_obj,
        final_state=run.end_state,
        transient=transient,
        record=cycles,
        period=system.period,
        name=system.name,
    )


def _scene_as_run(system: System) -> Scene | None:
    """The system's scene with the system's solver settings (None for a custom system)."""
    scene = system.scene
    if scene is None:
        return None
    settings = {k: getattr(system, k) for k in ("method", "rtol", "atol", "steps_per_cycle",
                                                 "max_steps", "restart_at_kinks")}
    if all(getattr(scene.solver, k) == v for k, v in settings.items()):
        return scene
    return scene.with_params(**settings)


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
