"""Convergence and consistency of the Runge-Kutta kernels.

The steppers of chaospound.solvers, composed into an engine.

Test problem: the PAIR model with a gap so large that the towers never touch,
i.e. two uncoupled linear damped oscillators driven through their base,

    x'' + c x' + k x = c u_g' + k u_g,     u_g = sin(w t),  w = 1 / r,

tower A: k = 1, c = 0.06; tower B: k = Om^2 = 2.25, c = 2 zeta Om = 0.09.
B is driven close to resonance (w^2 = 2.04), so the two components have quite
different amplitudes. From rest the exact response is the steady state
``Im(H e^{iwt})``, ``H = (k + i c w) / (k - w^2 + i c w)``, plus the damped free
vibration ``e^{-ct/2} (C1 cos w_d t + C2 sin w_d t)``, ``w_d = sqrt(k - c^2/4)``,
whose constants cancel the steady state's initial displacement and velocity.
"""

import math

import numpy as np
import pytest
from kernels_by_name import rhs, rk
from scipy.integrate import DOP853 as ScipyDOP853
from scipy.integrate import RK45 as ScipyRK45

from chaospound.kernels.params import (
    N_PARAMS,
    P_BETA,
    P_CHI,
    P_GAP,
    P_GROUND,
    P_PERIOD_RATIO,
    PAIR,
    T_CX,
    T_MU,
    T_OM2,
    TOWER_A,
    TOWER_B,
)

PERIOD_RATIO = 0.7
#: (block, Om_i, Om_i^2, mu_i, 2 zeta Om_i)
TOWER_DATA = ((TOWER_A, 1.0, 1.0, 1.0, 0.06), (TOWER_B, 1.5, 2.25, 2.25, 0.09))
T_END = 4.0 * math.pi  # two periods of tower A
N_STATE = 4
ALL_METHODS = (rk.DOPRI5, rk.CASH_KARP, rk.RK4, rk.DOP853)
ADAPTIVE = (rk.DOPRI5, rk.CASH_KARP, rk.DOP853)
NAMES = {m: rk.METHOD_NAMES[m] for m in ALL_METHODS}
ORDER_SLACK = 0.3


def _params():
    p = np.zeros(N_PARAMS)
    p[P_PERIOD_RATIO] = PERIOD_RATIO
    p[P_GROUND] = 1.0
    p[P_GAP] = 1e6
    p[P_BETA] = 1000.0
    p[P_CHI] = 1.5
    for base, _om, om2, mu, cx in TOWER_DATA:
        p[base + T_OM2] = om2
        p[base + T_MU] = mu
        p[base + T_CX] = cx
    return p


P = _params()


def _exact(t):
    """Closed-form response from rest, state (X_A, X_A', X_B, X_B')."""
    w = 1.0 / PERIOD_RATIO
    state = np.empty(N_STATE)
    for k, (_, _, stiffness, _, c) in enumerate(TOWER_DATA):
        gain = (stiffness + 1j * c * w) / (stiffness - w * w + 1j * c * w)
        x_p0 = gain.imag
        v_p0 = (1j * w * gain).imag
        w_d = math.sqrt(stiffness - 0.25 * c * c)
        c1 = -x_p0
        c2 = (-v_p0 + 0.5 * c * c1) / w_d
        decay = math.exp(-0.5 * c * t)
        cos_t = math.cos(w_d * t)
        sin_t = math.sin(w_d * t)
        steady = gain * complex(math.cos(w * t), math.sin(w * t))
        state[2 * k] = steady.imag + decay * (c1 * cos_t + c2 * sin_t)
        state[2 * k + 1] = (1j * w * steady).imag + decay * (
            (-0.5 * c * c1 + w_d * c2) * cos_t - (0.5 * c * c2 + w_d * c1) * sin_t
        )
    return state


def _f(t, y):
    out = np.empty(N_STATE)
    rhs(PAIR, t, y, P, out)
    return out


class _Work:
    """Caller-side arrays of the kernels."""

    def __init__(self):
        self.K = np.zeros((rk.MAX_STAGES, N_STATE))
        self.Q = np.zeros((rk.MAX_DENSE, N_STATE))
        self.y_new = np.empty(N_STATE)
        self.f_new = np.empty(N_STATE)
        self.out = np.empty(N_STATE)
        self.scratch = np.empty(N_STATE)


def _step(method, t, h, y, work, rtol=1e-6, atol=1e-6):
    """One step from (t, y); returns the error measure."""
    return rk.rk_step(method, PAIR, t, h, y, _f(t, y), P, rtol, atol,
                      work.K, work.y_new, work.f_new)


