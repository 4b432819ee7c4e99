"""Explicit Runge-Kutta steps and dense-output preparation, as composition templates.

The functions below call the composition's right-hand side (``rhs`` at a time,
``rhs_grounded`` with the ground motion given) and its ground motion's carried
state (``ground_shifted``, ``ground_at_anchor``): :mod:`chaospound.engine.compose`
binds those, and the method's own names (``step``, ``dense_prepare``,
``step_error`` and the tableau ``TAB_A, TAB_B, TAB_C``) from its
:class:`.tableaux.Method`. Nothing here depends on the physics.

A step's contract::

    err, c0, c1 = step(t, h, y, f0, p, rtol, atol, K, y_new, f_new, c0, c1)
    if err <= 1.0:                      # accept
        dense_prepare(t, h, y, f0, y_new, f_new, p, K, Q)
        dense_eval(rows, Q, y, h, theta, out)       # state at t + theta h

Arrays are caller-allocated and the kernels never allocate: ``K`` has shape
``(MAX_STAGES, n)``, ``Q`` ``(MAX_DENSE, n)``. ``y_new`` and ``f_new`` must not
alias ``y``, ``f0`` or rows of ``K``; ``y_new`` doubles as the stage scratch
vector during a step. ``(c0, c1)`` is the ground motion's carried state at t
(:mod:`chaospound.physics.ground.sine`); a step returns it at ``t + h``.
The error measure is ``<= 1`` for acceptance: DOPRI5's RMS norm of
``err / (atol + rtol max(|y|, |y_new|))``, or the method's ``step_error``.
"""

import math

from chaospound.kernels.free import (
    ERROR_ORDER,
    GROUND,
    TAB_A,
    TAB_B,
    TAB_C,
    ground_at_anchor,
    ground_shifted,
    rhs,
    rhs_grounded,
    step_error,
)
from chaospound.kernels.jit import inline, kernel
from chaospound.solvers.tableaux import (
    _A21,
    _A31,
    _A32,
    _A41,
    _A42,
    _A43,
    _A51,
    _A52,
    _A53,
    _A54,
    _A61,
    _A62,
    _A63,
    _A64,
    _A65,
    _B1,
    _B3,
    _B4,
    _B5,
    _B6,
    _E1,
    _E3,
    _E4,
    _E5,
    _E6,
    _E7,
    DOP853_A,
    DOP853_C,
    DOP853_D,
    DOPRI5_DENSE,
    MAX_DENSE,
)

# ==== template ====


@kernel
def dopri5_step(t, h, y, f0, p, rtol, atol, K, y_new, f_new, c0, c1):
    """Unrolled Dormand-Prince 5(4) step; same results as the generic tableau loop.

    The ground motion at every stage comes from the carried state (angle
    addition for the sine: no library sine in the step; the driver resets it
    at each section). Returns ``(err, c0, c1)`` with the carried state at t + h.
    """
    n = y.shape[0]
    s1, k1 = ground_shifted(c0, c1, h, p, GROUND)
    ug_end, vg_end = ground_at_anchor(s1, k1, p, GROUND)  # stages 6 and 7 share t + h
    for i in range(n):
        K[0, i] = f0[i]
        y_new[i] = y[i] + h * (_A21 * f0[i])
    ug, vg = _ground_shifted(c0, c1, 0.2 * h, p)
    rhs_grounded(t + 0.2 * h, y_new, p, ug, vg, K[1])
    for i in range(n):
        y_new[i] = y[i] + h * (_A31 * K[0, i] + _A32 * K[1, i])
    ug, vg = _ground_shifted(c0, c1, 0.3 * h, p)
    rhs_grounded(t + 0.3 * h, y_new, p, ug, vg, K[2])
    for i in range(n):
        y_new[i] = y[i] + h * (_A41 * K[0, i] + _A42 * K[1, i] + _A43 * K[2, i])
    ug, vg = _ground_shifted(c0, c1, 0.8 * h, p)
    rhs_grounded(t + 0.8 * h, y_new, p, ug, vg, K[3])
    for i in range(n):
        y_new[i] = y[i] + h * (_A51 * K[0, i] + _A52 * K[1, i] + _A53 * K[2, i]
                               + _A54 * K[3, i])
    ug, vg = _ground_shifted(c0, c1, (8.0 / 9.0) * h, p)
    rhs_grounded(t + (8.0 / 9.0) * h, y_new, p, ug, vg, K[4])
    for i in range(n):
        y_new[i] = y[i] + h * (_A61 * K[0, i] + _A62 * K[1, i] + _A63 * K[2, i]
                               + _A64 * K[3, i] + _A65 * K[4, i])
    rhs_grounded(t + h, y_new, p, ug_end, vg_end, K[5])
    for i in range(n):
        y_new[i] = y[i] + h * (_B1 * K[0, i] + _B3 * K[2, i] + _B4 * K[3, i]
                               + _B5 * K[4, i] + _B6 * K[5, i])
    rhs_grounded(t + h, y_new, p, ug_end, vg_end, f_new)
    # the scaled errors first (a loop without a carried sum, which the compiler
    # vectorises), then their squares summed in the order of the components
    for i in range(n):
        K[6, i] = f_new[i]
        err = h * (_E1 * K[0, i] + _E3 * K[2, i] + _E4 * K[3, i] + _E5 * K[4, i]
                   + _E6 * K[5, i] + _E7 * f_new[i])
        scale = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        K[7, i] = err / scale
    total = 0.0
    for i in range(n):
        total += K[7, i] ** 2
    return math.sqrt(total / n), s1, k1


