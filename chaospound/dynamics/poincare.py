"""Poincare sections: stroboscopic and impact sections (docs/model.md section 11).

* :func:`stroboscopic_section`: the state at t = (phase + k) T for
  k = transient .. transient + cycles (cycles + 1 states), T the excitation
  period. A periodic response of period P cycles gives P distinct points.
* :func:`impact_section`: the state at the onset of every impact of a run,
  with the corner labels.

Both return a :class:`Section` of plain arrays. Nothing here knows about
files or plots.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..kernels.params import P_PHASE0
from ..scene import Scene
from ..simulate import Simulation
from .system import System, as_system, evolve

__all__ = ["Section", "impact_section", "stroboscopic_section"]

STROBOSCOPIC = "stroboscopic"
IMPACT = "impact"


@dataclass(frozen=True)
class Section:
    """Points of a Poincare section.

    Attributes
    ----------
    kind : {"stroboscopic", "impact"}
        How the points were taken.
    times : ndarray (n_points,)
        Normalised times t = tau omega_Ax of the points.
    states : ndarray (n_points, n)
        States in the order of ``state_names`` (lengths in A_g, velocities in
        A_g omega_Ax, rotations in rad).
    state_names : tuple of str
    phase : float or None
        Section phase as a fraction of T (stroboscopic sections; None for
        impact sections, whose phases are ``(times / period) % 1``).
    labels : tuple of str or None
        Corner label of each point (impact sections), None otherwise.
    cycles : ndarray of int (n_points,)
        Excitation cycle index k of each point.
    period : float
        Excitation (sampling) period T, normalised time.
    model : str
        Model that ran ("towers", "pair", ..., or a reference system's name).
    """

    kind: str
    times: np.ndarray
    states: np.ndarray
    state_names: tuple[str, ...]
    phase: float | None
    labels: tuple[str, ...] | None
    cycles: np.ndarray
    period: float
    model: str

    def __len__(self) -> int:
        return int(self.times.shape[0])

    def component(self, name: str) -> np.ndarray:
        """The column of one state component, by name (e.g. ``"dX_A"``)."""
        if name not in self.state_names:
            raise ValueError(f"state {name!r} not in this section ({', '.join(self.state_names)})")
        return self.states[:, self.state_names.index(name)]

    def to_json_dict(self) -> dict:
        """JSON-ready form."""
        return {
            "kind": self.kind,
            "model": self.model,
            "period": self.period,
            "phase": self.phase,
            "state_names": list(self.state_names),
            "times": self.times.tolist(),
            "cycles": self.cycles.tolist(),
            "states": self.states.tolist(),
            "labels": None if self.labels is None else list(self.labels),
        }


def stroboscopic_section(
    scene_or_system: Scene | System,
    *,
    phase: float = 0.0,
    transient: int | None = None,
    cycles: int = 200,
    initial_state: np.ndarray | None = None,
    start_at_section: bool = False,
) -> Section:
    """States at t = (phase + k) T, k = transient .. transient + cycles.

    Parameters
    ----------
    scene_or_system : Scene or System
        Any system (a Scene runs its smallest exact model; a reference
        oscillator; a user's own, :func:`~chaospound.dynamics.system.custom_system`),
        integrated with its solver settings from its initial state at t = 0.
    phase : float
        Section phase as a fraction of the period, in [0, 1).
    transient : int, optional
        Cycles discarded first (default: the scene's ``run.transient`` or the
        system's ``transient``).
    cycles : int
        Cycles recorded, >= 1; the section has cycles + 1 points.
    initial_state : ndarray, optional
        State replacing the system's initial state.
    start_at_section : bool
        Start at the section time ``phase T`` instead of t = 0.

    Returns
    -------
    Section
    """
    phase = float(phase)
    if not 0.0 <= phase < 1.0:
        raise ValueError(f"phase = {phase!r}: must be in [0, 1) (a fraction of the period)")
    cycles = int(cycles)
    if cycles < 1:
        raise ValueError(f"cycles = {cycles}: must be >= 1")
    if transient is not None and int(transient) < 0:
        raise ValueError(f"transient = {transient}: must be >= 0")
    system = as_system(scene_or_system)
    transient = system.transient if transient is None else int(transient)
    params = system.params.copy()
    params[P_PHASE0] = phase * system.period
    run = evolve(replace(system, params=params), initial_state, transient=transient,
                 cycles=cycles, start_at_section=start_at_section)
    return Section(
        kind=STROBOSCOPIC,
        times=run.section_times,
        states=run.sections,
        state_names=tuple(system.state_names),
        phase=phase,
        labels=None,
        cycles=run.cycles,
        period=system.period,
        model=system.model_name,
    )


def impact_section(simulation: Simulation) -> Section:
    """The state at the onset of every impact of a run, with its corner label.

    Parameters
    ----------
    simulation : Simulation
        A run of :func:`chaospound.simulate.simulate`.

    Returns
    -------
    Section
        ``kind = "impact"``; at every point d_max = max(d_lo, d_hi) = 0.
    """
    imp = simulation.impacts
    return Section(
        kind=IMPACT,
        times=imp.time.copy(),
        states=imp.state.copy(),
        state_names=tuple(simulation.state_names),
        phase=None,
        labels=tuple(imp.labels),
        cycles=imp.cycle.copy(),
        period=simulation.period,
        model=simulation.model,
    )
