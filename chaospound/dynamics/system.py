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
import time
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
    P_HALF_L,
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

__all__ = ["Evolution", "SimulationError", "System", "advance", "as_system", "custom_system",
           "duffing", "evolve", "lorenz", "monodromy", "raise_on_failure", "warm_up"]


_NO_TANGENT = np.zeros((0, 0))  #: tangent_log placeholder of plain runs


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
    ground_y : bool
        The ground's y component drives the towers' Y (a scene's
        ``Excitation.has_y``; the composition's ``ground_y``).
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
    ground_y: bool = False
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
            ground_y=scene.excitation.has_y,
        )

    @property
    def dim(self) -> int:
        return self.n_states if self.model_id == CUSTOM else MODEL_DIMS[self.model_id]

    @property
    def composition(self) -> Composition:
        """What the engine integrates: model, contact law, ground motion, method."""
        return Composition(model="user" if self.model_id == CUSTOM else self.model_name,
                           law=self.law, ground=self.ground, method=self.method,
                           user=self.user, ground_y=self.ground_y)

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
                  user=UserFunctions.of(rhs, jacobian, gap, n), names=names,
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


@dataclass(frozen=True)
class Evolution:
    """What one run of the engine returns (:func:`evolve`).

    Attributes
    ----------
    state : ndarray (n,)
        The state at the last section, ``transient + cycles``.
    vectors : ndarray (k, n) or None
        The tangent vectors at the last section of a tangent run (orthonormal
        after a "qr" run's re-orthonormalisation, the unit vectors after a
        "propagator" run's reset).
    end_state : ndarray (n,)
        Where the engine stopped: the last section's state, or, when a contact
        episode runs through that section, the state at its end (the engine
        follows it to record its peak and duration).
    clock : ndarray (3,)
        ``[k, tau, h]`` where the engine stopped (``end_state``): section index,
        local time after it (normalised time) and the next step size.
    stats : ndarray of int64
        Counters of :mod:`chaospound.engine.tables` (``ST_*``); status OK.
    cycles : ndarray of int (cycles + 1,)
        Indices k of the recorded sections, ``transient .. transient + cycles``.
    section_times : ndarray (cycles + 1,)
        Their times ``t0 + k T`` (normalised time, t0 the section's time origin).
    sections : ndarray (cycles + 1, n)
        The states at those sections (the stroboscopic section).
    impacts : ndarray (n_impacts, N_IMP_FIELDS)
        Impact table (:mod:`chaospound.engine.tables`, ``IMP_*``) of the onsets in
        the record window; empty unless ``impacts=True``.
    impact_states : ndarray (n_impacts, n)
        The states at those onsets.
    samples : ndarray (rows, n + 1) or None
        Dense samples of the record window, column 0 the time (``samples_per_cycle``).
    tangent_log : ndarray or None
        A tangent run's per-cycle record of the window, one row per cycle: "qr",
        ``log R_ii`` of the k vectors' re-orthonormalisation, shape
        (cycles, k); "propagator", the vectors at the section before their reset
        to the unit vectors, shape (cycles, k n) (row reshaped (k, n): the
        transposed propagator of that cycle).
    wall_s : float
        Wall time of the run (s), compilation excluded.
    """

    state: np.ndarray
    vectors: np.ndarray | None
    end_state: np.ndarray
    clock: np.ndarray
    stats: np.ndarray
    cycles: np.ndarray
    section_times: np.ndarray
    sections: np.ndarray
    impacts: np.ndarray
    impact_states: np.ndarray
    samples: np.ndarray | None
    tangent_log: np.ndarray | None
    wall_s: float

    @property
    def steps(self) -> int:
        """Accepted steps."""
        return int(self.stats[kin.ST_ACCEPTED])

    @property
    def augmented_state(self) -> np.ndarray:
        """The state at the last section followed by the tangent vectors."""
        if self.vectors is None:
            return self.state
        return np.concatenate((self.state, self.vectors.ravel()))


TANGENTS = ("none", "qr", "propagator")  #: the tangent modes of :func:`evolve`