def _local_orders(hs, errors):
    hs = np.asarray(hs)
    errors = np.asarray(errors)
    return np.log(errors[:-1] / errors[1:]) / np.log(hs[:-1] / hs[1:])


def _fixed_step_error(method, n_steps, work):
    h = T_END / n_steps
    y = np.zeros(N_STATE)
    f0 = _f(0.0, y)
    for i in range(n_steps):
        rk.rk_step(method, PAIR, i * h, h, y, f0, P, 1e-6, 1e-6, work.K, work.y_new, work.f_new)
        y[:] = work.y_new
        f0[:] = work.f_new
    return np.max(np.abs(y - _exact(T_END)))


# ------------------------------------------------------------- the reference


def test_closed_form_solves_the_model():
    """The reference itself: starts at rest and satisfies y' = rhs(t, y)."""
    np.testing.assert_allclose(_exact(0.0), 0.0, atol=1e-14)
    delta = 1e-5
    for t in (0.3, 2.0, 7.7, T_END):
        slope = (_exact(t + delta) - _exact(t - delta)) / (2 * delta)
        np.testing.assert_allclose(slope, _f(t, _exact(t)), rtol=0, atol=1e-8)


# ----------------------------------------------------------- convergence orders

#: step counts over T_END in the asymptotic regime, above round-off
FIXED_STEPS = {
    rk.DOPRI5: (160, 320, 640),
    rk.CASH_KARP: (160, 320, 640),
    rk.RK4: (160, 320, 640),
    rk.DOP853: (20, 40, 80),
}


@pytest.mark.parametrize("method", ALL_METHODS, ids=NAMES.get)
def test_fixed_step_global_order(method):
    work = _Work()
    counts = FIXED_STEPS[method]
    errors = [_fixed_step_error(method, n, work) for n in counts]
    orders = _local_orders([T_END / n for n in counts], errors)
    assert np.all(np.abs(orders - rk.METHOD_ORDER[method]) < ORDER_SLACK), (errors, orders)


ESTIMATE_STEPS = {
    rk.DOPRI5: 2.0 ** -np.arange(4, 7),
    rk.CASH_KARP: 2.0 ** -np.arange(4, 7),
    rk.DOP853: 2.0 ** -np.arange(1, 5),
}


@pytest.mark.parametrize("method", ADAPTIVE, ids=NAMES.get)
def test_embedded_error_estimate_order(method):
    """One step from a state on the exact orbit: err ~ h^(ERROR_ORDER + 1)."""
    work = _Work()
    t = 1.3
    y = _exact(t)
    # unit absolute scale (Cash-Karp: rtol 1 and its own |y| + |h f| scale)
    rtol, atol = (1.0, 0.0) if method == rk.CASH_KARP else (0.0, 1.0)
    hs = ESTIMATE_STEPS[method]
    errors = [_step(method, t, h, y, work, rtol, atol) for h in hs]
    orders = _local_orders(hs, errors)
    assert np.all(np.abs(orders - (rk.ERROR_ORDER[method] + 1)) < ORDER_SLACK), (errors, orders)


#: steps for the dense-output order and the interpolant's own order q
DENSE_STEPS = {
    rk.DOPRI5: (2.0 ** -np.arange(3, 6), 4),
    rk.CASH_KARP: (2.0 ** -np.arange(2, 6), 3),
    rk.RK4: (2.0 ** -np.arange(3, 6), 3),
    rk.DOP853: (2.0 ** -np.arange(1, 4), 7),
}


def _dense(method, t, h, y, work):
    f0 = _f(t, y)
    rk.rk_step(method, PAIR, t, h, y, f0, P, 1e-6, 1e-6, work.K, work.y_new, work.f_new)
    rk.dense_prepare(method, PAIR, t, h, y, f0, work.y_new, work.f_new, P, work.K, work.Q)
    return f0


@pytest.mark.parametrize("method", ALL_METHODS, ids=NAMES.get)
def test_dense_output_order(method):
    """Max interpolation error over one step ~ h^(q + 1)."""
    work = _Work()
    t = 1.3
    y = _exact(t)
    hs, q = DENSE_STEPS[method]
    errors = []
    for h in hs:
        _dense(method, t, h, y, work)
        worst = 0.0
        for theta in np.linspace(0.0, 1.0, 41):
            rk.dense_eval(method, work.Q, y, h, theta, work.out)
            worst = max(worst, np.max(np.abs(work.out - _exact(t + theta * h))))
        errors.append(worst)
    orders = _local_orders(hs, errors)
    assert np.all(np.abs(orders - (q + 1)) < ORDER_SLACK), (errors, orders)


