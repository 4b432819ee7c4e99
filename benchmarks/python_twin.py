"""The pounding equations in plain Python: the baseline of the speed benchmark.

An independent transcription of docs/model.md sections 5-6, with the
closed-form line-contact moments of :mod:`chaospound.physics.contact.moments`, written
with ``math`` on Python floats, as a scipy user would write it.
``chaospound bench`` (:mod:`chaospound.bench`) integrates it with
``solve_ivp(RK45)`` as the "Python rhs" run; tests/test_bench.py checks it
against the composed engine's ``rhs`` to 1e-12.

It lives here, outside the package: it is a second copy of the physics, kept
only to measure against. :func:`chaospound.bench.load_python_twin` finds it in
a source checkout.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from chaospound.kernels.params import (
    MODEL_NAMES,
    P_BETA,
    P_CHI,
    P_GAP,
    P_GROUND,
    P_HALF_L,
    P_PERIOD_RATIO,
    P_Y_C,
    P_Y_OFF,
    PAIR,
    T_CT,
    T_CX,
    T_CY,
    T_EX,
    T_EY,
    T_KTH,
    T_MU,
    T_OM2,
    T_OMT2,
    T_RHO2,
    TOWER_A,
    TOWER_B,
    TOWER_WALL,
    TOWERS,
    WALL,
)
from chaospound.physics.contact.moments import EPS_SERIES, SERIES_MAX_TERMS, SERIES_RTOL

__all__ = ["python_fun", "python_rhs"]


def python_rhs(model: int, t: float, y: Sequence[float], p: Sequence[float]) -> list[float]:
    """Right-hand side of the pounding equations in plain Python (no numba).

    An independent transcription of docs/model.md sections 5-6 with the closed-form
    line-contact moments of :mod:`chaospound.physics.contact.moments`, written with
    ``math`` on Python floats, as a scipy user would write it. The benchmark's
    scipy baseline uses it; the tests check it against
    the composed engine's ``rhs``.

    Parameters
    ----------
    model : int
        Model id (:mod:`chaospound.kernels.params`).
    t : float
        Forcing time; the ground moves as ``u_g = sin(t / r)``.
    y : sequence of float
        State in the model's order.
    p : sequence of float
        Packed parameters (``Scene.pack``); a list is fastest.

    Returns
    -------
    list of float
        ``dy/dt``.
    """
    if p[P_GROUND] == 0.0:
        ug = vg = 0.0
    else:
        r = p[P_PERIOD_RATIO]
        ug = math.sin(t / r)
        vg = math.cos(t / r) / r
    if model == TOWERS:
        return _py_towers(y, p, ug, vg)
    if model == TOWER_WALL:
        return _py_tower_wall(y, p, ug, vg)
    if model == PAIR:
        return _py_pair(y, p, ug, vg)
    if model == WALL:
        return _py_wall(y, p, ug, vg)
    raise ValueError(f"model = {model!r}: must be one of 0 .. {len(MODEL_NAMES) - 1}")


def python_fun(model: int, p: np.ndarray) -> Callable[[float, np.ndarray], list[float]]:
    """``fun(t, y)`` for ``solve_ivp`` calling :func:`python_rhs`."""
    params = [float(v) for v in p]

    def fun(t, y):
        return python_rhs(model, t, y.tolist(), params)

    return fun


def _py_towers(y, p, ug, vg):
    """12-state towers model (docs/model.md 5-6): two towers, line contact between them."""
    x_a, vx_a, y_a, vy_a, th_a, vth_a, x_b, vx_b, y_b, vy_b, th_b, vth_b = y
    y_c = p[P_Y_C]
    y_ca = y_a + p[TOWER_A + T_EY]  # current CM heights
    y_cb = y_b + p[P_Y_OFF] + p[TOWER_B + T_EY]
    d_c = x_a - x_b - p[P_GAP] - th_a * (y_c - y_ca) + th_b * (y_c - y_cb)
    force, moment = _py_line_contact(d_c, th_b - th_a, p[P_HALF_L], p[P_BETA], p[P_CHI])
    q_tha = moment - (y_ca - y_c) * force
    q_thb = -(moment - (y_cb - y_c) * force)
    return _py_tower(
        p, TOWER_A, x_a, vx_a, y_a, vy_a, th_a, vth_a, ug, vg, -force, -th_a * force, q_tha
    ) + _py_tower(p, TOWER_B, x_b, vx_b, y_b, vy_b, th_b, vth_b, ug, vg,
                  force, th_b * force, q_thb)  # fmt: skip


def _py_tower_wall(y, p, ug, vg):
    """6-state model: tower A against a rigid wall riding on the ground."""
    x_a, vx_a, y_a, vy_a, th_a, vth_a = y
    y_c = p[P_Y_C]
    y_ca = y_a + p[TOWER_A + T_EY]
    d_c = x_a - ug - p[P_GAP] - th_a * (y_c - y_ca)
    force, moment = _py_line_contact(d_c, -th_a, p[P_HALF_L], p[P_BETA], p[P_CHI])
    q_tha = moment - (y_ca - y_c) * force
    return _py_tower(
        p, TOWER_A, x_a, vx_a, y_a, vy_a, th_a, vth_a, ug, vg, -force, -th_a * force, q_tha
    )


def _py_pair(y, p, ug, vg):
    """4-state translational pair (Chau & Wei 2001): point Hertz contact."""
    x_a, vx_a, x_b, vx_b = y
    d = x_a - x_b - p[P_GAP]
    force = p[P_BETA] * d ** p[P_CHI] if d > 0.0 else 0.0
    a, b = TOWER_A, TOWER_B
    return [
        vx_a,
        -p[a + T_CX] * (vx_a - vg) - p[a + T_OM2] * (x_a - ug) - p[a + T_MU] * force,
        vx_b,
        -p[b + T_CX] * (vx_b - vg) - p[b + T_OM2] * (x_b - ug) + p[b + T_MU] * force,
    ]


def _py_wall(y, p, ug, vg):
    """2-state model (Davis 1992): tower A's X against a ground-borne wall."""
    x_a, vx_a = y
    d = x_a - ug - p[P_GAP]
    force = p[P_BETA] * d ** p[P_CHI] if d > 0.0 else 0.0
    a = TOWER_A
    return [
        vx_a,
        -p[a + T_CX] * (vx_a - vg) - p[a + T_OM2] * (x_a - ug) - p[a + T_MU] * force,
    ]


