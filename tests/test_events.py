"""Event location on a step's interpolant (the templates of chaospound.engine.events, composed).

The root finder of the contact events refines roots of the end penetrations
by Newton's method, using the interpolated penetration *rate* as the
derivative (the rate interpolates the velocities, so it is only close to the
derivative of the interpolated penetration), pushed past the estimate so that
the bracket closes. Whatever the interpolant, the contract is the bracket's:
the returned theta is on the far side of the sign change and the near side
lies within TIME_TOL in time. Checked here on random cubic Hermite
interpolants of the PAIR model (``d = X_A - X_B - gap``), with and without a
usable slope at the bracket's upper end, and on rates (extrema, EXTREMUM_TOL).
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from kernels_by_name import events, rk

from chaospound.kernels.params import N_PARAMS, P_GAP, P_GROUND, P_PERIOD_RATIO, PAIR

GAP = 0.5
finite = st.floats(-3.0, 3.0, allow_nan=False)


def _params():
    p = np.zeros(N_PARAMS)
    p[P_PERIOD_RATIO] = 0.7
    p[P_GROUND] = 0.0
    p[P_GAP] = GAP
    return p


def _hermite(y0, y1, f0, f1, h):
    """Dense rows of the cubic Hermite interpolant (rk.RK4's, via dense_prepare)."""
    q = np.zeros((rk.MAX_DENSE, 4))
    k = np.zeros((rk.MAX_STAGES, 4))
    rk.dense_prepare(rk.RK4, PAIR, 0.0, h, y0, f0, y1, f1, _params(), k, q)
    return q


def _value(q, y0, h, theta, which):
    work = np.empty(4)
    ends = np.empty(4)
    return events.end_value(PAIR, rk.RK4, q, y0, 0.0, h, theta, _params(), which, work, ends)


@settings(max_examples=300, deadline=None)
@given(x0=finite, x1=finite, v0=finite, v1=finite, a0=finite, a1=finite,
       h=st.floats(1e-3, 0.5), use_slope=st.booleans())
def test_crossing_root_brackets_a_sign_change_within_time_tol(x0, x1, v0, v1, a0, a1, h,
                                                              use_slope):
    # tower B at rest at 0: d = x_A - GAP, rate = v_A
    y0 = np.array([x0, v0, 0.0, 0.0])
    y1 = np.array([x1, v1, 0.0, 0.0])
    f0 = np.array([v0, a0, 0.0, 0.0])
    f1 = np.array([v1, a1, 0.0, 0.0])
    d0, d1 = x0 - GAP, x1 - GAP
    if d0 == 0.0 or d1 == 0.0 or (d0 > 0.0) == (d1 > 0.0):
        return
    q = _hermite(y0, y1, f0, f1, h)
    slope = h * v1 if use_slope else 0.0
    theta = events.locate_root(PAIR, rk.RK4, q, y0, 0.0, h, _params(), 0, 0.0, d0, 1.0, d1,
                               slope, np.empty(4), np.empty(4))
    assert 0.0 < theta <= 1.0
    far = _value(q, y0, h, theta, 0)
    assert far == 0.0 or (far > 0.0) == (d1 > 0.0)
    near = _value(q, y0, h, max(theta - events.TIME_TOL / h, 0.0), 0)
    assert near == 0.0 or (near > 0.0) != (d1 > 0.0) or theta - events.TIME_TOL / h <= 0.0


@settings(max_examples=100, deadline=None)
@given(v0=st.floats(0.1, 3.0), v1=st.floats(-3.0, -0.1), h=st.floats(1e-3, 0.5))
def test_extremum_of_the_penetration_is_located_to_extremum_tol(v0, v1, h):
    """A rate that turns from + to - inside the step: its root is the maximum of d."""
    y0 = np.array([0.0, v0, 0.0, 0.0])
    y1 = np.array([0.0, v1, 0.0, 0.0])
    f0 = np.array([v0, (v1 - v0) / h, 0.0, 0.0])
    f1 = np.array([v1, (v1 - v0) / h, 0.0, 0.0])
    q = _hermite(y0, y1, f0, f1, h)
    theta = events.locate_extremum(PAIR, rk.RK4, q, y0, 0.0, h, _params(), 0, v0, v1,
                                   np.empty(4), np.empty(4))
    # the interpolated velocity is linear here: it vanishes at v0 / (v0 - v1)
    assert abs(theta - v0 / (v0 - v1)) * h <= 2.0 * events.EXTREMUM_TOL
