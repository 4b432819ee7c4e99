"""Periodic orbits by Newton shooting on the stroboscopic map, with Floquet multipliers.

A period-k orbit (k forcing periods) is a fixed point of P^k, solved by
Newton's method on F(x) = P^k(x) - x with the Jacobian M - I, M the
monodromy matrix of the map's provider (:mod:`chaospound.orbits.maps`) at the
looser tolerance of :meth:`StroboscopicMap.approximate_monodromy`, kept from
an earlier iterate while the residual falls at least twofold per iteration
(chord steps: one run of k periods each instead of a matrix); the exact matrix
is evaluated once, at the converged state.
Safeguards: the Newton step is cut to a trust radius (``trust`` times the
state scale max(1, |x|_inf)) and then backtracked (halved) until the residual
decreases; converged when |F|_inf <= tol * max(1, |x|_inf) (default 1e-10).
The multipliers are the eigenvalues of that exact M, the Floquet exponents
log|mu| / (k T) per unit normalised time.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..dynamics.system import SimulationError
from ..physics.corners import CORNER_LABELS
from ..scene import Scene
from .maps import StroboscopicMap, state_scale

__all__ = ["Orbit", "OrbitNotFound", "find_orbit", "minimal_period", "newton_fixed_point",
           "orbit_at", "orbit_trajectory"]

ORBIT_TOL = 1e-10  #: default residual, relative to max(1, |x|_inf)
#: a fixed point of P^k repeats after d | k cycles when its sections d apart agree to
#: this, relative to max(1, |x|_inf): far above an orbit's residual (1e-10), far below
#: the spread of a period-doubled orbit's sections except right at its doubling (the
#: spread grows as the square root of the distance from it)
MINIMAL_PERIOD_TOL = 1e-7


class OrbitNotFound(SimulationError):
    """Newton's method did not converge to a periodic orbit (one-line message)."""


@dataclass(frozen=True)
class Orbit:
    """A periodic orbit of the stroboscopic map and its Floquet data.

    Attributes
    ----------
    parameter : str or None
        Name of the map's parameter.
    value : float
        Its value (NaN without a parameter).
    period : int
        k, in forcing periods.
    forcing_period : float
        T (normalised time, t = tau omega_Ax for the pounding models).
    state : ndarray (n,)
        State at the section (units of the model's states, e.g. A_g and
        A_g omega_Ax).
    state_names : tuple of str
    multipliers : ndarray (n,) complex
        Floquet multipliers, eigenvalues of M = d P^k / d x, by decreasing modulus.
    monodromy : ndarray (n, n)
    impact_velocity : ndarray
        Relative impact velocities of the impacts in one period of the orbit
        (k forcing periods), in onset order (A_g omega_Ax).
    impact_phase : ndarray
        Their onset phases (t - t0) / T - cycle, in [0, 1).
    impact_cycle : ndarray of int
        The forcing cycle (0 .. k-1) of each onset.
    corners : tuple of str
        Corner labels of the impacts ("face", "A+", ...).
    residual : float
        |P^k(x) - x|_inf / max(1, |x|_inf) at the returned state.
    iterations : int
        Newton iterations.
    """

    parameter: str | None
    value: float
    period: int
    forcing_period: float
    state: np.ndarray
    state_names: tuple[str, ...]
    multipliers: np.ndarray
    monodromy: np.ndarray = field(repr=False)
    impact_velocity: np.ndarray
    impact_phase: np.ndarray
    impact_cycle: np.ndarray
    corners: tuple[str, ...]
    residual: float
    iterations: int

    @property
    def exponents(self) -> np.ndarray:
        """Floquet exponents log|mu| / (k T), per unit normalised time, descending."""
        with np.errstate(divide="ignore"):
            return np.log(np.abs(self.multipliers)) / (self.period * self.forcing_period)

    @property
    def stable(self) -> bool:
        """All multipliers strictly inside the unit circle."""
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    @property
    def impacts_per_period(self) -> int:
        return int(self.impact_velocity.shape[0])

    @property
    def label(self) -> str:
        """"n-k": impacts per period and period in forcing cycles (as the regimes)."""
        return f"{self.impacts_per_period}-{self.period}"

    def to_json_dict(self) -> dict:
        """JSON-ready summary (``chaospound orbit --json``)."""
        mu = self.multipliers
        return {
            "parameter": self.parameter,
            "value": None if not np.isfinite(self.value) else self.value,
            "period_cycles": self.period,
            "forcing_period": self.forcing_period,
            "state_names": list(self.state_names),
            "state": self.state.tolist(),
            "multipliers": [{"re": float(z.real), "im": float(z.imag), "abs": float(abs(z))}
                            for z in mu],
            "floquet_exponents": [float(e) if np.isfinite(e) else None
                                  for e in self.exponents],
            "stable": self.stable,
            "impacts_per_period": self.impacts_per_period,
            "label": self.label,
            "corners": list(self.corners),
            "impact_velocities": self.impact_velocity.tolist(),
            "impact_phases": self.impact_phase.tolist(),
            "impact_cycles": self.impact_cycle.tolist(),
            "residual": self.residual,
            "iterations": self.iterations,
        }


