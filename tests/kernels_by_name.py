"""The kernel-level tests' view of the engine: kernels looked up by model and method.

The kernel tests (test_rk, test_events, test_models, test_contact, ...) were written
against functions that took a model id and a method id. The engine no longer
dispatches on ids: each (model, law, ground, method) is a composed module
(:mod:`chaospound.engine.compose`). This adapter, in Python and for the tests
only, maps the ids to the composition and calls its kernels, so that the tests'
bodies, parameters and tolerances stay exactly what they were. The ground motion
is read from the packed vector's ``P_GROUND`` slot (1: sine, 0: none), as the
old kernels did.
"""

from __future__ import annotations

import functools
from types import SimpleNamespace

import numpy as np

from chaospound.engine import events as _events
from chaospound.engine.compose import Composition, engine_for
from chaospound.kernels.params import (
    DUFFING,
    LORENZ,
    MODEL_DIMS,
    P_GROUND,
    PAIR,
    TANGENT,
    TOWER_WALL,
    TOWERS,
    WALL,
)
from chaospound.physics.contact import hertz
from chaospound.physics.contact import moments as _moments
from chaospound.solvers import controllers, dense, tableaux

_MODELS = {WALL: "wall", TOWER_WALL: "tower-wall", PAIR: "pair", TOWERS: "towers",
           LORENZ: "lorenz", DUFFING: "duffing"}
_METHODS = ("dopri5", "cash-karp", "rk4", "dop853")


def kernels(model: int, p: np.ndarray, method: int = 0):
    """The composed module of a model id (``TANGENT + id`` for tangent), a method id
    and the ground motion of ``p``."""
    return _module(model, bool(p[P_GROUND] == 1.0), method)


@functools.cache  # tests call kernels per sample: build each Composition once
def _module(model: int, sine: bool, method: int):
    tangent = model >= TANGENT
    base = model - TANGENT if tangent else model
    return engine_for(Composition(_MODELS[base], ground="sine" if sine else "none",
                                  method=_METHODS[method],
                                  tangent="qr" if tangent else "none")).module


# ------------------------------------------------------------------ models


def _jacobian(model, t, y, p, jac):
    k = kernels(model, p)
    n = MODEL_DIMS[model]
    lin = k.model_linearize(t, y, p)
    unit = np.zeros(n)
    column = np.zeros(n)
    for c in range(n):
        unit[c] = 1.0
        k.model_jvp(p, lin, unit, column)
        unit[c] = 0.0
        jac[:, c] = column


models = SimpleNamespace(
    rhs=lambda model, t, y, p, out: kernels(model, p).rhs(t, y, p, out),
    contact_ends=lambda model, t, y, p, out: kernels(model, p).model_ends(t, y, p, out),
    penetration_rate=lambda model, t, y, p, y_at: kernels(model, p).model_rate(t, y, p, y_at),
    contact_forces=lambda model, t, y, p, q: kernels(model, p).model_forces(t, y, p, q),
    contact_potential=lambda model, t, y, p: kernels(model, p).model_potential(t, y, p),
    contact_force_rate=lambda model, t, y, p, e: kernels(model, p).model_force_rate(t, y, p, e),
    energy=lambda model, y, p: kernels(model, p).model_energy(y, p),
    jacobian_trace=lambda model, p: kernels(model, p).model_trace(p),
    jacobian=_jacobian,
)

# ------------------------------------------------------------------ methods

_BY_ID = [tableaux.METHODS[name] for name in _METHODS]
_CONTROLLERS = [getattr(controllers, m.controller) for m in _BY_ID]


def _rk_step(method, model, t, h, y, f0, p, rtol, atol, K, y_new, f_new):
    k = kernels(model, p, method)
    c0, c1 = k.ground_anchor(t, p, k.GROUND)
    err, _, _ = k.step(t, h, y, f0, p, rtol, atol, K, y_new, f_new, c0, c1)
    return err


rk = SimpleNamespace(
    DOPRI5=0, CASH_KARP=1, RK4=2, DOP853=3,
    METHOD_NAMES=_METHODS,
    METHOD_ORDER=tuple(m.order for m in _BY_ID),
    ERROR_ORDER=tuple(m.error_order for m in _BY_ID),
    NEW_EVALS=tuple(m.new_evals for m in _BY_ID),
    DENSE_EVALS=tuple(m.dense_evals for m in _BY_ID),
    N_STAGES=(6, 6, 4, 12),
    DENSE_ROWS=tuple(m.dense_rows for m in _BY_ID),
    MAX_STAGES=tableaux.MAX_STAGES,
    MAX_DENSE=tableaux.MAX_DENSE,
    rk_step=_rk_step,
    dense_prepare=lambda method, model, t, h, y, f0, y_new, f_new, p, K, Q: kernels(
        model, p, method).dense_prepare(t, h, y, f0, y_new, f_new, p, K, Q),
    dense_eval=lambda method, Q, y, h, theta, out: dense.dense_eval(
        _BY_ID[method].dense_rows, Q, y, h, theta, out),
    dense_eval_derivative=lambda method, Q, y, h, theta, out: dense.dense_eval_derivative(
        _BY_ID[method].dense_rows, Q, y, h, theta, out),
    step_factor=lambda method, err, err_prev: _CONTROLLERS[method](err, err_prev),
    initial_step=lambda method, model, t, y, f0, p, rtol, atol, w1, w2: kernels(
        model, p, method).initial_step(t, y, f0, p, rtol, atol, w1, w2),
)

# ------------------------------------------------------------------- events

events = SimpleNamespace(
    TIME_TOL=_events.TIME_TOL,
    EXTREMUM_TOL=_events.EXTREMUM_TOL,
    FORCE_RATE=_events.FORCE_RATE,
    end_value=lambda model, method, q, y, t, h, theta, p, which, work, ends: kernels(
        model, p, method).end_value(q, y, t, h, theta, p, which, work, ends),
    locate_root=lambda model, method, q, y, t, h, p, which, lo, f_lo, hi, f_hi, slope, work,
    ends: kernels(model, p, method).locate_root(q, y, t, h, p, which, lo, f_lo, hi, f_hi, slope,
                                                work, ends),
    locate_extremum=lambda model, method, q, y, t, h, p, end, r_lo, r_hi, work, ends: kernels(
        model, p, method).locate_extremum(q, y, t, h, p, end, r_lo, r_hi, work, ends),
)

# ------------------------------------------------------------------ contact


def _law(beta, chi):
    return np.array([beta, chi])


contact = SimpleNamespace(
    EPS_SERIES=_moments.EPS_SERIES,
    moments=_moments.moments,
    line_contact=lambda d_c, slope, half, beta, chi: hertz.line_force(
        _law(beta, chi), 0, d_c, slope, 0.0, 0.0, half),
    line_potential=lambda d_lo, d_hi, beta, chi: hertz.line_potential(
        _law(beta, chi), 0, d_lo, d_hi),
    line_contact_gradient=lambda d_lo, d_hi, half, beta, chi: hertz.line_gradient(
        _law(beta, chi), 0, d_lo, d_hi, 0.0, 0.0, half),
)

# the names the tests import directly
rhs = models.rhs
contact_ends = models.contact_ends
penetration_rate = models.penetration_rate
contact_forces = models.contact_forces
contact_potential = models.contact_potential
energy = models.energy
jacobian_trace = models.jacobian_trace
jacobian = models.jacobian
EPS_SERIES = contact.EPS_SERIES
moments = contact.moments
line_contact = contact.line_contact
line_potential = contact.line_potential