def _py_tower(p, base, x, vx, yy, vy, th, vth, ug, vg, qx, qy, qth):
    """One tower's equations of motion (docs/model.md section 5), 6 derivatives."""
    om2 = p[base + T_OM2]
    mu = p[base + T_MU]
    ex = p[base + T_EX]
    ey = p[base + T_EY]
    xr = x - ug
    return [
        vx,
        -p[base + T_CX] * (vx - vg) - om2 * (xr + ey * th) + mu * qx,
        vy,
        -p[base + T_CY] * vy - om2 * (yy - ex * th) + mu * qy,
        vth,
        -p[base + T_CT] * vth
        - p[base + T_KTH] * (ey * xr - ex * yy)
        - p[base + T_OMT2] * th
        + mu * qth / p[base + T_RHO2],
    ]


def _py_line_contact(d_c, slope, half_length, beta, chi):
    """Force ``(beta/L) int d+^chi dy`` and moment ``(beta/L) int d+^chi (y - y_c) dy``."""
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0
    m0, m1 = _py_moments(chi, d_lo, d_hi)
    return beta * m0, beta * 2.0 * half_length * m1


def _py_moments(j, d_lo, d_hi):
    """``int_0^1 d+^j ds`` and ``int_0^1 d+^j (s - 1/2) ds`` for d linear in s.

    The three regimes of :func:`chaospound.physics.contact.moments.moments`: one end
    penetrating, nearly parallel (binomial series), clearly skewed.
    """
    if d_lo <= 0.0 or d_hi <= 0.0:  # one end only: the penetrated sub-interval
        if d_hi > 0.0:
            pen, other, sign = d_hi, d_lo, 1.0
        else:
            pen, other, sign = d_lo, d_hi, -1.0
        span = pen - other
        m0 = (pen / span) * pen**j / (j + 1.0)
        m1 = sign * m0 * (j * pen - (j + 2.0) * other) / (2.0 * (j + 2.0) * span)
        return m0, m1
    mean = 0.5 * (d_lo + d_hi)
    half_diff = 0.5 * (d_hi - d_lo)
    if abs(half_diff) < EPS_SERIES * mean:  # (1/2) int (1 + eps z)^j z^k dz, in powers of eps
        eps = half_diff / mean
        s0 = s1 = 0.0
        coef = power = 1.0
        for k in range(SERIES_MAX_TERMS):
            term = coef * power
            if k % 2 == 0:
                s0 += term / (k + 1.0)
            else:
                s1 += term / (k + 2.0)
            if k > 0 and abs(term) <= SERIES_RTOL * abs(s0):
                break
            coef *= (j - k) / (k + 1.0)
            power *= eps
        scale = mean**j
        return scale * s0, 0.5 * scale * s1
    delta = d_hi - d_lo  # skewed: antiderivatives at the ends
    hi1 = d_hi ** (j + 1.0)
    lo1 = d_lo ** (j + 1.0)
    diff1 = (hi1 - lo1) / (j + 1.0)
    diff2 = (hi1 * d_hi - lo1 * d_lo) / (j + 2.0)
    return diff1 / delta, (diff2 - mean * diff1) / (delta * delta)
