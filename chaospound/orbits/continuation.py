"""Pseudo-arclength continuation of periodic orbits and their bifurcation points.

Unknowns y = (x, lambda): the section state of a period-k orbit and the
parameter. The branch is the solution curve of G(x, lambda) = P^k(x; lambda) - x
= 0, followed by Keller's pseudo-arclength method:

* tangent t: the unit null vector of [M - I, dP^k/dlambda], oriented by the
  bordered system [[M - I, P_lambda], [t_prev^T]] t = [0, 1] (so t . t_prev > 0
  and folds are passed: the parameter component of t changes sign, the
  direction along the curve does not);
* predictor y_p = y + ds t; corrector: Newton on
  [G(y); t . (y - y_p)] = 0 with the bordered Jacobian, converged when
  |G|_inf <= tol * max(1, |x|_inf);
* step control: ds halved on a failed corrector or a turn of more than
  ``max_turn`` between consecutive tangents, grown by 1.5 after a corrector
  that converged in at most 2 iterations, kept in [ds_min, ds_max] (by
  default ds_max grows with the current point's state scale); the run
  stops after ``max_steps`` points, below ds_min, or on the parameter
  interval's edge (the last point is solved at the edge's value).

Test functions between consecutive points (docs/orbits.md):

* fold: sign change of the tangent's parameter component; located on the
  root of det(M - I) (a real multiplier through +1);
* period doubling: sign change of det(M + I) (a real multiplier through -1);
* Neimark-Sacker: the number of complex multipliers outside the unit circle
  changes; located on |mu| - 1 of the complex multiplier nearest the circle;
* grazing: the impacts per period change (an impact's velocity went to 0, or
  the minimum gap of a free flight touched 0); located by regula falsi on the
  local minimum of the clearance nearest zero (:mod:`.grazing`, dense output,
  signed: negative inside a contact) when it changes sign between the points,
  else by bisection on the change; a change of the corner sequence alone
  ("corner-change") by bisection.

Every location solves the orbit again on the pseudo-arclength hyperplane
y_a + s t_a (the same corrector) and brackets the root in s by the Illinois
variant of regula falsi (bisection for grazing), until the bracket's
parameter values agree to ``locate_tol`` (1e-9 by default).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..dynamics.system import SimulationError, System
from ..scene import Scene
from .grazing import grazing_test
from .maps import StroboscopicMap, state_scale
from .shooting import ORBIT_TOL, Orbit, OrbitNotFound, find_orbit, newton_fixed_point, orbit_at

__all__ = [
    "Branch",
    "SpecialPoint",
    "continue_branch",
    "continue_from",
    "switch_period_doubling",
]

SPECIAL_KINDS = ("fold", "period-doubling", "neimark-sacker", "grazing", "corner-change")
LOCATE_TOL = 1e-9  #: bracket width in the parameter at which a location stops


@dataclass(frozen=True)
class SpecialPoint:
    """A bifurcation point located on a branch.

    Attributes
    ----------
    kind : str
        "fold", "period-doubling", "neimark-sacker", "grazing" (impacts per
        period change) or "corner-change" (same count, other corners).
    value : float
        Parameter value.
    orbit : Orbit
        The orbit solved at the located point.
    index : int
        The point lies between the branch's points ``index - 1`` and ``index``.
    bracket : float
        Width of the final bracket in the parameter (the location's accuracy).
    test : float
        The test function's value there (grazing: the clearance's minimum, in
        the model's length unit; NaN for a corner change).
    eigenvector : ndarray or None
        Eigenvector of the critical multiplier (fold, period doubling).
    note : str
        What changed, e.g. "2 -> 1 impacts per period".
    """

    kind: str
    value: float
    orbit: Orbit
    index: int
    bracket: float
    test: float = float("nan")
    eigenvector: np.ndarray | None = field(default=None, repr=False)
    note: str = ""


@dataclass
class Branch:
    """A continued branch of period-k orbits.

    Attributes
    ----------
    parameter : str
    period : int
    orbits : list of Orbit
        In the order of the curve.
    special : list of SpecialPoint
    name : str
        Label ("period-1", "period-2 from PD at 0.812", ...).
    stop_reasons : list of str
        Why each direction stopped.
    """

    parameter: str
    period: int
    orbits: list[Orbit]
    special: list[SpecialPoint] = field(default_factory=list)
    name: str = ""
    stop_reasons: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.orbits)

    @property
    def values(self) -> np.ndarray:
        return np.array([o.value for o in self.orbits])

    @property
    def states(self) -> np.ndarray:
        return np.array([o.state for o in self.orbits])

    @property
    def multipliers(self) -> np.ndarray:
        return np.array([o.multipliers for o in self.orbits])

    @property
    def stable(self) -> np.ndarray:
        return np.array([o.stable for o in self.orbits], dtype=bool)

    @property
    def impacts_per_period(self) -> np.ndarray:
        return np.array([o.impacts_per_period for o in self.orbits], dtype=np.int64)

    def of_kind(self, kind: str) -> list[SpecialPoint]:
        return [sp for sp in self.special if sp.kind == kind]


# ---------------------------------------------------------------- corrector
@dataclass
class _Point:
    """A converged point of the extended system with what the tests need."""

    smap: StroboscopicMap
    x: np.ndarray
    lam: float
    m: np.ndarray
    p_lam: np.ndarray
    residual: float
    iterations: int
    k: int
    orbit: Orbit | None = None
    _clearance: float | None = None

    @property
    def y(self) -> np.ndarray:
        return np.append(self.x, self.lam)

    def clearance(self) -> float:
        """The grazing test function: the clearance's local minimum nearest zero."""
        if self._clearance is None:
            self._clearance = grazing_test(self.smap, self.x, self.k)
        return self._clearance

    def get_orbit(self) -> Orbit:
        if self.orbit is None:
            self.orbit = orbit_at(self.smap, self.x, self.k, self.m, self.residual,
                                  self.iterations)
        return self.orbit


def _evaluate(base: StroboscopicMap, x: np.ndarray, lam: float, k: int, *,
              approximate: bool = False):
    """(map at lam, P^k(x), M, dP^k/dlam); with ``approximate`` M is the map's
    approximate monodromy (chord iterations), P^k(x) still the exact state."""
    smap = base.with_parameter(value=lam)
    if approximate and smap.jacobian_rtol is not None:
        xk = smap.advance(x, k)
        _, m = smap.approximate_monodromy(x, k)
    else:
        xk, m = smap.monodromy(x, k)
    p_lam = smap.parameter_derivative(x, k)
    return smap, xk, m, p_lam


def _correct(base: StroboscopicMap, y_pred: np.ndarray, t: np.ndarray, k: int, *,
             tol: float, max_iter: int = 8) -> _Point:
    """Newton on [P^k(x; lam) - x; t . (y - y_pred)] = 0 from y_pred.

    Chord iterations: the bordered Jacobian of the predicted point, with the map's
    approximate monodromy (:meth:`StroboscopicMap.approximate_monodromy`), is kept
    while the residual falls at least fourfold per iteration (one run of k periods
    each), and evaluated afresh otherwise; the converged point gets its own exact M
    and dP/dlambda (for the tangent and the test functions).
    """
    n = y_pred.shape[0] - 1
    y = y_pred.copy()
    eye = np.eye(n)
    last = np.inf
    smap, xk, m, p_lam = _evaluate(base, y[:n], float(y[n]), k, approximate=True)
    fresh = True  # the Jacobian was evaluated at the current y
    exact = smap.jacobian_rtol is None  # ... and with the exact M
    jac = None
    res = np.inf
    for it in range(max_iter + 1):
        g = xk - y[:n]
        res = float(np.max(np.abs(g))) / state_scale(y[:n])
        if not np.isfinite(res):
            raise OrbitNotFound("corrector: non-finite residual")
        if res <= tol:
            if not (fresh and exact):
                smap, _, m, p_lam = _evaluate(base, y[:n], float(y[n]), k)
            return _Point(smap, y[:n].copy(), float(y[n]), m, p_lam, res, it, k)
        if it == max_iter or (it >= 2 and res > 0.5 * last):
            break
        if not fresh and res > 0.25 * last:  # slow chord: a fresh Jacobian
            smap, xk, m, p_lam = _evaluate(base, y[:n], float(y[n]), k, approximate=True)
            fresh = True
        if fresh:
            jac = np.zeros((n + 1, n + 1))
            jac[:n, :n] = m - eye
            jac[:n, n] = p_lam
            jac[n] = t
        last = res
        rhs = np.append(-g, -float(t @ (y - y_pred)))
        try:
            y = y + np.linalg.solve(jac, rhs)
        except np.linalg.LinAlgError:
            break
        smap = base.with_parameter(value=float(y[n]))
        xk = smap.advance(y[:n], k)
        fresh = False
    raise OrbitNotFound(f"corrector: no convergence (relative residual {res:.2e})")


def _tangent(p: _Point, t_prev: np.ndarray) -> np.ndarray:
    """Unit null vector of [M - I, P_lam], oriented along t_prev (bordered system)."""
    n = p.x.shape[0]
    jac = np.zeros((n + 1, n + 1))
    jac[:n, :n] = p.m - np.eye(n)
    jac[:n, n] = p.p_lam
    jac[n] = t_prev
    rhs = np.zeros(n + 1)
    rhs[n] = 1.0
    try:
        t = np.linalg.solve(jac, rhs)
    except np.linalg.LinAlgError:
        t = _null_vector(p)
        t = t if t @ t_prev >= 0 else -t
    return t / np.linalg.norm(t)


def _null_vector(p: _Point) -> np.ndarray:
    n = p.x.shape[0]
    a = np.hstack([p.m - np.eye(n), p.p_lam[:, None]])
    return np.linalg.svd(a)[2][-1]


# ----------------------------------------------------------- test functions
def _fold_test(p: _Point) -> float:
    return float(np.linalg.det(p.m - np.eye(p.x.shape[0])))


def _pd_test(p: _Point) -> float:
    return float(np.linalg.det(p.m + np.eye(p.x.shape[0])))


def _complex_outside(p: _Point) -> int:
    mu = np.linalg.eigvals(p.m)
    return int(np.sum((np.abs(mu.imag) > 1e-9 * np.abs(mu)) & (np.abs(mu) > 1.0)))


def _ns_test(p: _Point) -> float:
    mu = np.linalg.eigvals(p.m)
    cplx = mu[np.abs(mu.imag) > 1e-9 * np.abs(mu)]
    if cplx.size == 0:
        return float("nan")
    mod = np.abs(cplx) - 1.0
    return float(mod[np.argmin(np.abs(mod))])


def _signature(o: Orbit) -> tuple:
    return (o.impacts_per_period, o.corners)


# ----------------------------------------------------------------- location
def _locate(base: StroboscopicMap, a: _Point, t_a: np.ndarray, b: _Point, k: int,
            test: Callable[[_Point], float] | None, *, tol: float, locate_tol: float,
            max_iter: int = 60, far_side: bool = False) -> tuple[_Point, float]:
    """Root of ``test`` (or, with None, the change of impact signature) between a and b.

    Points on the way solve the corrector on the hyperplane t_a . (y - y_a) = s.
    Returns the located point (with ``far_side``, or without a test, the bracket's
    end on b's side: for grazing, the orbit with the new impacts) and the final
    bracket width in the parameter.
    """
    s_lo, s_hi = 0.0, float(t_a @ (b.y - a.y))
    p_lo, p_hi = a, b
    if test is None:
        sig_lo = _signature(a.get_orbit())
        f_lo = f_hi = 0.0
    else:
        f_lo, f_hi = test(a), test(b)
    side = 0
    s_total = abs(s_hi)
    for _ in range(max_iter):
        # the parameter to locate_tol; the arclength too (to 1e-6 of the step), since at a
        # fold the parameter is stationary and would stop the search far from the root
        if abs(p_hi.lam - p_lo.lam) <= locate_tol and abs(s_hi - s_lo) <= 1e-6 * s_total:
            break
        if abs(s_hi - s_lo) <= 1e-14 * max(1.0, abs(s_hi)):
            break
        if test is None or not (np.isfinite(f_lo) and np.isfinite(f_hi)) or f_lo == f_hi:
            s = 0.5 * (s_lo + s_hi)
        else:
            s = s_lo - f_lo * (s_hi - s_lo) / (f_hi - f_lo)
            width = s_hi - s_lo
            # keep the secant away from the ends (a safeguarded regula falsi)
            s = min(max(s, s_lo + 0.02 * width), s_hi - 0.02 * width)
        try:
            p = _correct(base, a.y + s * t_a, t_a, k, tol=tol)
        except (OrbitNotFound, SimulationError):
            s = 0.5 * (s_lo + s_hi)
            try:
                p = _correct(base, a.y + s * t_a, t_a, k, tol=tol)
            except (OrbitNotFound, SimulationError):
                break
        if test is None:
            same = _signature(p.get_orbit()) == sig_lo
        else:
            f = test(p)
            if f == 0.0:
                return p, 0.0
            same = np.sign(f) == np.sign(f_lo)
        if same:
            s_lo, p_lo = s, p
            if test is not None:
                f_lo = f
                if side == -1:
                    f_hi *= 0.5  # Illinois: halve the stale end's value
                side = -1
        else:
            s_hi, p_hi = s, p
            if test is not None:
                f_hi = f
                if side == 1:
                    f_lo *= 0.5
                side = 1
    bracket = abs(p_hi.lam - p_lo.lam)
    if test is None or far_side:
        return p_hi, bracket  # the first point with the new impacts
    best = p_lo if abs(test(p_lo)) <= abs(test(p_hi)) else p_hi
    return best, bracket


def _critical_vector(m: np.ndarray, target: float) -> np.ndarray:
    mu, vecs = np.linalg.eig(m)
    j = int(np.argmin(np.abs(mu - target)))
    v = vecs[:, j]
    v = np.real(v) if np.all(np.abs(np.imag(v)) < 1e-12) else v
    return v / np.linalg.norm(v)


def _doubling_vertex(base: StroboscopicMap, sp: SpecialPoint) -> SpecialPoint | None:
    """A "fold" of a period-2m branch where it meets its period-m parent, relabelled.

    There the period-2m branch, lambda - lambda* ~ c a^2 in its amplitude a, turns at
    a pitchfork of P^2m (the parent's period doubling), not at a fold; the located
    point, found on det(M - I) = 0 where the two branches almost coincide, is accurate
    only to about c a^2 (3e-7 in T/T_Ax on fig4-translational). Recognised by a
    period-m orbit next to the point with a multiplier near -1.
    """
    from dataclasses import replace

    orbit = sp.orbit
    if orbit.period % 2:
        return None
    half = orbit.period // 2
    at = base.with_parameter(value=sp.value)
    try:
        x, m, _, _ = newton_fixed_point(at, orbit.state, half, max_iter=8)
    except (OrbitNotFound, SimulationError):
        return None
    if np.max(np.abs(x - orbit.state)) > 0.05 * state_scale(x):
        return None
    if np.min(np.abs(np.linalg.eigvals(m) + 1.0)) > 0.05:
        return None
    return replace(sp, kind="period-doubling",
                   note=f"vertex: the period-{orbit.period} branch meets its period-{half} "
                   "parent (a pitchfork of the doubled map; located to about c a^2)")


def _specials_between(base, a: _Point, t_a, b: _Point, t_b, k, *, tol, locate, locate_tol,
                      index: int) -> list[SpecialPoint]:
    """Detect (and locate) the bifurcations between consecutive points a and b."""
    found: list[SpecialPoint] = []

    def add(kind, test, target=None, note="", far_side=False):
        if locate:
            p, bracket = _locate(base, a, t_a, b, k, test, tol=tol, locate_tol=locate_tol,
                                 far_side=far_side)
        else:
            p, bracket = b, abs(b.lam - a.lam)
        vec = None if target is None else _critical_vector(p.m, target)
        value = test(p) if test is not None else float("nan")
        found.append(SpecialPoint(kind=kind, value=p.lam, orbit=p.get_orbit(), index=index,
                                  bracket=bracket, test=value, eigenvector=vec, note=note))

    if np.sign(t_a[-1]) != np.sign(t_b[-1]) and t_a[-1] != 0.0:
        add("fold", _fold_test, 1.0)
        vertex = _doubling_vertex(base, found[-1])
        if vertex is not None:
            found[-1] = vertex
    if np.sign(_pd_test(a)) != np.sign(_pd_test(b)):
        add("period-doubling", _pd_test, -1.0)
    if _complex_outside(a) != _complex_outside(b):
        add("neimark-sacker", _ns_test)
    oa, ob = a.get_orbit(), b.get_orbit()
    if _signature(oa) != _signature(ob):
        kind = "grazing" if oa.impacts_per_period != ob.impacts_per_period else "corner-change"
        note = (f"{oa.impacts_per_period} -> {ob.impacts_per_period} impacts per period, "
                f"corners {' '.join(oa.corners) or '-'} -> {' '.join(ob.corners) or '-'}")
        test = None
        if kind == "grazing" and _clearance_changes_sign(a, b):
            test = _Point.clearance  # a free flight's minimum gap through zero
            note += "; located on the clearance's minimum"
        add(kind, test, note=note, far_side=True)
    return found


def _clearance_changes_sign(a: _Point, b: _Point) -> bool:
    try:
        ca, cb = a.clearance(), b.clearance()
    except SimulationError:
        return False
    return bool(np.isfinite(ca) and np.isfinite(cb) and np.sign(ca) != np.sign(cb))


# ------------------------------------------------------------------- driver
def _run_direction(base: StroboscopicMap, start: _Point, t0: np.ndarray, k: int,
                   lo: float, hi: float, *, ds: float, ds_min: float, ds_max: float,
                   per_scale: bool, max_steps: int, tol: float, detect: bool, locate: bool,
                   locate_tol: float, max_turn: float,
                   progress: Callable[[str], None] | None):
    points, tangents, specials = [start], [t0], []
    cos_turn = np.cos(np.radians(max_turn))
    while len(points) < max_steps:
        a, t_a = points[-1], tangents[-1]
        try:
            b = _correct(base, a.y + ds * t_a, t_a, k, tol=tol)
            t_b = _tangent(b, t_a)
            if float(t_b @ t_a) < cos_turn and ds > ds_min:
                raise OrbitNotFound("turn too sharp")
        except (OrbitNotFound, SimulationError):
            ds *= 0.5
            if ds < ds_min:
                reason = f"step size below ds_min = {ds_min:.3g} at {base.parameter} = {a.lam:.10g}"
                break
            continue
        if not lo <= b.lam <= hi:
            edge = hi if b.lam > hi else lo
            reason = f"reached {base.parameter} = {edge:g}"
            if abs(edge - a.lam) <= 1e-12 * max(1.0, abs(edge)):
                break  # already on the edge (a start at the interval's end)
            try:
                x0 = a.x + (b.x - a.x) * (edge - a.lam) / (b.lam - a.lam)
                smap = base.with_parameter(value=edge)
                x, m, res, it = newton_fixed_point(smap, x0, k, tol=tol)
                e = _Point(smap, x, edge, m, smap.parameter_derivative(x, k), res, it, k)
                t_e = _tangent(e, t_a)
                if detect:
                    specials += _specials_between(base, a, t_a, e, t_e, k, tol=tol,
                                                  locate=locate, locate_tol=locate_tol,
                                                  index=len(points))
                points.append(e)
                tangents.append(t_e)
            except (OrbitNotFound, SimulationError):
                pass
            break
        if detect:
            specials += _specials_between(base, a, t_a, b, t_b, k, tol=tol, locate=locate,
                                          locate_tol=locate_tol, index=len(points))
        points.append(b)
        tangents.append(t_b)
        if b.iterations <= 3:
            ds = min(ds * 1.5, ds_max * state_scale(b.x) if per_scale else ds_max)
        if progress is not None:
            progress(f"{base.parameter} = {b.lam:.6g}, {len(points)} points, ds = {ds:.3g}")
    else:
        reason = (f"max_steps = {max_steps} reached at {base.parameter} = "
                  f"{points[-1].lam:.10g} (raise max_steps, --max-steps, to go on)")
    return points, tangents, specials, reason


def _initial_tangent(p: _Point, direction: float) -> np.ndarray:
    t = _null_vector(p)
    if t[-1] * direction < 0 or (t[-1] == 0.0 and direction < 0):
        t = -t
    return t / np.linalg.norm(t)


def continue_from(smap: StroboscopicMap, orbit: Orbit, lo: float, hi: float, *,
                  directions: tuple[float, ...] = (1.0, -1.0), ds: float | None = None,
                  ds_min: float | None = None, ds_max: float | None = None,
                  max_steps: int = 400, tol: float = ORBIT_TOL, detect: bool = True,
                  locate: bool = True, locate_tol: float = LOCATE_TOL, max_turn: float = 30.0,
                  tangent: np.ndarray | None = None, name: str = "",
                  progress: Callable[[str], None] | None = None) -> Branch:
    """Continue a converged orbit of ``smap`` (at ``orbit.value``) within [lo, hi].

    Parameters
    ----------
    smap : StroboscopicMap
        A map with a parameter (:meth:`StroboscopicMap.of` with ``parameter``).
    orbit : Orbit
        The starting orbit, at ``smap.value``.
    lo, hi : float
        Parameter interval; a direction stops at its edge.
    directions : tuple of +1 / -1
        Initial directions in the parameter (both by default).
    ds, ds_min, ds_max : float, optional
        Initial, smallest and largest pseudo-arclength steps (in the units of
        (x, lambda)). By default the largest step is 0.1 max(width, 0.05) per
        unit of the current point's state scale (max(1, |x|_inf)): a branch
        whose amplitude grows takes longer steps, whichever end it starts
        from; a given ``ds_max`` is a fixed cap. The others default from the
        interval and the starting orbit's scale.
    max_steps : int
        Points per direction.
    tol : float
        Corrector residual, relative to max(1, |x|_inf).
    detect, locate : bool
        Look for bifurcations between points; locate them to ``locate_tol``.
    tangent : ndarray, optional
        Initial tangent (branch switching); default the null vector.

    Returns
    -------
    Branch
    """
    k = orbit.period
    lam0 = float(orbit.value)
    width = hi - lo
    scale = state_scale(orbit.state)
    ds = 0.02 * max(width, 0.05 * scale) if ds is None else ds
    if ds_min is None:
        ds_min = 1e-7 * (0.1 * max(width, 0.05 * scale) if ds_max is None else ds_max)
    per_scale = ds_max is None
    if per_scale:
        ds_max = 0.1 * max(width, 0.05)  # per unit of state scale
    base = smap.with_parameter(value=lam0)
    start = _Point(base, orbit.state.copy(), lam0, orbit.monodromy,
                   base.parameter_derivative(orbit.state, k), orbit.residual, orbit.iterations,
                   k, orbit)
    runs = []
    for direction in directions:
        if tangent is not None:
            t0 = np.asarray(tangent, dtype=float) * np.sign(direction)
            t0 = t0 / np.linalg.norm(t0)
        else:
            t0 = _initial_tangent(start, direction)
        runs.append(_run_direction(base, start, t0, k, lo, hi, ds=ds, ds_min=ds_min,
                                   ds_max=ds_max, per_scale=per_scale, max_steps=max_steps,
                                   tol=tol, detect=detect, locate=locate,
                                   locate_tol=locate_tol, max_turn=max_turn,
                                   progress=progress))
    orbits: list[Orbit] = []
    special: list[SpecialPoint] = []
    reasons = []
    if len(runs) == 2:
        (pb, _, sb, rb), (pf, _, sf, rf) = runs
        nb = len(pb)
        orbits = [p.get_orbit() for p in reversed(pb)] + [p.get_orbit() for p in pf[1:]]
        for sp in sb:  # between local points index-1, index -> combined nb-index, nb-index+1
            special.append(_reindex(sp, nb - sp.index))
        for sp in sf:
            special.append(_reindex(sp, sp.index + nb - 1))
        reasons = [rb, rf]
    else:
        pf, _, sf, rf = runs[0]
        orbits = [p.get_orbit() for p in pf]
        special = list(sf)
        reasons = [rf]
    special.sort(key=lambda sp: sp.index)
    return Branch(parameter=smap.parameter, period=k, orbits=orbits, special=special,
                  name=name or f"period-{k}", stop_reasons=reasons)


def _reindex(sp: SpecialPoint, index: int) -> SpecialPoint:
    from dataclasses import replace

    return replace(sp, index=index)


def continue_branch(obj: System | Scene | StroboscopicMap, parameter: str, start: float,
                    stop: float, *, period: int = 1, initial_state: np.ndarray | None = None,
                    transient: int | None = None,
                    factory: Callable[[float], System] | None = None, both: bool = True,
                    **options) -> Branch:
    """Find a period-k orbit at ``start`` and continue it over [start, stop].

    Parameters
    ----------
    obj : System, Scene or StroboscopicMap
        What to continue (a Scene or System gets orbit-work tolerances).
    parameter : str
        Flat scene parameter (e.g. ``period_ratio``), or a custom system's
        parameter label with ``factory``.
    start, stop : float
        The orbit is found at ``start`` (from ``initial_state`` or after
        ``transient`` periods) and continued towards ``stop`` first; with
        ``both`` also the other way. The branch stays within
        [min(start, stop), max(start, stop)].
    period : int
        k, forcing periods per orbit period.
    factory : callable, optional
        ``value -> System`` for custom systems.
    **options
        Passed to :func:`continue_from` (ds, ds_max, max_steps, tol, detect,
        locate, locate_tol, progress, ...).

    Returns
    -------
    Branch
        Points in the order of the curve: the run away from ``stop`` reversed, then
        the run towards ``stop`` (the start orbit once, between them).

    Raises
    ------
    OrbitNotFound
        No orbit at ``start``.
    """
    if isinstance(obj, StroboscopicMap):
        smap = obj if obj.parameter == parameter else obj.with_parameter(parameter, start)
    else:
        smap = StroboscopicMap.of(obj, parameter=parameter, factory=factory, value=start)
    smap = smap.with_parameter(parameter, start)
    orbit = find_orbit(smap, period=period, initial_state=initial_state, transient=transient)
    direction = 1.0 if stop >= start else -1.0
    # with both, the first run (reported reversed) goes away from stop
    directions = (-direction, direction) if both else (direction,)
    lo, hi = min(start, stop), max(start, stop)
    return continue_from(smap, orbit, lo, hi, directions=directions, **options)


def switch_period_doubling(smap: StroboscopicMap, point: SpecialPoint, lo: float, hi: float,
                           *, eps: float = 1e-3, **options) -> Branch:
    """Start and continue the period-2k branch born at a period doubling.

    The doubled orbit starts from x* + eps * v (v the unit eigenvector of the
    multiplier -1, eps relative to max(1, |x*|_inf)) on the hyperplane
    v . (x - x* - eps v) = 0 through the bifurcation point, so the corrector
    cannot fall back on the period-k orbit except by a parameter change of
    order eps / |v . dx/dlambda|; it then runs one direction along +v.

    Parameters
    ----------
    smap : StroboscopicMap
        The map with the branch's parameter.
    point : SpecialPoint
        A "period-doubling" point of a period-k branch.
    lo, hi : float
        Parameter interval of the new branch.
    eps : float
        Relative offset along the eigenvector.

    Returns
    -------
    Branch
        Period 2k, starting at the bifurcation.

    Raises
    ------
    OrbitNotFound
        The corrector found no doubled orbit (or fell back on the period-k one).
    """
    if point.kind != "period-doubling" or point.eigenvector is None:
        raise ValueError(f"a {point.kind} point: branch switching needs a period doubling")
    k2 = 2 * point.orbit.period
    x_star = point.orbit.state
    v = np.real(point.eigenvector)
    v = v / np.linalg.norm(v)
    base = smap.with_parameter(value=point.value)
    last: Exception | None = None
    for sign in (1.0, -1.0):
        for e in (eps, 4 * eps, 0.25 * eps):
            step = e * state_scale(x_star)
            t = np.append(sign * v, 0.0)
            y_star = np.append(x_star, point.value)
            try:
                p = _correct(base, y_star + step * t, t, k2, tol=options.get("tol", ORBIT_TOL))
            except (OrbitNotFound, SimulationError) as exc:
                last = exc
                continue
            single = p.smap.advance(p.x, point.orbit.period)
            if np.max(np.abs(single - p.x)) <= 1e-3 * step:
                last = OrbitNotFound("fell back on the period-k orbit")
                continue
            orbit = p.get_orbit()
            t_new = _tangent(p, t)
            options.setdefault("name", f"period-{k2} from PD at {point.value:.6g}")
            return continue_from(base, orbit, lo, hi, directions=(1.0,), tangent=t_new,
                                 **options)
    raise OrbitNotFound(f"no period-{k2} orbit found off the period doubling at "
                        f"{smap.parameter} = {point.value:.10g} ({last})")