@pytest.mark.parametrize("method", ALL_METHODS, ids=NAMES.get)
def test_dense_output_endpoints_and_derivative(method):
    """u(0) = y exactly, u(1) = y_new to rounding, u' = f at both ends and = du/dt inside."""
    work = _Work()
    t, h = 2.1, 0.4
    y = _exact(t)
    f0 = _dense(method, t, h, y, work)
    eps = np.finfo(float).eps
    size = np.maximum(np.abs(y), np.abs(work.y_new))

    rk.dense_eval(method, work.Q, y, h, 0.0, work.out)
    assert np.array_equal(work.out, y)
    rk.dense_eval(method, work.Q, y, h, 1.0, work.out)
    assert np.all(np.abs(work.out - work.y_new) <= 2 * eps * size)

    rk.dense_eval_derivative(method, work.Q, y, h, 0.0, work.out)
    np.testing.assert_allclose(work.out, f0, rtol=0, atol=1e-13 * np.max(size) / h)
    rk.dense_eval_derivative(method, work.Q, y, h, 1.0, work.out)
    np.testing.assert_allclose(work.out, work.f_new, rtol=0, atol=1e-13 * np.max(size) / h)

    delta = 1e-5
    plus = np.empty(N_STATE)
    minus = np.empty(N_STATE)
    for theta in (0.1, 0.37, 0.5, 0.83):
        rk.dense_eval(method, work.Q, y, h, theta + delta, plus)
        rk.dense_eval(method, work.Q, y, h, theta - delta, minus)
        rk.dense_eval_derivative(method, work.Q, y, h, theta, work.out)
        finite = (plus - minus) / (2 * delta * h)
        np.testing.assert_allclose(work.out, finite, rtol=1e-7, atol=1e-8)


# ------------------------------------------------------- agreement with scipy


