"""Earthquake runs: one scene under a recorded or stochastic ground motion.

:func:`quake` runs a scene from rest under a non-periodic ground motion (an
accelerogram, ``ground = "record"``, or filtered white noise, ``ground =
"stochastic"``) over the whole motion (plus an optional free-vibration tail) and
reports what an engineer reads off such a run:

- per corner label (face, A+, A-, B+, B-, docs/model.md section 8): the number of
  impacts and the peak impact force, relative impact velocity and penetration;
- per tower: the peak displacement relative to the ground of the centre of mass
  (the storey drift of a single-storey tower), of the facing corners (rotation
  included) and the peak rotation;
- a finite-time Lyapunov exponent over the motion (:func:`finite_time_lyapunov`),
  by the two-trajectory method, so that it works for every contact law, smooth or
  not: the growth rate of a tiny separation, renormalised every section;
- optionally an ensemble (:func:`ensemble`): the same run from initial states
  perturbed by ``perturb`` (random directions, seeded) or with the record scale
  spread by ``scale_spread``, and the percentiles of the peak impact force: the
  unpredictability that chaos implies, measured where it matters.

Everything is in model units (docs/model.md section 2); :mod:`chaospound.units`
converts to SI for a scene with physical units. The command line is
``chaospound quake`` (docs/units.md, docs/ground_motions.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from chaospound.dynamics.system import System
from chaospound.dynamics.system import raise_on_failure as _raise_on_failure
from chaospound.engine import tables as kin
from chaospound.scene import Scene, SceneError
from chaospound.simulate import CORNER_LABELS, Simulation, simulate

__all__ = [
    "CornerPeaks",
    "Ensemble",
    "FiniteTimeLyapunov",
    "QuakeRun",
    "TowerPeaks",
    "ensemble",
    "finite_time_lyapunov",
    "motion_end",
    "quake",
    "quake_scene",
]

#: dense samples per section interval for the peak displacements and the plots
SAMPLES_PER_CYCLE = 100
#: default separation of the two trajectories (units of A_g)
SEPARATION = 1e-7
#: the percentiles of the ensemble's peak impact force
PERCENTILES = (5.0, 25.0, 50.0, 75.0, 95.0)
_NO_TANGENT = np.zeros((0, 0))


@dataclass(frozen=True)
class CornerPeaks:
    """Impacts of one corner label over the run (model units).

    Attributes
    ----------
    corner : str
        "face", "A+", "A-", "B+" or "B-".
    impacts : int
    peak_force : float
        Largest episode peak of the contact force on A along -x (A_g K_Ax).
    peak_velocity : float
        Largest relative impact velocity at onset (A_g omega_Ax).
    peak_penetration : float
        Largest episode peak penetration (A_g).
    """

    corner: str
    impacts: int
    peak_force: float
    peak_velocity: float
    peak_penetration: float


@dataclass(frozen=True)
class TowerPeaks:
    """Peak displacements of one tower relative to the ground (model units, over the
    dense samples of the run).

    Attributes
    ----------
    tower : str
        "A" or "B".
    displacement : float
        max |X - u_g| of the centre of mass (A_g): the storey drift.
    corner_displacement : float
        max over the two facing corners of |x - u_g| with the rotation's share
        ``-th (y_corner - y_CM)`` (A_g).
    rotation : float
        max |th| (rad).
    """

    tower: str
    displacement: float
    corner_displacement: float
    rotation: float


@dataclass(frozen=True)
class FiniteTimeLyapunov:
    """Finite-time largest Lyapunov exponent over the motion (two trajectories).

    Attributes
    ----------
    exponent : float
        sum of log(d_k / d0) over the sections, divided by the time covered
        (per unit normalised time; times omega_Ax = 2 pi / T_Ax: per second).
    logs : ndarray
        log(d_k / d0) of each section interval.
    separation : float
        d0 (A_g units, Euclidean norm of the state difference).
    time : float
        Time covered (normalised).
    """

    exponent: float
    logs: np.ndarray
    separation: float
    time: float

    @property
    def amplification(self) -> float:
        """exp(exponent * time): how much a tiny error grows over the motion."""
        return float(math.exp(min(700.0, self.exponent * self.time)))


@dataclass(frozen=True)
class Ensemble:
    """Peak impact force (A_g K_Ax) over an ensemble of nearby runs.

    Attributes
    ----------
    peak_force : ndarray (n,)
        Each run's largest impact force (0 without impacts).
    impacts : ndarray of int (n,)
    perturb, scale_spread : float
        The initial-state perturbation (A_g) and the relative record-scale spread.
    percentiles : dict
        {5, 25, 50, 75, 95: value}.
    realisations : bool
        Each run its own stochastic realisation (ground_seed + i).
    """

    peak_force: np.ndarray
    impacts: np.ndarray
    perturb: float
    scale_spread: float
    percentiles: dict = field(default_factory=dict)
    realisations: bool = False

    @property
    def spread(self) -> float:
        """max - min of the peak impact force."""
        return float(self.peak_force.max() - self.peak_force.min())


@dataclass(frozen=True)
class QuakeRun:
    """Result of :func:`quake` (model units).

    Attributes
    ----------
    scene : Scene
        The scene as run (transient 0, sections from t = 0).
    simulation : Simulation
        The run, with a dense trajectory.
    motion_end, time : float
        The ground motion's last sample time and the time covered (normalised).
    corners : list of CornerPeaks
        Only corners that were hit.
    towers : list of TowerPeaks
    ground_displacement : ndarray
        u_g at the trajectory's samples (A_g).
    lyapunov : FiniteTimeLyapunov or None
    ensemble : Ensemble or None
    """

    scene: Scene
    simulation: Simulation
    motion_end: float
    time: float
    corners: list[CornerPeaks]
    towers: list[TowerPeaks]
    ground_displacement: np.ndarray
    lyapunov: FiniteTimeLyapunov | None = None
    ensemble: Ensemble | None = None

    @property
    def impacts(self) -> int:
        return len(self.simulation.impacts)

    @property
    def peak_force(self) -> float:
        """Largest impact force of the run (0 without impacts)."""
        force = self.simulation.impacts.peak_force
        return float(np.nanmax(force)) if force.size else 0.0

    def to_json_dict(self) -> dict:
        """JSON-ready summary (model units)."""
        out = {
            "scene": self.scene.to_dict(),
            "model": self.simulation.model,
            "motion_end": self.motion_end,
            "time": self.time,
            "impacts": self.impacts,
            "peak_force": self.peak_force,
            "corners": [vars(c) for c in self.corners],
            "towers": [vars(t) for t in self.towers],
            "impact_list": self.simulation.to_json_dict()["impacts"],
        }
        if self.lyapunov is not None:
            out["lyapunov"] = {"exponent": self.lyapunov.exponent,
                               "separation": self.lyapunov.separation,
                               "time": self.lyapunov.time,
                               "amplification": self.lyapunov.amplification,
                               "logs": self.lyapunov.logs.tolist()}
        if self.ensemble is not None:
            e = self.ensemble
            out["ensemble"] = {"runs": int(e.peak_force.size), "perturb": e.perturb,
                               "scale_spread": e.scale_spread, "realisations": e.realisations,
                               "peak_force": e.peak_force.tolist(),
                               "impacts": e.impacts.tolist(),
                               "percentiles": {f"{k:g}": v for k, v in e.percentiles.items()},
                               "spread": e.spread}
        return out


def quake_scene(scene: Scene, record: str | None = None, scale: float | None = None) -> Scene:
    """The scene set up for an earthquake run.

    Parameters
    ----------
    scene : Scene
        Its ground is used unless ``record`` is given; it must then be a record or a
        stochastic motion.
    record : str, optional
        An accelerogram file (sets ``ground = "record"``, ``ground_file``).
    scale : float, optional
        ``ground_scale``.

    Returns
    -------
    Scene
        With transient 0 and section phase 0 (sections at t = k T from the start).

    Raises
    ------
    SceneError
        A periodic ground motion without ``record``, or the record's own errors.
    """
    changes: dict[str, object] = {"transient": 0, "phase": 0.0}
    if record is not None:
        changes.update(ground="record", ground_file=record)
    if scale is not None:
        changes["ground_scale"] = scale
    scene = scene.with_params(**changes)
    if scene.excitation.ground not in ("record", "stochastic"):
        raise SceneError(f"ground = {scene.excitation.ground}: an earthquake run needs a record "
                         "(--record FILE, or ground = record) or ground = stochastic")
    return scene


def motion_end(block: np.ndarray) -> float:
    """The last sample time (normalised) of a record block."""
    n = int(block[0])
    return float(block[3 + n - 1])


def _cycles(scene: Scene, end: float, tail: float) -> int:
    """Section intervals that cover [0, end + tail]."""
    return max(1, math.ceil((end + tail) / scene.period - 1e-12))


def quake(
    scene: Scene,
    *,
    record: str | None = None,
    scale: float | None = None,
    tail: float = 0.0,
    samples_per_cycle: int = SAMPLES_PER_CYCLE,
    lyapunov: bool = True,
    separation: float = SEPARATION,
    runs: int = 0,
    perturb: float = 0.0,
    scale_spread: float = 0.0,
    seed: int = 0,
) -> QuakeRun:
    """Run a scene under a record or a stochastic motion and collect its peaks.

    Parameters
    ----------
    scene : Scene
    record, scale
        See :func:`quake_scene`.
    tail : float
        Free vibration after the motion's last sample (normalised time, >= 0); the
        run covers whole section intervals T = 2 pi r.
    samples_per_cycle : int
        Dense samples per section interval, for the peak displacements (>= 1).
    lyapunov : bool
        Also compute the finite-time Lyapunov exponent (doubles the cost).
    separation : float
        Its initial separation (A_g).
    runs, perturb, scale_spread, seed
        The ensemble (:func:`ensemble`); ``runs = 0``: none.

    Returns
    -------
    QuakeRun
    """
    if not (math.isfinite(tail) and tail >= 0.0):
        raise ValueError(f"tail = {tail!r}: must be >= 0")
    if samples_per_cycle < 1:
        raise ValueError(f"samples_per_cycle = {samples_per_cycle}: must be >= 1")
    scene = quake_scene(scene, record, scale)
    block = scene.excitation.ground_block()
    end = motion_end(block)
    cycles = _cycles(scene, end, tail)
    scene = scene.with_params(record=cycles)
    sim = _finite_trajectory(simulate(scene, samples_per_cycle=samples_per_cycle))
    system = System.from_scene(scene)
    ground = _ground_displacement(system, sim.trajectory.time)
    result = QuakeRun(
        scene=scene, simulation=sim, motion_end=end, time=cycles * scene.period,
        corners=corner_peaks(sim), towers=tower_peaks(sim, ground),
        ground_displacement=ground,
        lyapunov=finite_time_lyapunov(scene, cycles, separation, seed) if lyapunov else None,
        ensemble=ensemble(scene, runs, perturb, scale_spread, seed) if runs > 0 else None,
    )
    return result


def _finite_trajectory(sim: Simulation) -> Simulation:
    """The run with the unfilled rows of its trajectory dropped.

    Under a record the engine may skip a dense sample whose time coincides, to
    rounding, with the end of a step landed on a record sample; the rows that are
    filled carry their own times, the skipped ones stay NaN at the end of the table.
    """
    from dataclasses import replace

    from chaospound.simulate import Trajectory

    traj = sim.trajectory
    keep = np.isfinite(traj.time)
    if keep.all():
        return sim
    return replace(sim, trajectory=Trajectory(traj.time[keep], traj.state[keep]))


def corner_peaks(sim: Simulation) -> list[CornerPeaks]:
    """Impact count and peaks per corner label (only the labels that were hit)."""
    imp = sim.impacts
    out = []
    for code, label in enumerate(CORNER_LABELS):
        hit = imp.corner == code
        if not np.any(hit):
            continue
        out.append(CornerPeaks(label, int(hit.sum()), float(np.nanmax(imp.peak_force[hit])),
                               float(np.max(imp.velocity[hit])),
                               float(np.nanmax(imp.peak_penetration[hit]))))
    return out


def _ground_displacement(system: System, times: np.ndarray) -> np.ndarray:
    """u_g of x at the given times, from the engine's own ground functions."""
    module = system.engine().module
    p = system.params
    out = np.empty(times.shape[0])
    for i, t in enumerate(times):
        out[i] = module.ground_at(float(t), p, module.GROUND)[0]
    return out


