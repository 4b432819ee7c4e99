"""The clearance of a periodic orbit: the grazing test function of continuation.

An impact appears or disappears (grazing) when a local minimum of the
clearance along the orbit passes through zero: the minimum gap of a free
flight touches zero, or, seen from the other side, the peak penetration of an
impact (whose velocity goes to zero with it) shrinks to nothing. The clearance
is the negative penetration ``-d`` at each end of the contact (the model's
``model_ends``: a rigid line contact is deepest at an end; a custom system's
``g`` from its gap function), in A_g (the model's length unit).

:func:`clearance_minima` samples one period of the orbit with the integrator's
dense output (``GRAZING_SAMPLES`` per forcing cycle) together with the
clearance's rate (``model_ends`` gives both), and locates every local minimum
between two samples on the cubic Hermite interpolant of (clearance, rate):
error O(h^4) in the sample spacing h, so the minimum varies smoothly with the
parameter and a root of :func:`grazing_test` can be located by regula falsi
like the other test functions (:mod:`chaospound.orbits.continuation`).
"""

from __future__ import annotations

import numpy as np

from .maps import StroboscopicMap

__all__ = ["GRAZING_SAMPLES", "clearance_minima", "free_flight_clearance", "grazing_test"]

GRAZING_SAMPLES = 400  #: dense samples per forcing cycle


def _hermite_minima(t: np.ndarray, c: np.ndarray, r: np.ndarray) -> list[tuple[float, float]]:
    """(time, value) of the local minima of the cubic Hermite interpolant of (c, c')."""
    out = []
    for i in range(t.shape[0] - 1):
        if not (r[i] < 0.0 <= r[i + 1]):
            continue
        h = t[i + 1] - t[i]
        a1 = h * r[i]
        a2 = 3.0 * (c[i + 1] - c[i]) - h * (2.0 * r[i] + r[i + 1])
        a3 = 2.0 * (c[i] - c[i + 1]) + h * (r[i] + r[i + 1])
        # p'(s) = a1 + 2 a2 s + 3 a3 s^2 = 0 with p'' > 0, s in [0, 1]
        roots = np.roots([3.0 * a3, 2.0 * a2, a1]) if (a3 != 0.0 or a2 != 0.0) else []
        best = None
        for s in np.real(np.asarray(roots)[np.abs(np.imag(roots)) < 1e-12]):
            if -1e-9 <= s <= 1.0 + 1e-9 and 2.0 * a2 + 6.0 * a3 * s > 0.0:
                s = min(max(float(s), 0.0), 1.0)
                best = s
        s = 1.0 if best is None else best
        value = c[i] + a1 * s + a2 * s * s + a3 * s ** 3
        out.append((t[i] + s * h, float(value)))
    return out


def clearance_minima(smap: StroboscopicMap, state: np.ndarray, k: int = 1, *,
                     samples_per_cycle: int = GRAZING_SAMPLES) -> np.ndarray:
    """Local minima of the clearance over one period of the orbit through a section state.

    Parameters
    ----------
    smap : StroboscopicMap
    state : ndarray (n,)
        A section state of a period-k orbit.
    k : int
        Period in forcing cycles.
    samples_per_cycle : int
        Dense samples per cycle.

    Returns
    -------
    ndarray (m, 3)
        Rows (time from the section, clearance, end): time in normalised units,
        clearance in the model's length unit (negative: a contact, the value its
        peak penetration), end 0 or 1 (the contact line's low and high ends;
        both 0 for a point contact).
    """
    from ..simulate import simulate

    system = smap.system
    run = simulate(system, transient=0, record=int(k), initial_state=state,
                   start_at_section=True, samples_per_cycle=int(samples_per_cycle))
    time, states = run.trajectory.time, run.trajectory.state
    ends_of = system.engine().module.model_ends
    ends = np.zeros((time.shape[0], 4))
    work = np.zeros(4)
    for i in range(time.shape[0]):
        ends_of(float(time[i]), states[i], system.params, work)
        ends[i] = work
    rows = []
    point_contact = bool(np.array_equal(ends[:, 0], ends[:, 1]))
    for end in (0,) if point_contact else (0, 1):
        for t, value in _hermite_minima(time, -ends[:, end], -ends[:, end + 2]):
            rows.append((t - time[0], value, end))
    return np.array(rows, dtype=float).reshape(-1, 3)


def grazing_test(smap: StroboscopicMap, state: np.ndarray, k: int = 1, *,
                 samples_per_cycle: int = GRAZING_SAMPLES) -> float:
    """The local minimum of the clearance nearest zero (signed; +inf if there is none).

    Positive: the closest approach of a free flight; negative: the shallowest
    impact's peak penetration. Its sign changes where an impact appears or
    disappears (grazing).
    """
    minima = clearance_minima(smap, state, k, samples_per_cycle=samples_per_cycle)
    if minima.shape[0] == 0:
        return float("inf")
    values = minima[:, 1]
    return float(values[np.argmin(np.abs(values))])


def free_flight_clearance(smap: StroboscopicMap, state: np.ndarray, k: int = 1, *,
                          samples_per_cycle: int = GRAZING_SAMPLES) -> float:
    """The minimum gap over the free flights of one period (+inf if none approaches)."""
    minima = clearance_minima(smap, state, k, samples_per_cycle=samples_per_cycle)
    free = minima[minima[:, 1] >= 0.0, 1]
    return float(free.min()) if free.size else float("inf")
