"""The one vocabulary of the analyses: a periodically sampled dynamical system.

A :class:`System` is what every analysis (Lyapunov exponents, sections,
classification) runs on: a built-in model id with its packed parameters, an
initial state, the sampling period (the excitation period of a forced
system, the re-orthonormalisation interval of an autonomous one) and the
solver settings. Pounding scenes become systems through
:meth:`System.from_scene`; the reference oscillators used to validate the
engine (Lorenz, the Ueda-Duffing oscillator) are built by :func:`lorenz` and
:func:`duffing`.
"""

from __future__ import annotations

import hashlib
import inspect
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..engine import tables as kin
from ..engine.compose import Composition, Engine, UserFunctions, engine_for
from ..kernels.params import (
    CUSTOM,
    DUFFING,
    LORENZ,
    MODEL_DIMS,
    N_PARAMS,
    P_PERIOD,
    P_PERIOD_RATIO,
    P_PHASE0,
    REF_0,
    REF_1,
    REF_2,
    REF_3,
    REF_4,
    SYSTEM_NAMES,
)
from ..scene import PARAMETERS, STATE_NAMES, Scene
from ..solvers.tableaux import METHOD_NAMES

__all__ = ["SimulationError", "System", "advance", "custom_system", "duffing", "lorenz",
           "monodromy", "raise_on_failure"]


class SimulationError(RuntimeError):
    """A run that could not finish (step budget, step-size underflow, NaN)."""