def tower_peaks(sim: Simulation, ground: np.ndarray) -> list[TowerPeaks]:
    """Peak relative displacements and rotations of the towers over the trajectory."""
    scene, names = sim.scene, sim.state_names
    state = sim.trajectory.state
    out = []
    for label in ("A", "B"):
        if f"X_{label}" not in names:
            continue
        x = state[:, names.index(f"X_{label}")] - ground
        tower = getattr(scene, f"tower_{label}")
        if f"th_{label}" in names:
            th = state[:, names.index(f"th_{label}")]
            # facing corners at y = +-l/2 from the CS, i.e. +-l/2 - e_y from the CM
            arms = (0.5 * tower.length - tower.e_y, -0.5 * tower.length - tower.e_y)
            corner = max(float(np.max(np.abs(x - th * arm))) for arm in arms)
            rotation = float(np.max(np.abs(th)))
        else:
            corner, rotation = float(np.max(np.abs(x))), 0.0
        out.append(TowerPeaks(label, float(np.max(np.abs(x))), corner, rotation))
    return out


def _advance_one(system: System, p: np.ndarray, y: np.ndarray, k: int) -> np.ndarray:
    """Integrate from the section k (absolute time k T) to k + 1, in place."""
    n = y.shape[0]
    clock = np.array([float(k), 0.0, 0.0])
    stats = np.zeros(kin.N_STATS, dtype=np.int64)
    h_fixed = system.period / system.steps_per_cycle
    system.engine().run_cycles(p, y, clock, k + 1, k + 1, system.rtol, system.atol, h_fixed,
                               system.max_steps, system.restart_at_kinks, 0, np.zeros((1, n)),
                               np.zeros((1, n + 1)), np.zeros((0, kin.N_IMP_FIELDS)),
                               np.zeros((0, n)), stats, _NO_TANGENT)
    status = int(stats[kin.ST_STATUS])
    if status != kin.STATUS_OK:
        _raise_on_failure(status, stats, clock, system.period, system.max_steps, y)
    return y