def newton_fixed_point(smap: StroboscopicMap, x0: np.ndarray, k: int = 1, *,
                       tol: float = ORBIT_TOL, max_iter: int = 40, trust: float = 1.0,
                       chord: bool = True, exact_monodromy: bool = True,
                       give_up_early: bool = False,
                       ) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Solve P^k(x) = x by safeguarded Newton's method.

    Parameters
    ----------
    smap : StroboscopicMap
    x0 : ndarray (n,)
        Starting section state.
    k : int
        Period in forcing cycles.
    tol : float
        Converged when |P^k(x) - x|_inf <= tol * max(1, |x|_inf).
    max_iter : int
        Newton iterations allowed.
    trust : float
        Largest step, relative to max(1, |x|_inf) (inf-norm).
    chord : bool
        Keep the monodromy of an earlier iterate while the residual falls at least
        twofold per iteration (the chord method: one run of k periods per iteration
        instead of a whole matrix), and evaluate it afresh when it does not. The
        matrices of the iterations are then the map's approximate ones
        (:meth:`StroboscopicMap.approximate_monodromy`, looser tolerances: their
        error only slows the chord steps' linear convergence, of rate about
        |M_used - M(x*)|); the returned matrix is always the map's own, evaluated at
        the returned state. Without ``chord`` every iteration evaluates the exact
        matrix (plain Newton).
    exact_monodromy : bool
        Return the map's own matrix at the fixed point (default); False: its
        approximate one there (:meth:`StroboscopicMap.approximate_monodromy`, about
        half the cost; multipliers to about its rtol), for a caller that needs only
        the orbit's stability.
    give_up_early : bool
        For a caller that only asks whether an orbit is near (the converged
        classification): a chord step (a matrix of an earlier iterate) that does not
        decrease the residual is not searched along but retried at once with a fresh
        matrix, and a line search along a fresh matrix's step that finds no decrease
        down to a step of 1e-3 raises :class:`OrbitNotFound` (near a torus or a chaotic
        set there is no fixed point for Newton to descend to; without this option such
        an attempt spends its ``max_iter`` iterations at about ten runs of k periods
        each). Default False: every iteration searches its step, as before.

    Returns
    -------
    x, M, residual, iterations
        Fixed point, monodromy there, relative residual, iterations used.

    Raises
    ------
    OrbitNotFound
        No convergence, a singular M - I, or a failed integration on the way.
    """
    x = np.array(x0, dtype=np.float64)
    n = x.shape[0]
    eye = np.eye(n)
    res = float("nan")
    try:
        if chord:
            xk, m, fresh = smap.advance(x, k), None, False
        else:
            (xk, m), fresh = smap.monodromy(x, k), True
        m_here = m is not None  # m was evaluated at the current x
        for it in range(max_iter + 1):
            f = xk - x
            res = float(np.max(np.abs(f))) / state_scale(x)
            if not np.isfinite(res):
                raise OrbitNotFound(f"period-{k} orbit: the residual became non-finite at "
                                    f"iteration {it}")
            if res <= tol:
                if not fresh:
                    _, m = (smap.monodromy if exact_monodromy
                            else smap.approximate_monodromy)(x, k)
                return x, m, res, it
            if it == max_iter:
                break
            if m is None:
                _, m = smap.approximate_monodromy(x, k)
                m_here = True
            try:
                dx = np.linalg.solve(m - eye, -f)
            except np.linalg.LinAlgError:
                raise OrbitNotFound(f"period-{k} orbit: M - I is singular at iteration {it} "
                                    f"(residual {res:.2e}); a multiplier is 1 (fold)") from None
            radius = trust * state_scale(x)
            size = float(np.max(np.abs(dx)))
            if size > radius:
                dx *= radius / size
            norm0 = float(np.max(np.abs(f)))
            stale = not m_here  # a chord step: the matrix of an earlier iterate
            alpha = 1.0
            while True:
                x_try = x + alpha * dx
                try:
                    xk_try = smap.advance(x_try, k)
                    norm = float(np.max(np.abs(xk_try - x_try)))
                except SimulationError:
                    norm = np.inf
                descent = norm < (1.0 - 0.25 * alpha) * norm0
                if descent or alpha < 1e-3 or (give_up_early and stale):
                    break
                alpha *= 0.5
            if give_up_early and not descent:
                if not stale:
                    raise OrbitNotFound(f"period-{k} orbit: no descent along Newton's step at "
                                        f"iteration {it} (relative residual {res:.2e})")
                m = None  # retry from x with a fresh matrix
                continue
            if not np.isfinite(norm):
                raise OrbitNotFound(f"period-{k} orbit: the integration failed along the "
                                    f"Newton step at iteration {it}")
            x, xk, fresh, m_here = x_try, xk_try, False, False
            if not chord:
                xk, m = smap.monodromy(x, k)
                fresh = m_here = True
            elif norm > 0.5 * norm0:
                m = None  # slow: an approximate matrix at the new iterate
    except OrbitNotFound:
        raise
    except SimulationError as exc:
        raise OrbitNotFound(f"period-{k} orbit: integration failed ({exc})") from None
    raise OrbitNotFound(f"period-{k} orbit: no convergence in {max_iter} Newton iterations "
                        f"(relative residual {res:.2e} > {tol:.0e}); try a longer transient "
                        "or another period")


def orbit_at(smap: StroboscopicMap, x: np.ndarray, k: int, m: np.ndarray, residual: float,
             iterations: int) -> Orbit:
    """The :class:`Orbit` record of a converged fixed point: multipliers and impacts."""
    mu = np.linalg.eigvals(m)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    velocity, phase, cycle, corners = orbit_impacts(smap, x, k)
    system = smap.system
    return Orbit(parameter=smap.parameter, value=smap.value, period=int(k),
                 forcing_period=system.period, state=np.array(x, dtype=np.float64),
                 state_names=tuple(system.state_names), multipliers=mu, monodromy=m,
                 impact_velocity=velocity, impact_phase=phase, impact_cycle=cycle,
                 corners=corners, residual=float(residual), iterations=int(iterations))


def minimal_period(smap: StroboscopicMap, x: np.ndarray, k: int,
                   tol: float = MINIMAL_PERIOD_TOL) -> int:
    """The smallest d dividing k with P^d(x) = x, for a fixed point x of P^k.

    Newton's method on P^k(x) = x converges to any orbit whose period divides k: from
    the slow approach to a period-1 orbit whose multiplier is near -1, whose sections
    alternate for hundreds of cycles and so look period-2, it finds the period-1
    orbit. This tells which.

    Parameters
    ----------
    smap : StroboscopicMap
        The map (its system and tolerances run the k cycles).
    x : ndarray (n,)
        A fixed point of P^k (model units).
    k : int
        Its period as solved, in forcing cycles.
    tol : float
        Sections d apart agree when their largest difference is at most ``tol``
        times max(1, |x|_inf).

    Returns
    -------
    int
        d, the orbit's period in forcing cycles (k when no proper divisor repeats).
    """
    from ..simulate import simulate

    k = int(k)
    divisors = [d for d in range(1, k) if k % d == 0]
    if not divisors:
        return k
    sections = simulate(smap.system, transient=0, record=max(divisors), initial_state=x,
                        start_at_section=True).strobe.state
    scale = state_scale(x)
    for d in divisors:
        if float(np.max(np.abs(sections[d] - sections[0]))) <= tol * scale:
            return d
    return k


def orbit_impacts(smap: StroboscopicMap, x: np.ndarray, k: int):
    """Impacts in one period (k forcing cycles) of the orbit through the section state x.

    Returns (velocity, phase, cycle, corner labels), from
    :func:`chaospound.simulate.simulate` started at the section with the map's
    tolerances.
    """
    from ..simulate import simulate

    run = simulate(smap.system, transient=0, record=int(k), initial_state=x,
                   start_at_section=True)
    imp = run.impacts
    return (imp.velocity.copy(), imp.phase.copy(), imp.cycle.astype(np.int64).copy(),
            tuple(CORNER_LABELS[int(c)] for c in imp.corner))


def find_orbit(obj: StroboscopicMap | Scene | object, *, period: int = 1,
               initial_state: np.ndarray | None = None, transient: int | None = None,
               tol: float = ORBIT_TOL, max_iter: int = 40) -> Orbit:
    """Find a period-k orbit by Newton shooting and report its Floquet data and impacts.

    Parameters
    ----------
    obj : StroboscopicMap, System or Scene
        A System or Scene is wrapped by :meth:`StroboscopicMap.of` (rtol 1e-12,
        atol 1e-14, dop853).
    period : int
        k, forcing periods per orbit period (>= 1).
    initial_state : ndarray, optional
        Starting section state; default: the state after ``transient`` periods
        from the system's initial state.
    transient : int, optional
        Periods run first when no initial state is given (default: the
        system's, e.g. the scene's run.transient).
    tol : float
        Relative residual |P^k(x) - x|_inf / max(1, |x|_inf) to reach.
    max_iter : int
        Newton iterations allowed.

    Returns
    -------
    Orbit

    Raises
    ------
    OrbitNotFound
        Newton did not converge (one line, with the residual reached).
    ValueError
        period < 1 or a malformed initial state.
    """
    smap = obj if isinstance(obj, StroboscopicMap) else StroboscopicMap.of(obj)
    k = int(period)
    if k < 1:
        raise ValueError(f"period = {period}: need an integer >= 1")
    if initial_state is None:
        x0 = smap.start_state(transient)
    else:
        x0 = np.asarray(initial_state, dtype=np.float64).ravel()
        if x0.shape != (smap.dim,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"initial_state has shape {x0.shape}: need {smap.dim} finite "
                             "values")
    x, m, res, it = newton_fixed_point(smap, x0, k, tol=tol, max_iter=max_iter)
    return orbit_at(smap, x, k, m, res, it)


def orbit_trajectory(smap: StroboscopicMap, orbit: Orbit, samples_per_cycle: int = 200):
    """One period of the orbit as a dense trajectory (and its impacts).

    Parameters
    ----------
    smap : StroboscopicMap
        The map the orbit was found with (at the orbit's parameter value).
    orbit : Orbit
    samples_per_cycle : int
        Samples per forcing cycle (>= 1).

    Returns
    -------
    chaospound.simulate.Simulation
        ``trajectory.time`` (normalised time from the section) and
        ``trajectory.state`` over k forcing cycles, ``impacts`` of that period.
    """
    from ..simulate import simulate

    if samples_per_cycle < 1:
        raise ValueError(f"samples_per_cycle = {samples_per_cycle}: need >= 1")
    return simulate(smap.system, transient=0, record=orbit.period, initial_state=orbit.state,
                    start_at_section=True, samples_per_cycle=int(samples_per_cycle))