@dataclass(frozen=True)
class System:
    """A built-in dynamical system with its solver settings.

    Attributes
    ----------
    name : str
        Label for reports.
    model_id : int
        Base model id (kernels.params): a pounding model, LORENZ or DUFFING.
    params : ndarray
        Packed parameter vector.
    initial_state : ndarray
        State at t = 0.
    period : float
        Sampling period T (normalised time): sections are taken and tangent
        vectors re-orthonormalised every T.
    state_names : tuple of str
    method, rtol, atol, steps_per_cycle, max_steps, restart_at_kinks :
        Solver settings, as in :class:`chaospound.scene.Solver`.
    transient : int
        Default transient, in periods.
    scene : Scene or None
        The scene it came from, if any.
    n_states : int or None
        State dimension of a custom system (built-in models know theirs).
    ground : str
        The ground motion (a key of :data:`chaospound.engine.compose.GROUNDS`).
    law : str
        The contact law (a key of :data:`chaospound.engine.compose.LAWS`).
    user : UserFunctions or None
        A custom system's functions.
    record : int
        Default record window, in periods (a scene's: its own).
    names : tuple of str
        Names of a custom system's parameters, in the order of ``q``
        (:attr:`parameter_names`).
    period_of : callable or None
        A custom system's period as a function of its named parameters
        (a mapping name -> value), re-evaluated by :meth:`with_params`.
    origin : str
        Where the system was defined, e.g. ``my_oscillator.py:system`` (set by
        :func:`load_system`); part of a sweep store's identity of the system.
    """

    name: str
    model_id: int
    params: np.ndarray
    initial_state: np.ndarray
    period: float
    state_names: tuple[str, ...]
    method: str = "dopri5"
    rtol: float = 1e-9
    atol: float = 1e-11
    steps_per_cycle: int = 400
    max_steps: int = 50_000_000
    restart_at_kinks: bool = True
    transient: int = 40
    scene: Scene | None = field(default=None, compare=False)
    n_states: int | None = None
    ground: str = "sine"
    law: str = "hertz"
    user: UserFunctions | None = field(default=None, compare=False, repr=False)
    record: int = 8
    names: tuple[str, ...] = ()
    period_of: Callable[[Mapping[str, float]], float] | None = field(
        default=None, compare=False, repr=False)
    origin: str = field(default="", compare=False)

    @classmethod
    def from_scene(cls, scene: Scene) -> System:
        """The smallest exact model of a pounding scene (docs/model.md section 9)."""
        model_id = scene.model_id()
        solver = scene.solver
        return cls(
            name=scene.name,
            model_id=model_id,
            params=scene.pack(model_id),
            initial_state=scene.initial_vector(model_id),
            period=scene.period,
            state_names=STATE_NAMES[model_id],
            method=solver.method,
            rtol=solver.rtol,
            atol=solver.atol,
            steps_per_cycle=solver.steps_per_cycle,
            max_steps=solver.max_steps,
            restart_at_kinks=solver.restart_at_kinks,
            transient=scene.run.transient,
            record=scene.run.record,
            scene=scene,
            ground=scene.excitation.ground,
            law=scene.contact.contact_law,
        )

    @property
    def dim(self) -> int:
        return self.n_states if self.model_id == CUSTOM else MODEL_DIMS[self.model_id]

    @property
    def composition(self) -> Composition:
        """What the engine integrates: model, contact law, ground motion, method."""
        return Composition(model="user" if self.model_id == CUSTOM else self.model_name,
                           law=self.law, ground=self.ground, method=self.method,
                           user=self.user)

    def engine(self, tangent: str = "none") -> Engine:
        """The compiled engine of this system; ``tangent`` "qr" or "propagator" carries
        tangent vectors (:class:`chaospound.engine.compose.Composition`)."""
        return engine_for(self.composition.with_tangent(tangent))

    @property
    def has_gap(self) -> bool:
        """Whether the system has contact events (a custom system: a gap function)."""
        return self.user is None or self.user.gap is not None

    @property
    def model_name(self) -> str:
        return SYSTEM_NAMES[self.model_id]

    def with_solver(self, **settings) -> System:
        """A copy with other solver settings (method, rtol, atol, ...)."""
        return replace(self, **settings)

    @property
    def is_custom(self) -> bool:
        """A user's own system (:func:`custom_system`)."""
        return self.model_id == CUSTOM

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The names :meth:`with_params` accepts: a custom system's named parameters
        (``q0, q1, ...`` when they were given as a sequence), a scene's numeric flat
        parameters (``chaospound params``); none for the reference oscillators."""
        if self.scene is not None:
            flat = self.scene.to_dict()
            return tuple(k for k in PARAMETERS if _is_number(flat.get(k)))
        return self.names

    @property
    def parameter_values(self) -> dict[str, float]:
        """Name -> value of every parameter in :attr:`parameter_names`."""
        if self.scene is not None:
            flat = self.scene.to_dict()
            return {k: float(flat[k]) for k in self.parameter_names}
        q = self.params[N_PARAMS:N_PARAMS + len(self.names)]
        return {k: float(v) for k, v in zip(self.names, q, strict=True)}

    def with_params(self, **values: float) -> System:
        """A copy with some named parameters replaced.

        Parameters
        ----------
        **values : float
            Named parameters (:attr:`parameter_names`). A custom system gets
            the entries of its ``q`` replaced (and its period re-evaluated when
            it was given as a function of them); a system made from a scene is
            rebuilt from ``scene.with_params(**values)``, keeping this system's
            solver settings (those not among ``values``).

        Returns
        -------
        System

        Raises
        ------
        ValueError
            An unknown name (the message lists the valid ones), a non-finite
            value, or a value the scene refuses.
        """
        if self.scene is not None:
            rebuilt = System.from_scene(self.scene.with_params(**values))
            kept = {k: getattr(self, k) for k in SOLVER_SETTINGS if k not in values}
            return replace(rebuilt, **kept)
        if not self.names:
            raise ValueError(f"system {self.name!r} has no named parameters")
        p = self.params.copy()
        for name, value in values.items():
            if name not in self.names:
                raise ValueError(f"unknown parameter {name!r} of system {self.name!r}; "
                                 f"its parameters are: {', '.join(self.names)}")
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{name} = {value!r}: need a number") from None
            if not math.isfinite(number):
                raise ValueError(f"{name} = {number}: need a finite number")
            p[N_PARAMS + self.names.index(name)] = number
        period = self.period
        if self.period_of is not None:
            q = p[N_PARAMS:N_PARAMS + len(self.names)]
            period = _period_value(self.period_of, dict(zip(self.names, q.tolist(),
                                                            strict=True)))
            p[P_PERIOD] = period
            p[P_PERIOD_RATIO] = period / (2.0 * np.pi)
        return replace(self, params=p, period=period)

    def source_digest(self) -> str:
        """sha256 of the file defining a custom system's functions ('' if unknown)."""
        if self.user is None:
            return ""
        if self.user.digest:
            return self.user.digest
        try:  # functions defined in __main__ or a notebook: hash their source
            text = "".join(inspect.getsource(getattr(f, "py_func", f))
                           for f in (self.user.rhs, self.user.jacobian, self.user.gap)
                           if f is not None)
        except (OSError, TypeError):
            return ""
        return hashlib.sha256(text.encode()).hexdigest()