def evolve(system: System | Scene, initial_state: np.ndarray | None = None, *,
           transient: int = 0, cycles: int = 1, start_at_section: bool | None = None,
           start_phase: float | None = None, tangent: str = "none",
           vectors: int | None = None, impacts: bool = False,
           impact_capacity: int | None = None, samples_per_cycle: int = 0) -> Evolution:
    """Integrate a system through ``transient + cycles`` periods: the one engine entry.

    Every analysis runs the engine through this function. The run goes from
    its start to the section ``transient + cycles`` (sections are the times
    ``t0 + k T``, t0 the section's time origin ``phase T``); the record window
    is the last ``cycles`` periods, whose sections, impacts and dense samples
    are returned. Contact events are located and landed on
    (docs/model.md sections 8, 10).

    Parameters
    ----------
    system : System or Scene
        What to integrate, with its solver settings (a Scene becomes
        :meth:`System.from_scene`). The packed vector ``system.params`` is used
        in place: a contact law's per-episode memory (hertzdamp's onset
        velocity) is written there and carries over to the next run of the same
        system, as a continued trajectory needs.
    initial_state : ndarray, optional
        The start state (default: the system's initial state). In a tangent
        run it may also hold tangent vectors after the state (n (k + 1)
        values); a plain state of n values gets ``vectors`` unit vectors.
    transient : int
        Periods integrated before the record window (>= 0).
    cycles : int
        Periods of the record window (>= 0 in a plain run).
    start_at_section : bool, optional
        Start at the section time t0 (local time 0) instead of t = 0; default:
        at the section when ``initial_state`` is given (a section state, e.g.
        of an earlier run), at t = 0 otherwise (the system's initial state).
    start_phase : float, optional
        Start at forcing phase ``start_phase`` (a fraction of the period, in
        [0, 1)) instead: at the time ``start_phase T`` minus the whole periods
        that put it within one period before the first section (the sections
        stay where they are); basins over the initial phase use it.
    tangent : {"none", "qr", "propagator"}
        Carry tangent vectors (the variational equations ``V' = J V``,
        docs/model.md section 12): "qr" re-orthonormalises them at every
        section and logs the stretching factors of the window's cycles (the
        Lyapunov exponents); "propagator" stores them at every section of the
        window and resets them to the unit vectors (monodromy matrices).
    vectors : int, optional
        Number of tangent vectors added to a plain state (default: n).
    impacts : bool
        Record the impacts of the window (the table grows as needed; an
        episode still running at the window's end is followed to its release).
    impact_capacity : int, optional
        Initial size of the impact table.
    samples_per_cycle : int
        Dense samples per period over the record window (0: none).

    Returns
    -------
    Evolution

    Raises
    ------
    SimulationError
        The step budget ran out, the step size underflowed or the state became
        non-finite; the message carries the numbers.
    ValueError
        Bad counts, a state of the wrong size, an unknown tangent mode.
    """
    system = as_system(system)
    transient, cycles = int(transient), int(cycles)
    if transient < 0 or cycles < 0:
        raise ValueError(f"transient = {transient}, cycles = {cycles}: need >= 0")
    if tangent not in TANGENTS:
        raise ValueError(f"tangent = {tangent!r}: need one of {', '.join(TANGENTS)}")
    n = system.dim
    given = initial_state is not None
    start = system.initial_state if initial_state is None else initial_state
    y = np.array(start, dtype=np.float64, copy=True).ravel()
    if tangent == "none" and y.shape[0] != n:
        raise ValueError(f"initial_state has {y.shape[0]} values: need {n} "
                         f"({', '.join(system.state_names)})")
    if tangent != "none" and y.shape[0] == n:
        k_vectors = n if vectors is None else int(vectors)
        if not 1 <= k_vectors <= n:
            raise ValueError(f"vectors = {k_vectors}: need 1 .. {n}")
        augmented = np.zeros(n * (k_vectors + 1))
        augmented[:n] = y
        for i in range(k_vectors):
            augmented[n * (i + 1) + i] = 1.0
        y = augmented
    if tangent != "none" and (y.shape[0] % n or y.shape[0] < 2 * n):
        raise ValueError(f"initial_state has {y.shape[0]} values: a tangent run needs the "
                         f"{n} states followed by k tangent vectors of {n}")
    k_vectors = y.shape[0] // n - 1
    if start_at_section is None:
        start_at_section = given
    params = system.params
    t0 = float(params[P_PHASE0])
    tau_start = 0.0 if (start_at_section or t0 == 0.0) else -t0
    if start_phase is not None:  # t0 + tau_start = start_phase T (mod T), tau_start <= 0
        if not 0.0 <= start_phase < 1.0:
            raise ValueError(f"start_phase = {start_phase}: must be in [0, 1)")
        tau_start = -((t0 - start_phase * system.period) % system.period)
    k_record, k_end = transient, transient + cycles
    n_rows = samples_per_cycle * cycles + 1 if samples_per_cycle > 0 else 1
    width = {"none": 0, "qr": k_vectors, "propagator": k_vectors * n}[tangent]
    log = np.zeros((cycles, width)) if tangent != "none" else _NO_TANGENT
    capacity = (impact_capacity or max(64, 16 * (cycles + 1))) if impacts else 0
    engine = system.engine(tangent)
    if tangent == "none":
        warm_up(engine, params)
    y_start = y
    started = time.perf_counter()
    while True:
        y = y_start.copy()
        clock = np.array([0.0, tau_start, 0.0])
        strobe = np.full((cycles + 1, y.shape[0]), np.nan)
        traj = np.full((n_rows, y.shape[0] + 1), np.nan)
        imp = np.zeros((capacity, kin.N_IMP_FIELDS))
        imp_state = np.zeros((capacity, y.shape[0]))
        stats = np.zeros(kin.N_STATS, dtype=np.int64)
        n_imp = engine.run_cycles(params, y, clock, k_record, k_end, system.rtol, system.atol,
                                  system.period / system.steps_per_cycle, system.max_steps,
                                  system.restart_at_kinks, samples_per_cycle, strobe, traj,
                                  imp, imp_state, stats, log)
        status = int(stats[kin.ST_STATUS])
        if status != kin.STATUS_OVERFLOW:
            break
        capacity *= 4
    wall = time.perf_counter() - started
    raise_on_failure(status, stats, clock, system.period, system.max_steps, y)
    k = np.arange(k_record, k_end + 1)
    return Evolution(
        state=strobe[-1, :n].copy(),
        vectors=strobe[-1, n:].reshape(k_vectors, n).copy() if k_vectors else None,
        end_state=y[:n].copy() if k_vectors else y,
        clock=clock,
        stats=stats,
        cycles=k,
        section_times=t0 + k * system.period,
        sections=strobe[:, :n] if k_vectors else strobe,
        impacts=imp[:n_imp],
        impact_states=imp_state[:n_imp, :n],
        samples=traj if samples_per_cycle > 0 else None,
        tangent_log=log if tangent != "none" else None,
        wall_s=wall,
    )


