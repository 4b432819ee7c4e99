"""The Runge-Kutta methods on closed forms, without a pounding model (issue 14, item 3).

Each method of :data:`chaospound.solvers.tableaux.METHODS` is composed with a user
system ``y' = A y`` (a damped rotation, eigenvalues -0.3 +- 2i), whose flow is
``expm(A t)``. Checked: the order of the propagated solution, the order of the
embedded error estimate, the order of the dense output, and the step-size
controllers' limits. A new explicit method is one ``Method`` in ``METHODS`` and it
joins these tests by itself.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from scipy.linalg import expm

from chaospound.dynamics.system import custom_system
from chaospound.solvers import controllers, dense
from chaospound.solvers.tableaux import MAX_DENSE, MAX_STAGES, METHODS

A = np.array([[-0.3, 2.0], [-2.0, -0.3]])


@njit(cache=True)
def rotation_rhs(t, y, q, out):
    out[0] = q[0] * y[0] + q[1] * y[1]
    out[1] = q[2] * y[0] + q[3] * y[1]


@njit(cache=True)
def rotation_jacobian(t, y, q, jac):
    jac[0, 0] = q[0]
    jac[0, 1] = q[1]
    jac[1, 0] = q[2]
    jac[1, 1] = q[3]


def _kernels(method: str):
    system = custom_system(rotation_rhs, rotation_jacobian, params=A.ravel(), period=1.0,
                           initial_state=(1.0, 0.0), method=method)
    return system.engine().module, system.params


class _Work:
    def __init__(self):
        self.K = np.zeros((MAX_STAGES, 2))
        self.Q = np.zeros((MAX_DENSE, 2))
        self.y_new = np.empty(2)
        self.f_new = np.empty(2)
        self.f0 = np.empty(2)


def _step(kernels, p, t, h, y, work, rtol=1e-3, atol=1e-6):
    kernels.rhs(t, y, p, work.f0)
    err, _, _ = kernels.step(t, h, y, work.f0, p, rtol, atol, work.K, work.y_new, work.f_new,
                             0.0, 1.0)
    return err


def _global_error(kernels, p, n_steps: int, t_end: float = 2.0) -> float:
    work = _Work()
    y = np.array([1.0, 0.0])
    h = t_end / n_steps
    for i in range(n_steps):
        _step(kernels, p, i * h, h, y, work)
        y = work.y_new.copy()
    return float(np.max(np.abs(y - expm(A * t_end) @ [1.0, 0.0])))


@pytest.mark.parametrize("name", list(METHODS))
def test_order_of_the_propagated_solution(name):
    method = METHODS[name]
    kernels, p = _kernels(name)
    steps = (4, 8, 16) if method.order >= 8 else (16, 32, 64)  # above round-off
    errors = [_global_error(kernels, p, n) for n in steps]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - method.order) < 0.35), (errors, orders)


def test_the_embedded_estimate_of_dopri5_is_its_local_error_of_order_5():
    kernels, p = _kernels("dopri5")
    estimates = []
    for h in (0.2, 0.1, 0.05):
        # rtol 0, atol 1: the RMS of the raw estimate of one step
        estimates.append(_step(kernels, p, 0.0, h, np.array([1.0, 0.0]), _Work(), 0.0, 1.0))
    orders = np.log2(np.array(estimates[:-1]) / np.array(estimates[1:]))
    assert np.all(np.abs(orders - 5.0) < 0.3), orders


@pytest.mark.parametrize("name, local_order, steps", [
    ("dopri5", 5, (0.1, 0.05, 0.025)), ("cash-karp", 4, (0.05, 0.025, 0.0125)),
    ("rk4", 4, (0.05, 0.025, 0.0125)), ("dop853", 8, (0.4, 0.2, 0.1))])
def test_dense_output_order(name, local_order, steps):
    """Mid-step interpolation error of one step ~ h^(q+1): q = 4 (DOPRI5's continuous
    extension), 3 (cubic Hermite), 7 (DOP853's)."""
    method = METHODS[name]
    kernels, p = _kernels(name)
    y0 = np.array([1.0, 0.0])
    errors = []
    for h in steps:
        work = _Work()
        _step(kernels, p, 0.0, h, y0, work)
        kernels.dense_prepare(0.0, h, y0, work.f0, work.y_new, work.f_new, p, work.K, work.Q)
        out = np.empty(2)
        dense.dense_eval(method.dense_rows, work.Q, y0, h, 0.5, out)
        errors.append(np.max(np.abs(out - expm(A * 0.5 * h) @ y0)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - local_order) < 0.4), (errors, orders)


@pytest.mark.parametrize("name, low, high", [("pi_factor", 0.2, 10.0),
                                             ("rkqs_factor", 0.1, 5.0),
                                             ("dop853_factor", 1.0 / 3.0, 6.0),
                                             ("fixed_factor", 1.0, 1.0)])
def test_controllers_stay_in_their_limits_and_shrink_with_the_error(name, low, high):
    factor = getattr(controllers, name)
    errors = np.logspace(-12, 6, 200)
    values = np.array([factor(e, 1e-2) for e in errors])
    assert np.all(values >= low - 1e-15) and np.all(values <= high + 1e-15)
    # a larger error never grows the step more, among accepted and among rejected steps
    # (Hairer's PI controller drops its memory term on rejection, so the factor may
    # rise as the error crosses 1)
    for side in (errors <= 1.0, errors > 1.0):
        assert np.all(np.diff(values[side]) <= 1e-15)
    if name != "fixed_factor":
        assert factor(2.0, 1e-2) < 1.0  # a rejected step shrinks
        assert factor(float("nan"), 1e-2) == low  # a non-finite error: the smallest factor
