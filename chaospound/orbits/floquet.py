"""Exact Floquet exponents of a periodic response, for ``classify`` and the Lyapunov report.

A steady response found periodic (period P forcing cycles) is a stable
fixed point of P^P, the stroboscopic map iterated P times. Its Lyapunov
exponents are then exactly the Floquet exponents log|mu_i| / (P T) of that
orbit, mu_i the eigenvalues of its monodromy matrix; a QR estimate over a
finite run only approaches them (slowly when two multipliers are close in
modulus: docs/orbits.md). :func:`response_floquet` solves the orbit by Newton
shooting (:mod:`chaospound.orbits.shooting`, residual 1e-10 relative to the
state scale, rtol 1e-12, the response's own scheme: :func:`response_map`) from a
section state of the response and reports its multipliers and exponents.

Which monodromy:

* the variational ("propagator") engine by default: exact up to the
  integration tolerance;
* a composition whose tangent dynamics the engine refuses
  (:func:`chaospound.engine.compose.check_tangent`: a point contact whose
  Jacobian is singular at onset, Jankowski's on the wall and pair models; a
  law with per-episode memory on a model that does not carry its
  sensitivity) falls back on the 5-point finite-difference monodromy
  (:func:`finite_difference_monodromy`, about 1e-8 relative), which
  differentiates the map itself. The laws with memory (hertzdamp,
  hunt_crossley) on the pounding models and Kelvin-Voigt's jumping force on
  the point models (its saltation matrix) are variational. With the
  finite difference and a law with memory the result holds only when no
  contact episode spans a section: the memory (the onset velocity) is then
  rewritten by every run before it is used; otherwise the map also depends
  on a memory that is not in the state, and the report says so (``exact``
  False, ``note``).

The report says whether the orbit confirms the response: Newton converged
near the start (within ``CONFIRM_DISTANCE`` of the state scale), with the
same impacts per period and, for a response classified with corners, the
same corner sequence (up to rotation), and all multipliers inside the unit
circle.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

import numpy as np

from ..dynamics.system import SimulationError, System, as_system
from ..scene import Scene
from .maps import ORBIT_METHOD, StroboscopicMap, finite_difference_monodromy, state_scale
from .shooting import Orbit, OrbitNotFound, minimal_period, newton_fixed_point, orbit_at

__all__ = ["FloquetReport", "detect_period", "response_floquet", "spectrum_floquet"]

#: the orbit confirms the response when Newton moved the start by less than this
#: (relative to max(1, |x|_inf)); a converged response is within ~1e-5 of its orbit
CONFIRM_DISTANCE = 1e-3
NEWTON_ITERATIONS = 12  #: Newton iterations allowed from a converged response


def response_map(system: System, **options) -> StroboscopicMap:
    """The stroboscopic map a response's orbit is solved on: orbit tolerances (rtol
    1e-12, atol 1e-14), the response's own scheme (a fixed-step one: dop853).

    Not the orbit tools' dop853 (:data:`~chaospound.orbits.maps.ORBIT_METHOD`): from a
    converged response Newton takes one or two iterations, whose monodromy runs
    dopri5's variational engine for n >= 4 states anyway
    (:func:`~chaospound.orbits.maps.variational_monodromy`), so the response's scheme
    costs a few milliseconds more and spares compiling a second scheme's engines (about
    4 s each) on the first ``classify`` or ``lyapunov`` of a composition. Measured
    (:func:`detect_period` then :func:`response_floquet` from 300 cycles of transient,
    best of 5, warm caches; dop853 against dopri5): fig3a 19.0 against 22.1 ms, fig4
    at T/T_Ax 0.95 (P = 2) 29.1 against 34.8 ms, fig4-translational at 0.7 5.0 against
    7.9 ms, the wall 3.8 against 6.1 ms; the largest multipliers agree to 1e-11.
    """
    method = ORBIT_METHOD if system.method == "rk4" else None
    return StroboscopicMap.of(system, method=method, **options)


@dataclass(frozen=True)
class FloquetReport:
    """The Floquet data of a periodic response, or why there are none.

    Attributes
    ----------
    period : int
        P, in forcing cycles.
    found : bool
        Newton converged to a periodic orbit.
    multipliers : ndarray (n,) complex
        Eigenvalues of the monodromy of P cycles, by decreasing modulus
        (empty when not found).
    exponents : ndarray (n,)
        log|mu| / (P T), per unit normalised time, descending.
    forcing_period : float
        T.
    method : str
        "variational" (exact: the propagator engine) or "finite-difference"
        (5-point stencil, about 1e-8 relative), or "" when not found.
    exact : bool
        The exponents are the response's exact Lyapunov exponents: orbit
        found, confirmed, and its monodromy valid (see the module docstring).
    confirmed : bool
        The orbit is the response: near the start, same impacts (and corners),
        stable.
    stable : bool
        max |mu| < 1.
    residual : float
        Newton's relative residual.
    iterations : int
    distance : float
        |x_orbit - x_start|_inf / max(1, |x|_inf).
    note : str
        Why a fallback was used, why the orbit does not confirm the response,
        or why Newton failed.
    orbit : Orbit or None
    minimal_period : int
        The orbit's own period in forcing cycles, a divisor of ``period``
        (:func:`~chaospound.orbits.shooting.minimal_period`): smaller where Newton found
        a shorter orbit (the response then still approaches it, and the orbit does not
        confirm it); 0 when not found.
    """

    period: int
    found: bool
    multipliers: np.ndarray
    exponents: np.ndarray
    forcing_period: float
    method: str = ""
    exact: bool = False
    confirmed: bool = False
    stable: bool = False
    residual: float = float("nan")
    iterations: int = 0
    distance: float = float("nan")
    note: str = ""
    orbit: Orbit | None = None
    minimal_period: int = 0

    @property
    def max_exponent(self) -> float | None:
        return float(self.exponents[0]) if self.found else None

    @property
    def per_cycle(self) -> np.ndarray:
        """Exponents per forcing cycle (times T)."""
        return self.exponents * self.forcing_period

    def to_json_dict(self) -> dict:
        """JSON-ready summary (the ``floquet`` evidence of ``classify``)."""
        return {
            "period_cycles": self.period,
            "found": self.found,
            "exact": self.exact,
            "confirmed": self.confirmed,
            "stable": self.stable,
            "method": self.method,
            "multipliers": [{"re": float(z.real), "im": float(z.imag), "abs": float(abs(z))}
                            for z in self.multipliers],
            "exponents": [float(e) if np.isfinite(e) else None for e in self.exponents],
            "residual": float(self.residual),
            "iterations": int(self.iterations),
            "distance": float(self.distance),
            "minimal_period": int(self.minimal_period),
            "note": self.note,
        }


def _failed(period: int, forcing_period: float, note: str) -> FloquetReport:
    empty = np.zeros(0)
    return FloquetReport(period=period, found=False, multipliers=empty.astype(complex),
                         exponents=empty, forcing_period=forcing_period, note=note)


def tangent_refusal(system: System) -> str | None:
    """Why the engine refuses a variational monodromy for this system (None if it does not)."""
    from ..engine.compose import check_tangent

    try:
        check_tangent(system.composition.with_tangent("propagator"))
    except ValueError as exc:
        return str(exc).split(";")[0]
    return None


def _memory_law(system: System) -> bool:
    from ..engine.compose import LAWS

    if system.scene is None or system.law not in LAWS:
        return False
    return bool(importlib.import_module(LAWS[system.law]).MEMORY)


def _contact_spans_section(smap: StroboscopicMap, x: np.ndarray, k: int) -> bool:
    """A contact episode of the orbit through x is under way at one of its sections."""
    from ..simulate import simulate

    run = simulate(smap.system, transient=0, record=int(k), initial_state=x,
                   start_at_section=True)
    onset, end = run.impacts.time, run.impacts.time + run.impacts.duration
    sections = run.strobe.time[1:]
    return bool(np.any((onset[:, None] < sections[None, :]) & (sections[None, :] < end[:, None])))


def _same_cycle_of_corners(a: tuple[str, ...] | list[str], b: tuple[str, ...]) -> bool:
    a, b = list(a), list(b)
    if len(a) != len(b):
        return False
    return not a or any(b[i:] + b[:i] == a for i in range(len(b)))


def response_floquet(system_or_scene: System | Scene, state: np.ndarray, period: int, *,
                     impacts_per_period: int | None = None,
                     corner_sequence: tuple[str, ...] | list[str] | None = None,
                     max_iter: int = NEWTON_ITERATIONS) -> FloquetReport:
    """Solve the periodic orbit of a periodic response and report its Floquet exponents.

    Parameters
    ----------
    system_or_scene : System or Scene
        The system as analysed (its own tolerances are replaced by the orbit
        solver's, rtol 1e-12 and atol 1e-14: :func:`response_map`).
    state : ndarray (n,)
        A section state of the converged response (the start of Newton).
    period : int
        P, the response's period in forcing cycles.
    impacts_per_period, corner_sequence : optional
        What the response showed; the orbit confirms it only if it has the same
        (corners up to a rotation: the section may cut the group elsewhere).
    max_iter : int
        Newton iterations allowed.

    Returns
    -------
    FloquetReport
        Never raises for a failed Newton or integration: ``found`` False and
        ``note`` say why.
    """
    system = as_system(system_or_scene)
    k = int(period)
    x0 = np.asarray(state, dtype=np.float64).ravel()
    refused = tangent_refusal(system)
    notes = []
    if refused is None:
        smap = response_map(system)
        method = "variational"
    else:
        smap = response_map(system, monodromy_provider=finite_difference_monodromy)
        method = "finite-difference"
        notes.append(f"finite-difference monodromy: {refused}")
    try:
        x, m, res, it = newton_fixed_point(smap, x0, k, max_iter=max_iter)
        orbit = orbit_at(smap, x, k, m, res, it)
    except (OrbitNotFound, SimulationError) as exc:
        note = f"no orbit: {exc}"
        if method == "finite-difference" and _memory_law(system):
            try:
                if _contact_spans_section(smap, x0, k):
                    note += (f" (a contact episode spans a section: the map depends on the "
                             f"{system.law} law's onset velocity, memory not in the state)")
            except SimulationError:
                pass
        return _failed(k, system.period, note)
    distance = float(np.max(np.abs(x - x0))) / state_scale(x)
    reasons = []
    if distance > CONFIRM_DISTANCE:
        reasons.append(f"Newton moved {distance:.2g} of the state scale from the response")
    if impacts_per_period is not None and orbit.impacts_per_period != impacts_per_period:
        reasons.append(f"the orbit has {orbit.impacts_per_period} impacts per period, the "
                       f"response {impacts_per_period}")
    elif corner_sequence is not None and not _same_cycle_of_corners(corner_sequence,
                                                                    orbit.corners):
        reasons.append(f"the orbit's corners {' '.join(orbit.corners)} differ from the "
                       f"response's {' '.join(corner_sequence)}")
    if not orbit.stable:
        reasons.append(f"the orbit is unstable (max |mu| = {abs(orbit.multipliers[0]):.6g})")
    shortest = minimal_period(smap, x, k)
    if shortest < k:
        reasons.append(f"the orbit repeats after {shortest} cycles, not {k}: the response "
                       "still approaches it")
    confirmed = not reasons
    valid = True
    if method == "finite-difference" and _memory_law(system) and \
            _contact_spans_section(smap, x, k):
        valid = False
        notes.append(f"a contact episode spans a section: the map also depends on the "
                     f"{system.law} law's onset velocity (memory not in the state), which "
                     "the finite differences hold fixed")
    notes += reasons
    return FloquetReport(period=k, found=True, multipliers=orbit.multipliers,
                         exponents=orbit.exponents, forcing_period=system.period,
                         method=method, exact=confirmed and valid, confirmed=confirmed,
                         stable=orbit.stable, residual=orbit.residual,
                         iterations=orbit.iterations, distance=distance,
                         note="; ".join(notes), orbit=orbit, minimal_period=shortest)


def detect_period(system_or_scene: System | Scene, state: np.ndarray, *, max_period: int = 16,
                  tol: float = 1e-6) -> tuple[int | None, np.ndarray]:
    """The period of the response through a section state, at orbit-work tolerances.

    Runs ``3 max_period`` cycles from ``state`` (:func:`response_map`) and returns
    the smallest P <= max_period whose last max(2P, 10) section pairs P apart
    agree within ``tol`` (relative to max(1, |x|_inf)), with the last section
    (the start for Newton); (None, last section) when no P does.
    """
    from ..simulate import simulate

    smap = response_map(as_system(system_or_scene))
    cycles = 3 * int(max_period) + 1
    run = simulate(smap.system, transient=0, record=cycles, initial_state=state,
                   start_at_section=True)
    sections = run.strobe.state
    last = sections.shape[0] - 1
    scale = state_scale(sections[-1])
    for p in range(1, int(max_period) + 1):
        pairs = max(2 * p, 10)
        if last < pairs + p:
            break
        tail = sections[last - pairs - p + 1:]
        if float(np.max(np.abs(tail[p:] - tail[:-p]))) <= tol * scale:
            return p, sections[-1].copy()
    return None, sections[-1].copy()



def spectrum_floquet(system_or_scene: System | Scene, spectrum, *,
                     max_period: int = 16) -> FloquetReport | None:
    """The exact Floquet exponents beside a QR Lyapunov spectrum, if the response is periodic.

    Parameters
    ----------
    system_or_scene : System or Scene
        The system the spectrum was computed for.
    spectrum : chaospound.dynamics.lyapunov.Spectrum
        Its ``final_state`` (the last section of the QR run) starts
        :func:`detect_period` and then Newton.
    max_period : int
        Longest period looked for, in forcing cycles.

    Returns
    -------
    FloquetReport or None
        None when the response has no period up to ``max_period`` (the QR
        estimate then stands alone); otherwise the orbit's report (``exact``
        says whether its exponents are the response's exact exponents).
    """
    if spectrum.final_state is None:
        return None
    try:
        period, state = detect_period(system_or_scene, spectrum.final_state,
                                      max_period=max_period)
    except SimulationError:
        return None
    if period is None:
        return None
    return response_floquet(system_or_scene, state, period)
