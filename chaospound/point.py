"""One task of a sweep: grid points run to steady state, classified, measured.

This is what a worker runs, whatever the backend (the local process pool of
:mod:`chaospound.sweep` or a Dask cluster, :mod:`chaospound.distributed`); both
import it from here, and the sweep engine above them decides which points go
into which task. ``spec`` is a :class:`chaospound.sweep.SweepSpec` (its
``point_values``, ``lyapunov``, ``lyapunov_cycles``, ``classify`` and
``window_tol``).

The target of a task is a :class:`~chaospound.scene.Scene` or a user's
:class:`~chaospound.dynamics.system.System` (:func:`run_system_point`): the
same steady run, classification and exponents, each point made by
``system.with_params`` of its grid values.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from .scene import Scene, SceneError
from .store import PointResult

__all__ = ["run_point", "run_system_point", "run_task"]


def run_task(scene, spec, indices: Sequence[int],
             start_state: np.ndarray | None, continuation: bool) -> list[PointResult]:
    """Run grid points in order; with continuation each starts from the previous one.

    ``scene`` is a Scene (:func:`run_point`) or a custom System
    (:func:`run_system_point`). Without continuation (the "fresh" branch)
    every point starts from the scene's initial state, whatever ran before it
    in the task: its label is the attractor reached from there, as
    :func:`chaospound.dynamics.classify.classify` names it, and does not
    depend on how the points are cut into tasks.
    """
    results = []
    state = start_state
    runner = run_point if isinstance(scene, Scene) else run_system_point
    for index in indices:
        result = runner(scene, spec, int(index), state if continuation else None)
        results.append(result)
        if continuation:
            state = result.final_state if result.status == 1 else None
    return results


def run_point(scene: Scene, spec, index: int,
              start_state: np.ndarray | None = None) -> PointResult:
    """Steady run, classification and optional exponents of one grid point
    (from ``start_state``, a section state, on a continuation branch)."""
    return _run(scene, len(scene.initial_vector()), spec, index, start_state)


def run_system_point(system, spec, index: int,
                     start_state: np.ndarray | None = None) -> PointResult:
    """:func:`run_point` for a user's System, swept over its named parameters.

    The point is ``system.with_params(**values)``, run for the system's transient
    and record windows. Its regime comes from the record window (or the
    adaptive classifier with ``spec.classify == "full"``) with every state
    component weighted equally, as :func:`chaospound.dynamics.classify.classify`
    does for custom systems; a system without a gap function has no impacts to
    classify: its points are stored "unresolved", with their sections, exponents
    and statistics.
    """
    return _run(system, system.dim, spec, index, start_state)


def _run(target, n_state: int, spec, index: int,
         start_state: np.ndarray | None) -> PointResult:
    """One point of a Scene or a System (see :func:`run_point`, :func:`run_system_point`)."""
    from .dynamics.classify import classify, classify_sequence, length_weights
    from .dynamics.lyapunov import lyapunov_spectrum
    from .dynamics.system import as_system
    from .simulate import SimulationError, simulate

    started = time.perf_counter()
    n_exp = 0 if spec.lyapunov == 0 else (n_state if spec.lyapunov < 0 else spec.lyapunov)
    try:
        values = spec.point_values(index)
        point = target.with_params(**values) if values else target
        is_scene = isinstance(point, Scene)
        system = as_system(point)  # a scene is packed once, here
        start_phase = None
        initial = spec.initial_values(index)
        if initial:  # a basin scan: this point's own initial state (and phase)
            start_state, start_phase = _initial_condition(system, initial)
        if spec.classify == "converged" and (is_scene or point.has_gap):
            return _run_converged(point, n_exp, spec, index, start_state, started)
        sim = simulate(system, initial_state=start_state,
                       start_at_section=start_state is not None and start_phase is None,
                       start_phase=start_phase)
        exps = errs = None
        max_exp = max_err = None
        if n_exp:
            spectrum = lyapunov_spectrum(system, k=n_exp, transient=0,
                                         initial_state=sim.strobe.state[-1],
                                         cycles=spec.lyapunov_cycles, tangent_transient=10)
            exps, errs = spectrum.exponents, spectrum.errors
            max_exp, max_err = float(exps[0]), float(errs[0])
        imp = sim.impacts
        transient_used = sim.transient
        if not system.has_gap:
            regime = _Unclassified(float("nan"))
        elif spec.classify == "full":
            regime = classify(system, floquet=False)  # a sweep stores no Floquet data
            if exps is None and regime.max_exponent is not None:
                max_exp, max_err = regime.max_exponent, regime.max_exponent_error
            transient_used = regime.transient_used
        else:
            strobe = sim.strobe.state
            if is_scene:  # rotations as lengths; a user's components weigh alike
                strobe = strobe * length_weights(point, sim.state_names)
            regime = classify_sequence(
                strobe, imp.cycle, imp.phase, imp.velocity, imp.labels,
                max_period=max(1, sim.record // 2), tol=spec.window_tol,
                exponent=None if exps is None else float(exps[0]),
                exponent_error=None if errs is None else float(errs[0]),
            )
        stats = sim.stats
        return PointResult(
            index=index, status=1, message="", regime=regime.regime,
            impacts_per_period=_int_or(regime.impacts_per_period),
            period_cycles=_int_or(regime.period_cycles),
            strobe_mismatch=float(regime.strobe_mismatch),
            zero_one=_float_or(regime.zero_one),
            max_exponent=_float_or(max_exp), max_exponent_error=_float_or(max_err),
            transient_used=int(transient_used),
            corner_sequence=" ".join(regime.corner_sequence),
            exponents=exps, final_state=sim.strobe.state[-1].copy(),
            steps=stats.steps, rejected=stats.rejected, rhs_evals=stats.rhs_evals,
            wall_s=time.perf_counter() - started,
            impacts=_impact_columns(imp),
            strobe=sim.strobe.state,
        )
    except (SimulationError, SceneError, ValueError, FloatingPointError, ZeroDivisionError,
            OverflowError) as exc:
        return _failed_point(index, n_state, f"{type(exc).__name__}: {exc}", started)


def _initial_condition(system, initial: dict[str, float]) -> tuple[np.ndarray, float | None]:
    """The start of a basin scan's point: the system's initial state with the scanned
    components replaced, and the scanned initial phase (None: the system's start)."""
    from .grid import INITIAL_PHASE

    state, names = np.array(system.initial_state, dtype=np.float64), system.state_names
    for name, value in initial.items():
        if name != INITIAL_PHASE:
            state[list(names).index(name)] = value
    return state, initial.get(INITIAL_PHASE)


def _run_converged(point, n_exp: int, spec, index: int, start_state,
                   started: float) -> PointResult:
    """One point classified by :func:`~chaospound.dynamics.converged.classify_converged`
    (from the scene's initial state, or from ``start_state`` on a continuation branch).

    The stored record (impacts, sections, final state) is the window the label
    was read from; an unresolved point's message says why.
    """
    from .dynamics.converged import classify_converged
    from .dynamics.lyapunov import lyapunov_spectrum

    record = point.run.record if isinstance(point, Scene) else point.record
    outcome = classify_converged(point, start_state=start_state, record=record)
    regime, record = outcome.regime, outcome.record
    exps = errs = None
    max_exp, max_err = regime.max_exponent, regime.max_exponent_error
    if n_exp:
        spectrum = lyapunov_spectrum(point, k=n_exp, transient=0,
                                     initial_state=outcome.final_state,
                                     cycles=spec.lyapunov_cycles, tangent_transient=10)
        exps, errs = spectrum.exponents, spectrum.errors
        max_exp, max_err = float(exps[0]), float(errs[0])
    imp, stats = record.impacts, record.stats
    why = regime.evidence.get("why", "") if regime.regime == "unresolved" else ""
    return PointResult(
        index=index, status=1, message=why, regime=regime.regime,
        impacts_per_period=_int_or(regime.impacts_per_period),
        period_cycles=_int_or(regime.period_cycles),
        strobe_mismatch=float(regime.strobe_mismatch),
        zero_one=_float_or(regime.zero_one),
        max_exponent=_float_or(max_exp), max_exponent_error=_float_or(max_err),
        transient_used=int(regime.transient_used),
        corner_sequence=" ".join(regime.corner_sequence),
        exponents=exps, final_state=outcome.final_state,
        steps=stats.steps, rejected=stats.rejected, rhs_evals=stats.rhs_evals,
        wall_s=time.perf_counter() - started,
        impacts=_impact_columns(imp),
        strobe=record.strobe.state,
    )


class _Unclassified:
    """The regime fields of a point that cannot be classified (no gap function)."""

    regime = "unresolved"
    impacts_per_period = None
    period_cycles = None
    zero_one = None
    corner_sequence = ()

    def __init__(self, strobe_mismatch: float) -> None:
        self.strobe_mismatch = strobe_mismatch


def _failed_point(index: int, n_state: int, message: str, started: float) -> PointResult:
    empty = np.zeros(0)
    return PointResult(
        index=index, status=2, message=message.splitlines()[0] if message else "failed",
        regime="failed", impacts_per_period=-1, period_cycles=-1, strobe_mismatch=np.nan,
        zero_one=np.nan, max_exponent=np.nan, max_exponent_error=np.nan, transient_used=-1,
        corner_sequence="", exponents=None,
        final_state=np.full(n_state, np.nan), steps=0, rejected=0, rhs_evals=0,
        wall_s=time.perf_counter() - started,
        impacts={"time": empty, "phase": empty, "velocity": empty,
                 "corner": np.zeros(0, dtype=np.int8), "peak_penetration": empty,
                 "peak_force": empty, "duration": empty},
        strobe=np.zeros((0, n_state)),
    )


def _impact_columns(imp) -> dict:
    """The impact table's columns as a point stores them (corner codes as int8)."""
    return {"time": imp.time, "phase": imp.phase, "velocity": imp.velocity,
            "corner": imp.corner.astype(np.int8),
            "peak_penetration": imp.peak_penetration, "peak_force": imp.peak_force,
            "duration": imp.duration}


def _int_or(value, default: int = -1) -> int:
    return default if value is None else int(value)


def _float_or(value, default: float = np.nan) -> float:
    return default if value is None else float(value)