@inline
def _ground_shifted(c0, c1, shift, p):
    """``(u_g, u_g')`` at ``t + shift`` from the carried state at t."""
    s, k = ground_shifted(c0, c1, shift, p, GROUND)
    return ground_at_anchor(s, k, p, GROUND)


@kernel
def tableau_step(t, h, y, f0, p, rtol, atol, K, y_new, f_new, c0, c1):
    """One step of the generic explicit tableau ``TAB_A, TAB_B, TAB_C``.

    On return rows ``0 .. len(TAB_B)`` of K hold the stages and f_new, as the
    dense output expects. The ground is evaluated at each stage's time
    (``rhs``); the carried state is advanced for the driver.
    """
    _advance(t, h, y, f0, p, TAB_A, TAB_B, TAB_C, K, y_new, f_new)
    err = step_error(h, y, f0, y_new, K, rtol, atol)
    s1, k1 = ground_shifted(c0, c1, h, p, GROUND)
    return err, s1, k1


@kernel
def _advance(t, h, y, f0, p, a, b, c, K, y_new, f_new):
    """Stages of an explicit tableau, the new state and f_new (stored in K too).

    ``K[0] = f0``; ``K[s] = rhs(t + c_s h, y + h sum_j a_sj K[j])`` for
    ``s = 1 .. len(b) - 1``; ``y_new = y + h sum_j b_j K[j]``;
    ``f_new = K[len(b)] = rhs(t + h, y_new)``. y_new is the stage scratch.
    """
    n = y.shape[0]
    n_stages = b.shape[0]
    for i in range(n):
        K[0, i] = f0[i]
    for s in range(1, n_stages):
        _stage(t, h, y, p, a, c, s, K, y_new)
    for i in range(n):
        acc = 0.0
        for j in range(n_stages):
            if b[j] != 0.0:
                acc += b[j] * K[j, i]
        y_new[i] = y[i] + h * acc
    rhs(t + h, y_new, p, f_new)
    for i in range(n):
        K[n_stages, i] = f_new[i]


@kernel
def _stage(t, h, y, p, a, c, s, K, scratch):
    """Stage s: ``K[s] = rhs(t + c_s h, y + h sum_{j<s} a_sj K[j])``."""
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(s):
            if a[s, j] != 0.0:
                acc += a[s, j] * K[j, i]
        scratch[i] = y[i] + h * acc
    rhs(t + c[s] * h, scratch, p, K[s])


@kernel
def initial_step(t, y, f0, p, rtol, atol, work1, work2):
    """Hairer's automatic initial step (HNW I, sec. II.4; scipy select_initial_step).

    Uses the method's ERROR_ORDER. ``work1`` and ``work2`` are scratch arrays of
    length n (they receive ``y + h0 f0`` and its rhs). No upper bound is
    applied: the caller clips to its interval and max step.
    """
    n = y.shape[0]
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        scale = atol + abs(y[i]) * rtol
        d0 += (y[i] / scale) ** 2
        d1 += (f0[i] / scale) ** 2
    d0 = math.sqrt(d0 / n)
    d1 = math.sqrt(d1 / n)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    for i in range(n):
        work1[i] = y[i] + h0 * f0[i]
    rhs(t + h0, work1, p, work2)
    d2 = 0.0
    for i in range(n):
        scale = atol + abs(y[i]) * rtol
        d2 += ((work2[i] - f0[i]) / scale) ** 2
    d2 = math.sqrt(d2 / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (ERROR_ORDER + 1))
    return min(100.0 * h0, h1)


@kernel
def hermite_dense(t, h, y, f0, y_new, f_new, p, K, Q):
    """Rows 0-2 of ``Q``: the cubic Hermite interpolant of (y, f0, y_new, f_new)."""
    n = y.shape[0]
    for i in range(n):
        delta = y_new[i] - y[i]
        Q[0, i] = delta
        Q[1, i] = h * f0[i] - delta
        Q[2, i] = 2.0 * delta - h * (f0[i] + f_new[i])


@kernel
def dopri5_dense(t, h, y, f0, y_new, f_new, p, K, Q):
    """The 4th-order continuous extension of DOPRI5 (Hermite rows plus one)."""
    hermite_dense(t, h, y, f0, y_new, f_new, p, K, Q)
    n = y.shape[0]
    last = DOPRI5_DENSE.shape[0] - 1
    for i in range(n):
        acc = DOPRI5_DENSE[last] * f_new[i]
        for j in range(last):
            acc += DOPRI5_DENSE[j] * K[j, i]
        Q[3, i] = h * acc


@kernel
def dop853_dense(t, h, y, f0, y_new, f_new, p, K, Q):
    """The 7th-order interpolant of dop853 / scipy: 3 extra stages into rows 13-15 of K."""
    hermite_dense(t, h, y, f0, y_new, f_new, p, K, Q)
    n = y.shape[0]
    for i in range(n):
        K[12, i] = f_new[i]
    scratch = Q[MAX_DENSE - 1]
    for s in range(13, 16):
        _stage(t, h, y, p, DOP853_A, DOP853_C, s, K, scratch)
    for row in range(DOP853_D.shape[0]):
        for i in range(n):
            acc = 0.0
            for j in range(16):
                d = DOP853_D[row, j]
                if d != 0.0:
                    acc += d * K[j, i]
            Q[3 + row, i] = h * acc