#: the settings :meth:`System.with_params` keeps from the system it starts from
SOLVER_SETTINGS = ("method", "rtol", "atol", "steps_per_cycle", "max_steps",
                   "restart_at_kinks", "transient", "record")


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _period_value(period_of, values: Mapping[str, float]) -> float:
    """The period a custom system's function gives for ``values``, checked."""
    try:
        period = float(period_of(values))
    except Exception as exc:  # the user's function: say which values broke it
        raise ValueError(f"period({values}) failed: {exc}") from None
    if not (math.isfinite(period) and period > 0.0):
        raise ValueError(f"period = {period} for {values}: need a finite number > 0")
    return period


def as_system(obj: System | Scene) -> System:
    """Accept a System or a Scene wherever an analysis takes a system."""
    if isinstance(obj, System):
        return obj
    if isinstance(obj, Scene):
        return System.from_scene(obj)
    raise TypeError(f"expected a System or a Scene, got {type(obj).__name__}")


def lorenz(sigma: float = 10.0, rho: float = 28.0, beta: float = 8.0 / 3.0, *,
           interval: float = 1.0, initial_state=(1.0, 1.0, 20.0), **solver) -> System:
    """Lorenz (1963); spectrum about (0.906, 0, -14.57) for the defaults."""
    p = np.zeros(N_PARAMS)
    p[REF_0], p[REF_1], p[REF_2] = sigma, rho, beta
    p[P_PERIOD] = interval
    return System(name="lorenz", model_id=LORENZ, params=p,
                  initial_state=np.array(initial_state, dtype=float), period=interval,
                  state_names=("x", "y", "z"), transient=50, ground="none", **solver)


def duffing(damping: float = 0.05, linear: float = 0.0, cubic: float = 1.0,
            amplitude: float = 7.5, frequency: float = 1.0, *,
            initial_state=(1.0, 0.0), **solver) -> System:
    """Forced Duffing ``x'' + d x' + a x + b x^3 = g cos(w t)``.

    The defaults are Ueda's (1979) chaotic oscillator, whose spectrum is about
    (0.0999, -0.1499) per unit time (Sprott 2003, Chaos and Time-Series
    Analysis); the sum is always -d.
    """
    p = np.zeros(N_PARAMS)
    p[REF_0], p[REF_1], p[REF_2], p[REF_3], p[REF_4] = (damping, linear, cubic, amplitude,
                                                      frequency)
    period = 2.0 * math.pi / frequency
    p[P_PERIOD] = period
    return System(name="duffing", model_id=DUFFING, params=p,
                  initial_state=np.array(initial_state, dtype=float), period=period,
                  state_names=("x", "dx"), transient=100, ground="none", **solver)