def finite_time_lyapunov(scene: Scene, cycles: int, separation: float = SEPARATION,
                         seed: int = 0) -> FiniteTimeLyapunov:
    """Largest finite-time Lyapunov exponent over ``cycles`` section intervals from t = 0.

    Two trajectories, the scene's initial state and one ``separation`` away along
    a seeded random direction, each with its own packed vector (a contact law's
    per-episode memory lives there), are integrated section by section in
    absolute time (the motion is not periodic); after each interval the log of
    the separation's growth is recorded and the separation is scaled back to
    ``separation`` along its current direction (Benettin et al. 1976). Needs no
    Jacobian: it works for every contact law, smooth or not. The integration
    error should stay well below ``separation`` (tighten rtol for small ones).
    """
    if not (separation > 0.0 and math.isfinite(separation)):
        raise ValueError(f"separation = {separation!r}: must be > 0")
    system = System.from_scene(scene)
    p_ref, p_other = system.params.copy(), system.params.copy()
    y = np.array(system.initial_state, dtype=np.float64)
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=y.shape[0])
    other = y + separation * direction / np.linalg.norm(direction)
    logs = np.zeros(cycles)
    for k in range(cycles):
        _advance_one(system, p_ref, y, k)
        _advance_one(system, p_other, other, k)
        delta = other - y
        norm = float(np.linalg.norm(delta))
        if norm == 0.0:  # the perturbation was lost below round-off
            logs[k] = -math.inf
            other = y + separation * direction / np.linalg.norm(direction)
            continue
        logs[k] = math.log(norm / separation)
        other = y + delta * (separation / norm)
    time = cycles * system.period
    return FiniteTimeLyapunov(float(logs.sum() / time), logs, separation, time)