@pytest.mark.parametrize("method", (rk.DOPRI5, rk.DOP853), ids=NAMES.get)
def test_step_error_and_interpolant_agree_with_scipy(method):
    """Same step, error norm and continuous extension as scipy's RK45 / DOP853.

    scipy does not expose the error norm, but its accepted-step update
    ``h_abs = h * 0.9 * err ** (-1 / (ERROR_ORDER + 1))`` (no PI part, within
    its limits) gives it back.
    """
    work = _Work()
    t, h = 1.0, 0.25  # t + h exact in binary, so scipy takes exactly this step
    tol = 1e-5 if method == rk.DOPRI5 else 1e-9  # puts err in (1e-3, 1)
    y = _exact(t)
    f0 = _f(t, y)
    err = rk.rk_step(method, PAIR, t, h, y, f0, P, tol, tol, work.K, work.y_new, work.f_new)
    rk.dense_prepare(method, PAIR, t, h, y, f0, work.y_new, work.f_new, P, work.K, work.Q)
    assert 1e-3 < err < 1.0
    solver_class = ScipyRK45 if method == rk.DOPRI5 else ScipyDOP853
    solver = solver_class(_f, t, y, t + h, first_step=h, rtol=tol, atol=tol)
    solver.step()
    assert solver.t == t + h
    np.testing.assert_allclose(work.y_new, solver.y, rtol=1e-14, atol=1e-14)
    err_scipy = (solver.h_abs / (0.9 * h)) ** -(rk.ERROR_ORDER[method] + 1)
    # the error weights cancel strongly: summation order shows at ~1e-8
    assert err == pytest.approx(err_scipy, rel=1e-6)
    interpolant = solver.dense_output()
    for theta in np.linspace(0.0, 1.0, 9):
        rk.dense_eval(method, work.Q, y, h, theta, work.out)
        np.testing.assert_allclose(work.out, interpolant(t + theta * h), rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("method", ADAPTIVE, ids=NAMES.get)
@pytest.mark.parametrize("start", (0.0, 1.3))
def test_initial_step_matches_hairer_heuristic(method, start):
    """Same first step as scipy's select_initial_step for the method's error order."""
    y = _exact(start)
    f0 = _f(start, y)
    solver_class = ScipyDOP853 if method == rk.DOP853 else ScipyRK45
    for rtol in (1e-3, 1e-6, 1e-9):
        h = rk.initial_step(method, PAIR, start, y, f0, P, rtol, rtol,
                            np.empty(N_STATE), np.empty(N_STATE))
        reference = solver_class(_f, start, y, 1e9, rtol=rtol, atol=rtol).h_abs
        assert h == pytest.approx(reference, rel=1e-12)


# ----------------------------------------------------------------- FSAL / f_new


@pytest.mark.parametrize("method", ALL_METHODS, ids=NAMES.get)
def test_f_new_is_rhs_at_new_state(method):
    work = _Work()
    t, h = 3.2, 0.25
    _step(method, t, h, _exact(t), work)
    # DOPRI5 takes the ground's phase at t + h by angle addition from t: a few ulps
    assert np.allclose(work.f_new, _f(t + h, work.y_new), rtol=4e-16, atol=4e-16)
    assert np.array_equal(work.K[rk.N_STAGES[method]], work.f_new)


# --------------------------------------------------------------- adaptive loop


def _adaptive_worst_error(method, rtol):
    """Integrate 0..T_END adaptively; worst error relative to each component's amplitude."""
    work = _Work()
    amplitude = np.max(np.abs([_exact(s) for s in np.linspace(0.0, T_END, 2001)]), axis=0)
    atol = rtol
    t = 0.0
    y = np.zeros(N_STATE)
    f0 = _f(t, y)
    h = rk.initial_step(method, PAIR, t, y, f0, P, rtol, atol, work.out, work.scratch)
    err_prev = 1e-4
    rejected = False
    worst = 0.0
    attempts = 0
    while t < T_END:
        attempts += 1
        assert attempts < 10_000
        h = min(h, T_END - t)
        err = rk.rk_step(method, PAIR, t, h, y, f0, P, rtol, atol, work.K, work.y_new, work.f_new)
        factor = rk.step_factor(method, err, err_prev)
        if err <= 1.0:
            if rejected:
                factor = min(factor, 1.0)
            t = t + h
            y[:] = work.y_new
            f0[:] = work.f_new
            err_prev = max(err, 1e-4)
            rejected = False
            worst = max(worst, np.max(np.abs(y - _exact(t)) / amplitude))
        else:
            rejected = True
        h *= factor
    assert t == T_END
    return worst


@pytest.mark.parametrize(
    ("method", "rtol"),
    [
        (rk.DOPRI5, 1e-6),
        (rk.DOPRI5, 1e-9),
        (rk.DOP853, 1e-6),
        (rk.DOP853, 1e-9),
        (rk.CASH_KARP, 1e-3),
        (rk.CASH_KARP, 1e-6),
    ],
    ids=lambda v: NAMES[v] if isinstance(v, int) else f"{v:g}",
)
def test_adaptive_loop_meets_tolerance(method, rtol):
    worst = _adaptive_worst_error(method, rtol)
    assert worst < 10.0 * rtol, worst / rtol


# ------------------------------------------------------------- controllers


def test_step_factor_limits():
    """Hairer's and Press's documented bounds and regimes."""
    for method, low, high in (
        (rk.DOPRI5, 0.2, 10.0),
        (rk.DOP853, 1.0 / 3.0, 6.0),
        (rk.CASH_KARP, 0.1, 5.0),
    ):
        assert rk.step_factor(method, 0.0, 1e-4) == high
        assert rk.step_factor(method, 1e12, 1.0) == low
        assert rk.step_factor(method, math.nan, 1.0) == low
        assert rk.step_factor(method, 1.5, 1.0) < 1.0
        assert rk.step_factor(method, 0.1, 0.5) > 1.0
    # PI part: a smaller previous error damps the growth (err_prev ** beta)
    assert rk.step_factor(rk.DOPRI5, 0.5, 1e-4) < rk.step_factor(rk.DOPRI5, 0.5, 0.5)
    assert rk.step_factor(rk.DOPRI5, 0.5, 0.5) == pytest.approx(0.9 * 0.5 ** -0.17 * 0.5 ** 0.04)
    # rejection: I part only
    assert rk.step_factor(rk.DOPRI5, 2.0, 1e-4) == pytest.approx(0.9 * 2.0 ** -0.17)
    assert rk.step_factor(rk.DOP853, 0.5, 1.0) == pytest.approx(0.9 * 0.5 ** -0.125)
    # rkqs: 5x below ERRCON, SAFETY errmax^PGROW above, errmax^PSHRNK on rejection
    assert rk.step_factor(rk.CASH_KARP, 1e-4, 1.0) == 5.0
    assert rk.step_factor(rk.CASH_KARP, 0.01, 1.0) == pytest.approx(0.9 * 0.01 ** -0.2)
    assert rk.step_factor(rk.CASH_KARP, 3.0, 1.0) == pytest.approx(0.9 * 3.0 ** -0.25)
    assert rk.step_factor(rk.RK4, 123.0, 1.0) == 1.0