def custom_system(rhs, jacobian, gap=None, *,
                  period: float | Callable[[Mapping[str, float]], float], initial_state,
                  params: Mapping[str, float] | Sequence[float] = (), state_names=None,
                  name: str = "custom", transient: int = 40, record: int = 8,
                  **solver) -> System:
    """A user's own jitted oscillator as a :class:`System` every analysis accepts.

    Parameters
    ----------
    rhs : numba.njit function ``rhs(t, y, q, out)``
        Writes ``dy/dt`` into ``out`` (time and state in the user's units).
    jacobian : numba.njit function ``jacobian(t, y, q, jac)``
        Writes ``d rhs_i / d y_j`` into the n x n array ``jac`` (the Lyapunov
        spectrum integrates ``V' = J V`` with it).
    gap : numba.njit function ``gap(t, y, q) -> (g, dg/dt)``, optional
        Distance to contact and its rate: an impact is an onset of ``g < 0``,
        located on the dense output and landed on like the towers' contacts;
        its velocity is ``-dg/dt``.
    period : float or callable
        Sampling period T: the forcing period of a forced system (sections are
        taken every T from t = 0), the re-orthonormalisation interval of an
        autonomous one. A function of the named parameters (called with a
        mapping name -> value, e.g. ``lambda q: 2 * math.pi * q["r"]``) when
        the period follows a parameter, so that sweeping it moves the sections.
    initial_state : sequence of float
        State at t = 0; its length is the dimension n.
    params : mapping of str to float, or sequence of float
        The vector ``q`` handed to the three functions: a mapping names its
        entries (in its order: ``{"zeta": 0.03, "gap": 1.0}`` is ``q[0]``,
        ``q[1]``), which :meth:`System.with_params`, sweeps and ``--set`` use;
        a plain sequence is named ``q0, q1, ...``.
    state_names : sequence of str, optional
        Labels of the state components (default y0, y1, ...).
    name : str
        Label for reports.
    transient, record : int
        Default transient and record window, in periods.
    **solver
        method, rtol, atol, steps_per_cycle, max_steps, restart_at_kinks, as in
        :class:`System`.

    Returns
    -------
    System
        With model "custom". Its integrator is the built-in one composed with
        these functions as its model (:mod:`chaospound.engine.compose`),
        compiled on first use. Functions importable by name from their module
        (a file, not ``__main__`` or a notebook) are compiled once per machine
        and loaded from numba's disk cache afterwards; others once per process.

    Raises
    ------
    ValueError
        A function that is not jitted or fails on the initial state, a bad
        period, state, parameter vector or solver setting.
    """
    from numba.core.registry import CPUDispatcher

    for label, fn in (("rhs", rhs), ("jacobian", jacobian), ("gap", gap)):
        if fn is not None and not isinstance(fn, CPUDispatcher):
            raise ValueError(f"{label} must be a numba.njit function, got {type(fn).__name__}")
    y0 = np.array(initial_state, dtype=np.float64).ravel()
    if isinstance(params, Mapping):
        names = tuple(str(k) for k in params)
        for key in names:
            if not key.isidentifier():
                raise ValueError(f"parameter name {key!r}: need an identifier")
        q = np.array([params[k] for k in params], dtype=np.float64).ravel()
    else:
        q = np.array(params, dtype=np.float64).ravel()
        names = tuple(f"q{i}" for i in range(q.size))
    if y0.size == 0 or not np.all(np.isfinite(y0)):
        raise ValueError(f"initial_state = {list(y0)}: need at least one finite number")
    if not np.all(np.isfinite(q)):
        raise ValueError(f"params = {list(q)}: need finite numbers")
    period_of = period if callable(period) else None
    if period_of is not None:
        period = _period_value(period_of, dict(zip(names, q.tolist(), strict=True)))
    if not (math.isfinite(period) and period > 0.0):
        raise ValueError(f"period = {period}: need a finite number > 0")
    if int(transient) < 0 or int(record) < 1:
        raise ValueError(f"transient = {transient}, record = {record}: need >= 0 and >= 1")
    method = solver.get("method", "dopri5")
    if method not in METHOD_NAMES:
        raise ValueError(f"method = {method!r}: need one of {', '.join(METHOD_NAMES)}")
    n = y0.size
    labels = (tuple(state_names) if state_names is not None
              else tuple(f"y{i}" for i in range(n)))
    if len(labels) != n:
        raise ValueError(f"state_names has {len(labels)} names for {n} states")
    _check_user_functions(rhs, jacobian, gap, y0, q)
    return System(name=name, model_id=CUSTOM, params=pack_custom(float(period), q, n),
                  initial_state=y0, period=float(period), state_names=labels,
                  transient=int(transient), record=int(record), n_states=n, ground="none",
                  user=UserFunctions.of(rhs, jacobian, gap, n, q.size), names=names,
                  period_of=period_of, **solver)


def pack_custom(period: float, q: np.ndarray, n: int) -> np.ndarray:
    """The packed vector of a user system: header, ``q``, Jacobian scratch.

    The header of :mod:`chaospound.kernels.params` carries the period
    (``P_PERIOD``); the user's ``q`` follows from ``N_PARAMS``, then an ``n x n``
    block that receives the Jacobian during a tangent run.
    """
    p = np.zeros(N_PARAMS + q.shape[0] + n * n)
    p[P_PERIOD] = period
    p[P_PERIOD_RATIO] = period / (2.0 * np.pi)
    p[N_PARAMS:N_PARAMS + q.shape[0]] = q
    return p


def _check_user_functions(rhs, jacobian, gap, y0: np.ndarray, q: np.ndarray) -> None:
    """Call each function once on the initial state: one clear line if it fails."""
    n = y0.size
    out = np.zeros(n)
    jac = np.zeros((n, n))
    _checked_call("rhs(t, y, q, out)", rhs, y0, q, out)
    _require_finite("rhs(t, y, q, out)", out)
    _checked_call("jacobian(t, y, q, jac)", jacobian, y0, q, jac)
    _require_finite("jacobian(t, y, q, jac)", jac)
    if gap is not None:
        values = np.asarray(_checked_call("gap(t, y, q)", gap, y0, q), dtype=float)
        if values.shape != (2,):
            raise ValueError(f"gap(t, y, q) must return (g, dg/dt), got {values!r}")
        _require_finite("gap(t, y, q)", values)


def _checked_call(label: str, fn, y0: np.ndarray, *args):
    """``fn(0, y0, *args)``; numba's typing errors and the like become one line."""
    try:
        return fn(0.0, y0.copy(), *args)
    except Exception as exc:  # numba typing errors, IndexError, ...
        text = str(exc).strip()
        first = text.splitlines()[0] if text else type(exc).__name__
        raise ValueError(f"{label} failed on the initial state: {first}") from None


