"""The impact map (docs/model.md section 11).

The sequence of impacts of a run, (phase_n, V_n, corner_n), and the map
n -> n+1 between consecutive impacts: the pairs (phase_n, phase_{n+1}),
(V_n, V_{n+1}) and (corner_n, corner_{n+1}). A response with n impacts per
period of P cycles repeats its corner sequence every n impacts; a periodic
response puts the pairs on n fixed points, a chaotic one spreads them over a
curve or a cloud.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from ..simulate import CORNER_LABELS, Simulation, simulate
from .system import System, as_system

__all__ = ["ImpactMap", "impact_map"]


@dataclass(frozen=True)
class ImpactMap:
    """Impact sequence of a run and its map n -> n+1.

    Attributes
    ----------
    time : ndarray (n,)
        Onset times t (normalised time).
    phase : ndarray (n,)
        ``(t mod T) / T`` in [0, 1).
    velocity : ndarray (n,)
        Relative impact velocities V (units of A_g omega_Ax).
    corner : ndarray of int (n,)
        Corner codes (:data:`chaospound.simulate.CORNER_LABELS`).
    cycle : ndarray of int (n,)
        Excitation cycle of each onset.
    phase_pairs, velocity_pairs : ndarray (n - 1, 2)
        Rows (phase_n, phase_{n+1}) and (V_n, V_{n+1}).
    corner_pairs : ndarray of int (n - 1, 2)
        Rows (corner_n, corner_{n+1}).
    period : float
        Excitation period T (normalised time).
    model : str
        Model that ran.
    """

    time: np.ndarray
    phase: np.ndarray
    velocity: np.ndarray
    corner: np.ndarray
    cycle: np.ndarray
    phase_pairs: np.ndarray
    velocity_pairs: np.ndarray
    corner_pairs: np.ndarray
    period: float
    model: str

    def __len__(self) -> int:
        return int(self.time.shape[0])

    @property
    def labels(self) -> tuple[str, ...]:
        """Corner labels of the impacts ("face", "A+", "A-", "B+", "B-")."""
        return tuple(CORNER_LABELS[int(c)] for c in self.corner)

    def to_json_dict(self) -> dict:
        """JSON-ready form: the sequence and the pairs of the map."""
        labels = self.labels
        return {
            "model": self.model,
            "period": self.period,
            "impacts": [
                {
                    "time": float(self.time[i]),
                    "phase": float(self.phase[i]),
                    "velocity": float(self.velocity[i]),
                    "corner": labels[i],
                    "cycle": int(self.cycle[i]),
                }
                for i in range(len(self))
            ],
            "pairs": {
                "phase": self.phase_pairs.tolist(),
                "velocity": self.velocity_pairs.tolist(),
                "corner": [[labels[i], labels[i + 1]] for i in range(len(self) - 1)],
            },
        }


def impact_map(simulation: Simulation | System | Scene, *, transient: int | None = None,
               cycles: int | None = None,
               initial_state: np.ndarray | None = None) -> ImpactMap:
    """The impact sequence of a run and the pairs of its map n -> n+1.

    Parameters
    ----------
    simulation : Simulation, System or Scene
        A run of :func:`chaospound.simulate.simulate`, whose impacts (onset in
        the record window) are taken in time order; or any system with contacts
        (a Scene, a system made from one, a
        :func:`~chaospound.dynamics.system.custom_system` with a gap function),
        run here by :func:`~chaospound.simulate.simulate`.
    transient, cycles : int, optional
        The run's transient and record window, in periods (a system only;
        default: its own).
    initial_state : ndarray, optional
        The run's start state (a system only).

    Returns
    -------
    ImpactMap
        With fewer than two impacts the pair arrays are empty (shape (0, 2)).

    Raises
    ------
    ValueError
        A custom system without a gap function (it has no impacts), or run
        settings given with a Simulation.
    """
    if not isinstance(simulation, Simulation):
        system = as_system(simulation)
        if not system.has_gap:
            raise ValueError(f"system {system.name!r} has no gap function: it has no impacts "
                             "(custom_system(rhs, jacobian, gap, ...))")
        simulation = simulate(system, transient=transient, cycles=cycles,
                              initial_state=initial_state)
    elif transient is not None or cycles is not None or initial_state is not None:
        raise ValueError("transient, cycles and initial_state set up a run: pass a System or "
                         "a Scene, not a Simulation")
    imp = simulation.impacts
    order = np.argsort(imp.time, kind="stable")  # already in time order; be explicit
    phase = imp.phase[order].astype(np.float64)
    velocity = imp.velocity[order].astype(np.float64)
    corner = imp.corner[order].astype(np.int64)
    return ImpactMap(
        time=imp.time[order].astype(np.float64),
        phase=phase,
        velocity=velocity,
        corner=corner,
        cycle=imp.cycle[order].astype(np.int64),
        phase_pairs=_pairs(phase),
        velocity_pairs=_pairs(velocity),
        corner_pairs=_pairs(corner),
        period=simulation.period,
        model=simulation.model,
    )


def _pairs(sequence: np.ndarray) -> np.ndarray:
    """Rows (s_n, s_{n+1}) of consecutive elements, shape (len - 1, 2)."""
    if sequence.shape[0] < 2:
        return np.zeros((0, 2), dtype=sequence.dtype)
    return np.column_stack((sequence[:-1], sequence[1:]))