def ensemble(scene: Scene, runs: int, perturb: float = 0.0, scale_spread: float = 0.0,
             seed: int = 0, realisations: bool = False) -> Ensemble:
    """Peak impact force over ``runs`` runs from perturbed initial states or record scales.

    Run i starts from the scene's initial state plus ``perturb`` times a random
    unit vector (seeded by ``seed``) and/or with ``ground_scale`` multiplied by
    ``1 + scale_spread u_i``, u_i uniform in [-1, 1]; with ``realisations`` (a
    stochastic motion) it also runs its own realisation, ``ground_seed + i``. The
    scene must be set up by :func:`quake_scene` with its record length (``quake``
    does it). Zero perturbation and spread repeat the same run: zero spread.
    """
    if runs < 1:
        raise ValueError(f"runs = {runs}: must be >= 1")
    if realisations and scene.excitation.ground != "stochastic":
        raise ValueError(f"realisations: ground = {scene.excitation.ground}, not stochastic")
    for name, value in (("perturb", perturb), ("scale_spread", scale_spread)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{name} = {value!r}: must be >= 0")
    if scale_spread >= 1.0:
        raise ValueError(f"scale_spread = {scale_spread!r}: must be < 1 (the scale stays > 0)")
    rng = np.random.default_rng(seed)
    base = scene.initial_vector()
    peaks, counts = np.zeros(runs), np.zeros(runs, dtype=np.int64)
    for i in range(runs):
        direction = rng.normal(size=base.shape[0])
        u = rng.uniform(-1.0, 1.0)
        member = scene
        if realisations:
            member = member.with_params(ground_seed=scene.excitation.ground_seed + i)
        if scale_spread > 0.0:
            member = member.with_params(ground_scale=scene.excitation.ground_scale
                                        * (1.0 + scale_spread * u))
        start = base + perturb * direction / np.linalg.norm(direction)
        sim = simulate(member, initial_state=start)
        force = sim.impacts.peak_force
        peaks[i] = float(np.nanmax(force)) if force.size else 0.0
        counts[i] = len(sim.impacts)
    percentiles = {q: float(np.percentile(peaks, q)) for q in PERCENTILES}
    return Ensemble(peaks, counts, perturb, scale_spread, percentiles, realisations)


def contact_force(run: QuakeRun) -> np.ndarray:
    """The contact force on A along -x at the trajectory's samples (A_g K_Ax).

    The model's ``model_forces`` at each sample, with the contact law's
    per-episode memory (hertzdamp's and hunt-crossley's onset velocity v0) written
    at every recorded onset as the engine writes it (``law_on_onset`` with the
    closing rate at the onset state), so that the dissipative laws' forces are
    those of the run.
    """
    sim = run.simulation
    system = System.from_scene(run.scene)
    module = system.engine().module
    p = system.params.copy()
    imp = sim.impacts
    ends = np.empty(4)
    q = np.empty(6)
    times, states = sim.trajectory.time, sim.trajectory.state
    out = np.empty(times.shape[0])
    memory = bool(module.LAW_MEMORY)
    onset = 0
    for i in range(times.shape[0]):
        t = float(times[i])
        while memory and onset < len(imp) and imp.time[onset] <= t:
            module.model_ends(float(imp.time[onset]), imp.state[onset], p, ends)
            rate = module.model_contact_point(float(imp.time[onset]), imp.state[onset], p,
                                              ends)[2]
            module.law_on_onset(p, module.LAW, rate)
            onset += 1
        out[i] = module.model_forces(t, states[i], p, q)
    return out


def plot_quake(run: QuakeRun, units=None):
    """Time histories of an earthquake run: ground acceleration, displacements relative
    to the ground, the clearance with the impacts, the contact force.

    Parameters
    ----------
    run : QuakeRun
    units : chaospound.units.PhysicalUnits, optional
        Draw in SI (s, g, mm, kN); else in model units.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from chaospound.simulate import contact_history
    from chaospound.units import GRAVITY, si_value

    sim = run.simulation
    contact = contact_history(sim)
    block = run.scene.excitation.ground_block()
    n = int(block[0])
    t_g, a_g = block[3:3 + n], block[3 + 3 * n:3 + 4 * n]
    time = sim.trajectory.time
    if units is not None:
        def tt(v):
            return si_value(units, "time", v)

        def length(v):
            return si_value(units, "length", v)

        def force(v):
            return si_value(units, "force", v)

        acc = a_g * units.acceleration / GRAVITY
        labels = ("t [s]", "u_g'' [g]", "x - u_g [mm]", "clearance [mm]", "force [kN]")
        force_unit = "kN"
    else:
        def tt(v):
            return v

        length = force = tt
        acc = a_g
        labels = ("t (omega_Ax)", "u_g'' (A_g omega_Ax^2)", "x - u_g (A_g)", "clearance (A_g)",
                  "force (A_g K_Ax)")
        force_unit = "A_g K_Ax"
    fig = Figure(figsize=(10.0, 9.0), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    axes[0].plot(tt(t_g), acc, lw=0.6, color="0.3")
    for label, color in (("A", "C0"), ("B", "C1")):
        if f"X_{label}" in sim.state_names:
            x = sim.trajectory.state[:, sim.state_names.index(f"X_{label}")]
            axes[1].plot(tt(time), length(x - run.ground_displacement), lw=0.8, color=color,
                         label=f"tower {label} (centre of mass)")
    axes[1].legend(loc="upper right", fontsize="small")
    axes[2].plot(tt(time), length(contact.clearance), lw=0.8, color="C2")
    axes[2].axhline(0.0, color="0.6", lw=0.5)
    imp = sim.impacts
    axes[2].plot(tt(imp.time), np.zeros(len(imp)), "v", color="C3", ms=4, label="impacts")
    axes[2].legend(loc="upper right", fontsize="small")
    axes[3].plot(tt(time), force(contact_force(run)), lw=0.8, color="C3")
    for ax, label in zip(axes, labels[1:], strict=True):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(labels[0])
    fig.suptitle(f"{run.scene.name}: {run.impacts} impacts, peak force "
                 f"{force(run.peak_force):.4g} {force_unit}")
    return fig