def _require_finite(label: str, values: np.ndarray) -> None:
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{label} gave non-finite values on the initial state")


def advance(system: System, state: np.ndarray, cycles: int, *, tangent: str = "none",
            tangent_log: np.ndarray | None = None, record_from: int | None = None,
            from_time_zero: bool = False):
    """Integrate ``cycles`` periods from a section; return (state, clock, stats).

    The run starts at the section (local time 0), or at t = 0 with
    ``from_time_zero`` (the scene's initial state), and ends on the section
    ``cycles`` periods later; contact events are landed on as in
    :func:`chaospound.simulate.simulate`. With ``tangent`` "qr", ``state`` holds
    the state followed by tangent vectors, which are re-orthonormalised at every
    section, and the logs of the stretching factors of cycles ``record_from ..``
    go to ``tangent_log``; with "propagator" the vectors of each cycle go there
    (see :func:`monodromy`). The returned state is the one at the last section
    even when a contact episode runs through it (the engine follows such an
    episode past the section to record its end; ``clock`` is then where it
    stopped).
    """
    y = np.array(state, dtype=np.float64, copy=True)
    n = y.shape[0]
    clock = np.zeros(3)
    if from_time_zero:
        clock[1] = -system.params[P_PHASE0]
    k_record = cycles if record_from is None else record_from
    strobe = np.zeros((cycles - k_record + 1, n))
    traj = np.zeros((1, n + 1))
    imp = np.zeros((0, kin.N_IMP_FIELDS))  # no impact table: nothing recorded
    imp_state = np.zeros((0, n))
    stats = np.zeros(kin.N_STATS, dtype=np.int64)
    log = np.zeros((0, 0)) if tangent_log is None else tangent_log
    h_fixed = system.period / system.steps_per_cycle
    system.engine(tangent).run_cycles(system.params, y, clock, k_record, cycles, system.rtol,
                                      system.atol, h_fixed, system.max_steps,
                                      system.restart_at_kinks, 0, strobe, traj, imp, imp_state,
                                      stats, log)
    status = int(stats[kin.ST_STATUS])
    if status != kin.STATUS_OK:
        raise_on_failure(status, stats, clock, system.period, system.max_steps, y)
    # a contact episode under way at the last section is followed past it (to record its
    # end): the state at the section is the strobe's last row, not y
    return strobe[-1].copy(), clock, stats


def monodromy(system: System, state: np.ndarray, periods: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The state ``periods`` sections on and the monodromy matrix ``d x_k / d x_0``.

    The variational equations ``V' = J V`` ride along the trajectory (the same
    Jacobian-vector products as the Lyapunov exponents), started from the
    identity at ``state``, a section; the engine stores and resets the vectors
    at every section, and the matrix is the product of the per-section
    propagators, formed here (no product of more than one period inside the
    kernel, where its conditioning could suffer).

    Returns
    -------
    (state, matrix) : (ndarray (n,), ndarray (n, n))
    """
    n = system.dim
    augmented = np.zeros(n * (n + 1))
    augmented[:n] = state
    for i in range(n):
        augmented[n * (i + 1) + i] = 1.0
    log = np.zeros((periods, n * n))
    y, _, _ = advance(system, augmented, periods, tangent="propagator", tangent_log=log,
                      record_from=0)
    matrix = np.eye(n)
    for row in log:
        matrix = row.reshape(n, n).T @ matrix
    return y[:n].copy(), matrix


def raise_on_failure(status, stats, clock, period, max_steps, y) -> None:
    """Raise :class:`SimulationError` with a one-line account of a failed kernel status."""
    if status == kin.STATUS_OK:
        return
    where = f"at cycle {int(clock[0])}, t = {clock[0] * period + clock[1]:.6g}"
    done = f"{int(stats[kin.ST_ACCEPTED])} steps accepted, {int(stats[kin.ST_REJECTED])} rejected"
    if status == kin.STATUS_MAX_STEPS:
        msg = (f"step budget max_steps = {max_steps} exhausted {where} ({done}); "
               "raise max_steps or loosen rtol")
    elif status == kin.STATUS_STEP_UNDERFLOW:
        msg = (f"step size fell below round-off {where} ({done}, last h = {clock[2]:.3g}); "
               "the contact is too stiff for this tolerance")
    else:
        msg = f"state became non-finite {where} ({done})"
    raise SimulationError(msg)