def advance(system: System, state: np.ndarray, cycles: int, *, tangent: str = "none",
            tangent_log: np.ndarray | None = None, record_from: int | None = None,
            from_time_zero: bool = False):
    """Integrate ``cycles`` periods from a section; return (state, clock, stats).

    A thin face of :func:`evolve` for the map-like callers (orbits, the
    two-trajectory exponent): the run starts at the section (local time 0),
    or at t = 0 with ``from_time_zero`` (the system's initial state), and ends
    on the section ``cycles`` periods later. With ``tangent`` "qr" or
    "propagator", ``state`` holds the state followed by tangent vectors and
    the returned state too; the log of cycles ``record_from ..`` (default:
    none) is copied into ``tangent_log`` when given. The returned state is the
    one at the last section even when a contact episode runs through it (the
    engine follows such an episode past the section to record its end;
    ``clock`` is then where it stopped).
    """
    record_from = cycles if record_from is None else int(record_from)
    run = evolve(system, state, transient=record_from, cycles=cycles - record_from,
                 start_at_section=not from_time_zero, tangent=tangent)
    if tangent_log is not None and run.tangent_log is not None:
        tangent_log[...] = run.tangent_log
    return run.augmented_state, run.clock, run.stats


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
    run = evolve(system, state, cycles=periods, start_at_section=True, tangent="propagator")
    n = system.dim
    matrix = np.eye(n)
    for row in run.tangent_log:
        matrix = row.reshape(n, n).T @ matrix
    return run.state, matrix


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


_WARM: set = set()


def warm_up(engine: Engine | None = None, params: np.ndarray | None = None) -> None:
    """Load (or compile) an engine once per process, outside any timing.

    A tiny call (one step from rest) makes later wall times
    (``Evolution.wall_s``) measure the work alone. Without an engine: the
    default scene's (fig3a's composition). ``params`` is the packed vector of a
    System of that composition (a copy is run: the laws' memory slots are
    written at onsets); without it a placeholder of the fixed layout serves the
    compositions that read nothing beyond it (Hertz under an x-only sine or no ground),
    and the others compile at their first real run: a composition with a law
    block or a record must never run on a vector that lacks them (the kernels
    do not check bounds).
    """
    if engine is None:
        engine = engine_for(DEFAULT_COMPOSITION)
    c = engine.composition
    if c in _WARM:
        return
    n = {"wall": 2, "tower-wall": 6, "pair": 4, "towers": 12}.get(c.model)
    if n is None or c.tangent != "none":
        return  # reference, user and tangent engines: compiled by their first real run
    y = np.zeros(n)
    if params is not None:
        p = np.array(params, dtype=np.float64)
    elif c.law == "hertz" and c.ground in ("sine", "none") and not c.ground_y:
        p = np.zeros(N_PARAMS)
        p[P_PERIOD] = 1.0
        p[P_PERIOD_RATIO] = 1.0
        p[P_HALF_L] = 0.5
    else:
        return
    stats = np.zeros(kin.N_STATS, dtype=np.int64)
    engine.run_cycles(p, y, np.zeros(3), 0, 1, 1e-6, 1e-9, 0.1, 1, True, 0,
                      np.zeros((2, n)), np.zeros((1, n + 1)), np.zeros((0, kin.N_IMP_FIELDS)),
                      np.zeros((0, n)), stats, _NO_TANGENT)
    _WARM.add(engine.composition)


#: the composition of the default scene (the paper's towers, Hertz, sine, DOPRI5)
DEFAULT_COMPOSITION = Composition(model="towers")
