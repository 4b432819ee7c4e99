"""The stroboscopic (Poincare) map of a periodically forced system and its monodromy.

A :class:`StroboscopicMap` wraps a :class:`~chaospound.dynamics.system.System`
(or a :class:`~chaospound.scene.Scene`, through ``as_system``) with the solver
settings of orbit work: ``advance(x, k)`` is the state k forcing periods after
the section state ``x`` (the section is t = t0 + j T, t0 = phase T; the forcing
phase is exact at every section, docs/model.md section 10) and
``monodromy(x, k)`` returns that state together with the monodromy matrix
M = dP^k/dx.

The monodromy provider is pluggable: the orbit solver and the continuation
call only ``monodromy(x, k)`` (and ``parameter_derivative``), which delegates
to ``StroboscopicMap.monodromy_provider``, a function
``provider(smap, x, k) -> (x_k, M)``. The default is
:func:`variational_monodromy`: the variational equations integrated with the
trajectory by a "propagator" engine (:func:`chaospound.dynamics.system.monodromy`,
one run of k periods with n tangent vectors). :func:`finite_difference_monodromy`
is the independent check (and the fallback for a user system whose Jacobian
is in doubt).

Why finite differences are adequate as a check: the contact force is continuous
(chi >= 1, docs/model.md section 6), so the flow is C^1 across the contact
kinks and P^k is differentiable wherever no impact grazes. A central
difference errs by its truncation (O(h^2) for the 3-point, O(h^4) for the
5-point stencil) plus the integration noise eps / h, with eps about 1e-12 of
the state scale at rtol 1e-12 (dop853, landing on every kink): the noise is
not smooth in x, because the accepted steps change with the perturbation.
Measured on fig3a (12 states, 3 impacts a cycle) and fig4-translational at
T/T_Ax = 0.7 through the identity det M = exp(trace(J) T) (the relative
error of det M): 3-point stencil 4e-7 / 2e-9 at h = 1e-3, 4e-8 / 1e-9 at
3e-4, 1e-7 / 7e-8 at 1e-4, 7e-7 at 1e-5; 5-point stencil 6e-9 / 2e-9 at
1e-3, 1e-9 / 3e-9 at 3e-4. Default: the 5-point stencil with the relative
step 1e-3 (4 n + 1 runs of k periods per matrix). Near a grazing impact the
map is smooth only on a scale below such a step (the wall model at gap 5
folds 6e-6 in T/T_Ax after grazing; with h = 1e-3 the fold came out 7.6e-7
off the value that steps 1e-4 .. 1e-7 agree on to 1e-12), so a column whose
3-point and 5-point estimates disagree by more than 1e-5 is redone with a
10 times smaller step, twice at most; with that the default finds that fold
within 1e-13 of the small-step value. For an affine map (no
contact) every stencil is exact up to round-off for any step, so a large step
(e.g. ``fd_step=0.1``) gives M to about 1e-13.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ..dynamics.system import System, as_system, evolve, monodromy
from ..scene import Scene

__all__ = [
    "ORBIT_ATOL",
    "ORBIT_METHOD",
    "ORBIT_RTOL",
    "MonodromyProvider",
    "StroboscopicMap",
    "finite_difference_monodromy",
    "state_scale",
]

ORBIT_RTOL = 1e-12  #: default relative tolerance of orbit work
ORBIT_ATOL = 1e-14  #: default absolute tolerance of orbit work
#: default scheme of orbit work: at rtol 1e-12 dop853 takes 5-13x fewer steps than dopri5
#: and is 1.4-5x faster on the wall and fig3a scenes (measured on this project's machine)
ORBIT_METHOD = "dop853"
FD_STEP = 1e-3  #: default relative step of the finite-difference monodromy
FD_ORDER = 4  #: default order of the finite-difference stencil (2 or 4)
#: 5-point stencil: a column whose 3-point estimate differs from it by more than this
#: (relative to max(1, |column|)) is redone with a 10 times smaller step, at most
#: FD_REFINEMENTS times: the map is not smooth on the step's scale (an impact near grazing)
FD_SMOOTH_TOL = 1e-5
FD_REFINEMENTS = 2
#: rtol of the approximate monodromy matrices of chord-Newton's iterations
#: (:meth:`StroboscopicMap.approximate_monodromy`); atol = 1e-2 rtol
JACOBIAN_RTOL = 1e-6
JACOBIAN_ATOL_PER_RTOL = 1e-2
#: scheme of the variational monodromy (tangent runs of n + 1 vectors): see
#: :func:`variational_monodromy`
MONODROMY_METHOD = "auto"
MONODROMY_DOPRI5_DIM = 4  #: "auto": dopri5 from this state dimension on

#: ``provider(smap, x, k) -> (x_k, M)``: state after k periods and d x_k / d x
MonodromyProvider = Callable[["StroboscopicMap", np.ndarray, int], tuple[np.ndarray, np.ndarray]]


def state_scale(x: np.ndarray) -> float:
    """The scale of a state for relative tolerances: ``max(1, |x|_inf)``."""
    return max(1.0, float(np.max(np.abs(x)))) if x.size else 1.0


def finite_difference_steps(x: np.ndarray, rel: float) -> np.ndarray:
    """Per-component finite-difference steps ``rel * max(|x_j|, 1e-2 * max(1, |x|_inf))``.

    A component's own magnitude sets its step, with a floor of 1 % of the state
    scale so that a component passing through 0 (a velocity at the section, a
    rotation that is not excited) still gets a step well above the integration
    noise. Steps are rounded to representable increments (x + h - x == h).
    """
    scale = state_scale(x)
    h = rel * np.maximum(np.abs(x), 1e-2 * scale)
    return (x + h) - x


def finite_difference_monodromy(smap: StroboscopicMap, x: np.ndarray,
                                k: int) -> tuple[np.ndarray, np.ndarray]:
    """Monodromy matrix of P^k at x by central differences.

    With ``smap.fd_order == 2`` column j is
    ``(P(x + h_j e_j) - P(x - h_j e_j)) / (2 h_j)`` (2 n + 1 runs of k
    periods); with 4 (default) the five-point stencil
    ``(-P(x + 2h) + 8 P(x + h) - 8 P(x - h) + P(x - 2h)) / (12 h)`` (4 n + 1
    runs), whose O(h^4) truncation allows a larger step and so less of the
    integration noise; a column whose 3-point and 5-point estimates differ by
    more than ``FD_SMOOTH_TOL`` is redone with the step divided by 10 (at most
    ``FD_REFINEMENTS`` times): near a grazing impact the map is smooth only on
    a small scale. Steps from :func:`finite_difference_steps`
    (``smap.fd_step`` relative).

    Returns
    -------
    x_k : ndarray (n,)
        P^k(x).
    M : ndarray (n, n)
        d P^k / d x (dimensionless ratios of the state's units).
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[0]
    xk = smap.advance(x, k)
    h = finite_difference_steps(x, smap.fd_step)
    m = np.empty((n, n))

    def shifted(j: int, times: float) -> np.ndarray:
        y = x.copy()
        y[j] += times * h[j]
        return smap.advance(y, k)

    for j in range(n):
        if smap.fd_order == 2:
            m[:, j] = (shifted(j, 1.0) - shifted(j, -1.0)) / (2.0 * h[j])
            continue
        for _ in range(FD_REFINEMENTS + 1):
            d1 = shifted(j, 1.0) - shifted(j, -1.0)
            d2 = shifted(j, 2.0) - shifted(j, -2.0)
            m[:, j] = (8.0 * d1 - d2) / (12.0 * h[j])
            three_point = d1 / (2.0 * h[j])
            gap = float(np.max(np.abs(three_point - m[:, j])))
            if gap <= FD_SMOOTH_TOL * max(1.0, float(np.max(np.abs(m[:, j])))):
                break
            h[j] = (x[j] + 0.1 * h[j]) - x[j]  # not smooth at this scale: a grazing
    return xk, m


def variational_monodromy(smap: StroboscopicMap, x: np.ndarray,
                          k: int) -> tuple[np.ndarray, np.ndarray]:
    """``(P^k(x), d P^k / d x)`` from the variational equations (the default provider).

    Exact up to the integration tolerance (the tangent vectors share the
    trajectory's step control), at the cost of one run of k periods with n
    tangent vectors instead of the 4 n + 1 runs of the finite difference. The
    run uses ``smap.monodromy_method`` at the map's tolerances; "auto" (the
    default) takes dopri5 for n >= 4 states and the map's scheme (dop853) below:
    with n + 1 vectors of n components per stage, dopri5's unrolled step costs
    about a tenth of dop853's generic one, which more than pays for its 7x more
    steps at rtol 1e-12 once n(n + 1) is large. Measured (best of 30,
    interleaved, one period): fig3a (n = 12) 4.5 ms against 10.8 ms,
    multipliers equal to 5e-12 and det M to 1e-11; fig4-translational (n = 4)
    0.39 against 0.53 ms; the wall (n = 2) 0.14 against 0.046 ms.
    """
    system = smap.system
    method = smap.monodromy_method
    if method == "auto":
        method = "dopri5" if system.dim >= MONODROMY_DOPRI5_DIM else None
    if method is not None and method != system.method and system.method != "rk4":
        system = system.with_solver(method=method)
    return monodromy(system, x, k)


@dataclass(frozen=True)
class StroboscopicMap:
    """P^k: section state -> section state k forcing periods later.

    Build with :meth:`of`. Attributes are the system as run (tight
    tolerances), the name and value of the continuation parameter (if any),
    and how to rebuild the map at another parameter value.

    Attributes
    ----------
    system : System
        The system with the orbit solver settings.
    parameter : str or None
        Name of the parameter the map is continued in (a flat scene parameter
        such as ``period_ratio``, or a label for a custom system).
    value : float
        Its current value (NaN without a parameter).
    factory : callable or None
        ``value -> System`` for custom systems (scenes use ``Scene.with_params``).
    fd_step : float
        Relative step of :func:`finite_difference_monodromy`.
    fd_order : int
        Its stencil's order (2 or 4).
    param_step : float
        Relative step of :meth:`parameter_derivative` (times ``max(|value|, 1)``).
    monodromy_provider : MonodromyProvider
        The strategy behind :meth:`monodromy`.
    jacobian_rtol : float or None
        rtol of :meth:`approximate_monodromy`, the matrices of chord-Newton's
        iterations (None: the exact ones).
    monodromy_method : str or None
        Runge-Kutta scheme of :func:`variational_monodromy`: "auto" (dopri5 for
        n >= 4, else the system's), a scheme's name, or None (the system's).
    """

    system: System
    parameter: str | None = None
    value: float = float("nan")
    factory: Callable[[float], System] | None = field(default=None, compare=False, repr=False)
    fd_step: float = FD_STEP
    fd_order: int = FD_ORDER
    param_step: float = 1e-6
    monodromy_provider: MonodromyProvider = field(default=variational_monodromy,
                                                  compare=False, repr=False)
    solver: dict = field(default_factory=dict, compare=False, repr=False)
    jacobian_rtol: float | None = JACOBIAN_RTOL
    monodromy_method: str | None = MONODROMY_METHOD

    @classmethod
    def of(cls, obj: System | Scene, *, parameter: str | None = None,
           factory: Callable[[float], System] | None = None, value: float | None = None,
           rtol: float = ORBIT_RTOL, atol: float = ORBIT_ATOL,
           method: str | None = ORBIT_METHOD, fd_step: float = FD_STEP,
           fd_order: int = FD_ORDER,
           monodromy_provider: MonodromyProvider = variational_monodromy,
           ) -> StroboscopicMap:
        """The stroboscopic map of a system or scene, with orbit-work tolerances.

        Parameters
        ----------
        obj : System or Scene
            What to map; a Scene runs its smallest exact model.
        parameter : str, optional
            Continuation parameter: a flat scene parameter (``chaospound
            params``), or any label when ``factory`` is given.
        factory : callable, optional
            ``value -> System``: rebuilds a custom system at another parameter
            value (required to continue a system that has no scene).
        value : float, optional
            The parameter's current value (default: read from the scene; a
            custom system's must be given).
        rtol, atol : float
            Tolerances of every integration (default 1e-12, 1e-14).
        method : str or None
            Runge-Kutta scheme (default dop853; None keeps the system's).
        fd_step : float
            Relative finite-difference step of the monodromy.
        fd_order : {2, 4}
            Order of the central-difference stencil.
        monodromy_provider : MonodromyProvider
            Strategy computing (P^k(x), M).
        """
        solver = {"rtol": float(rtol), "atol": float(atol)}
        if method is not None:
            solver["method"] = method
        system = as_system(obj).with_solver(**solver)
        if parameter is not None:
            if factory is None and system.scene is None:
                raise ValueError(f"parameter {parameter!r}: a custom system needs a factory "
                                 "(value -> System) to be continued")
            if value is None:
                if system.scene is None:
                    raise ValueError(f"parameter {parameter!r}: give its current value")
                value = _scene_value(system.scene, parameter)
        return cls(system=system, parameter=parameter,
                   value=float("nan") if value is None else float(value), factory=factory,
                   fd_step=fd_step, fd_order=fd_order,
                   monodromy_provider=monodromy_provider, solver=solver)

    # ------------------------------------------------------------------ map
    @property
    def dim(self) -> int:
        """State dimension n."""
        return self.system.dim

    @property
    def period(self) -> float:
        """Forcing period T (normalised time)."""
        return self.system.period

    def advance(self, x: np.ndarray, k: int = 1) -> np.ndarray:
        """P^k(x): the section state k forcing periods after the section state x.

        Raises
        ------
        SimulationError
            A failed integration (step budget, underflow, non-finite state).
        """
        return evolve(self.system, np.asarray(x, dtype=np.float64), cycles=int(k)).state

    def monodromy(self, x: np.ndarray, k: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """(P^k(x), d P^k / d x) from the map's monodromy provider."""
        return self.monodromy_provider(self, np.asarray(x, dtype=np.float64), int(k))

    def approximate_monodromy(self, x: np.ndarray, k: int = 1
                              ) -> tuple[np.ndarray, np.ndarray]:
        """(P^k(x), d P^k / d x) from the provider at the looser ``jacobian_rtol``.

        For the iterations of chord-Newton, whose convergence needs only an
        approximate matrix (its error of about ``jacobian_rtol`` is far below the
        O(|x - x*|) by which a matrix at an iterate differs from the one at the
        fixed point anyway). ``jacobian_rtol`` None, or not looser than the map's
        rtol: the exact :meth:`monodromy`.
        """
        rtol = self.jacobian_rtol
        if rtol is None or rtol <= self.system.rtol or self.system.method == "rk4":
            return self.monodromy(x, k)
        loose = replace(self, system=self.system.with_solver(
            rtol=rtol, atol=max(self.system.atol, JACOBIAN_ATOL_PER_RTOL * rtol)))
        return loose.monodromy(x, k)

    # ------------------------------------------------------------ parameter
    def with_parameter(self, name: str | None = None, value: float | None = None
                       ) -> StroboscopicMap:
        """The same map at another value of a parameter.

        Parameters
        ----------
        name : str, optional
            Parameter (default: the map's own); a flat scene parameter, or the
            map's parameter of a custom system built by its factory.
        value : float
            The new value.

        Returns
        -------
        StroboscopicMap
            With the same solver settings, provider and steps.
        """
        name = self.parameter if name is None else name
        if name is None or value is None:
            raise ValueError("with_parameter needs a parameter name and a value")
        value = float(value)
        if self.factory is not None and name == self.parameter:
            system = self.factory(value)
        elif self.system.scene is not None:
            system = System.from_scene(self.system.scene.with_params(**{name: value}))
        else:
            raise ValueError(f"parameter {name!r}: a custom system needs a factory")
        system = system.with_solver(**self.solver)
        return replace(self, system=system, parameter=name, value=value)

    def parameter_derivative(self, x: np.ndarray, k: int = 1) -> np.ndarray:
        """d P^k / d lambda at x by a central difference in the map's parameter.

        Step ``param_step * max(|lambda|, 1)``.
        """
        if self.parameter is None:
            raise ValueError("the map has no parameter to differentiate in")
        h = self.param_step * max(abs(self.value), 1.0)
        up = self.with_parameter(value=self.value + h).advance(x, k)
        down = self.with_parameter(value=self.value - h).advance(x, k)
        return (up - down) / (2.0 * h)

    def start_state(self, transient: int | None = None) -> np.ndarray:
        """The section state after ``transient`` periods from the system's initial state
        (default: the system's transient, e.g. the scene's run.transient)."""
        system = self.system
        cycles = system.transient if transient is None else int(transient)
        if cycles <= 0:
            return np.array(system.initial_state, dtype=np.float64)
        return evolve(system, cycles=cycles).state


def _scene_value(scene: Scene, name: str) -> float:
    values = scene.to_dict()
    if name not in values:
        from ..scene import SceneError

        raise SceneError(f"unknown parameter {name!r} (see 'chaospound params')")
    value = values[name]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"parameter {name!r} = {value!r}: not a number, cannot be continued")
    return float(value)
