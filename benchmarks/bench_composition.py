"""Historical: the measurement behind the redesign (docs/design/composition.md),
made on the id-dispatching kernels of commit 3fe32a0, which it copies in reduced
form and checks against ``chaospound.kernels.models``, ``rk`` and ``params``. Those
modules are gone since the composed engine replaced them; rerun it from a checkout
of 3fe32a0 (``git worktree add /tmp/old 3fe32a0``). The composed engine's own gate
is ``benchmarks/bench_versus.py`` and ``benchmarks/golden.py``.

How to compose the jitted engine: direct calls, dispatcher arguments,
first-class function types, generated modules or closures (issue 14).

A self-contained reduced copy of chaospound's hot path: the adaptive
Dormand-Prince 5(4) loop of ``kernels/rk.py`` (``dopri5_step``: 7 right-hand
side evaluations per step, the ground's phase carried by angle addition,
Hairer's PI controller of ``step_factor``) over the 12-state towers model of
``kernels/models.py`` (``_rhs_towers``, ``_tower_accel``) with the Hertz line
contact of ``kernels/contact.py`` (``line_contact``, ``force_moments``,
``moments``), copied verbatim with the model id switches removed. No events,
no sections: a fixed time span (48 excitation periods of fig3a by default,
from rest). The copy is checked bitwise against chaospound's own
``rhs_grounded`` and ``dopri5_step`` before anything is timed.

Variants of how the engine gets its right-hand side:

a  direct     the engine calls a module-level njit function (today's style)
b  dispatcher the right-hand side is a plain njit dispatcher argument
c  ftype      the argument is declared ``types.FunctionType(sig)`` (explicit
              signatures; an indirect call through a function pointer)
d  generated  a module with the engine's source and the composition's
              imports is written to a cache folder, keyed by a hash of the
              engine text and of the composed functions' source files,
              imported and compiled with cache=True (direct calls again)
e  closure    ``make_engine(rhs)`` returns an njit closure over rhs

Measured: per-step time relative to (a) in interleaved rounds; compile time
in a fresh process and load time in a second fresh process on the same cold
NUMBA_CACHE_DIR (cache hits and misses from numba's dispatcher stats);
bitwise equality of the final state with (a); instructions per step under
``valgrind --tool=callgrind`` (instrumentation switched on around the solve
only); and the first run of today's built-in kernels (``simulate(fig3a)``)
on a cold cache, with every dispatcher's compile time.

Usage::

    python benchmarks/bench_composition.py [--rounds 31] [--repeats 5] [--cycles 48]
        [--no-callgrind] [--no-builtin] [--output results/bench_composition.json]
"""

from __future__ import annotations

import os
import sys
import tempfile

if __name__ == "__main__":  # run as the importable module, so that children can import it
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import bench_composition

    bench_composition.main()
    raise SystemExit(0)

# the parent's own kernels never land in the repository's __pycache__
if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="bench_composition_parent_")

import argparse  # noqa: E402
import hashlib  # noqa: E402
import importlib  # noqa: E402
import inspect  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import resource  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402
from numba import njit, types  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DEFAULT_OUTPUT = ROOT / "results" / "bench_composition.json"
MODULE = "bench_composition"

kernel = njit(cache=True, _nrt=False, error_model="numpy")
inline = njit(cache=True, _nrt=False, error_model="numpy", forceinline=True)

# ====================================================== parameter layout (params.py)
P_PERIOD_RATIO = 0
P_GROUND = 1
P_GAP = 2
P_BETA = 3
P_CHI = 4
P_Y_C = 5
P_HALF_L = 6
P_Y_OFF = 7
P_PERIOD = 9
TOWER_A = 10
TOWER_B = 30
T_OM2 = 1
T_MU = 2
T_CX = 3
T_CY = 4
T_CT = 5
T_EX = 6
T_EY = 7
T_OMT2 = 9
T_KTH = 12
T_MU_RHO2 = 13

# ================================================= powers and ground (powers.py)


@inline
def power(x, e):
    if e == 1.5:
        return x * math.sqrt(x)
    if e == 2.5:
        return x * x * math.sqrt(x)
    if e == 0.5:
        return math.sqrt(x)
    if e == 1.0:
        return x
    if e == 2.0:
        return x * x
    if e == 3.0:
        return x * x * x
    if e == 0.0:
        return 1.0
    return x**e


SHIFT_MAX = 0.3
_S1 = -1.0 / 6.0
_S2 = 1.0 / 120.0
_S3 = -1.0 / 5040.0
_S4 = 1.0 / 362880.0
_S5 = -1.0 / 39916800.0
_S6 = 1.0 / 6227020800.0
_C1 = -0.5
_C2 = 1.0 / 24.0
_C3 = -1.0 / 720.0
_C4 = 1.0 / 40320.0
_C5 = -1.0 / 3628800.0
_C6 = 1.0 / 479001600.0
_C7 = -1.0 / 87178291200.0


@inline
def phase_shifted(sin0, cos0, shift, p):
    if p[P_GROUND] == 0.0:
        return 0.0, 1.0
    x = shift / p[P_PERIOD_RATIO]
    if abs(x) <= SHIFT_MAX:
        x2 = x * x
        sin_x = x + x * x2 * (_S1 + x2 * (_S2 + x2 * (_S3 + x2 * (_S4 + x2 * (_S5 + x2 * _S6)))))
        cos_x = 1.0 + x2 * (_C1 + x2 * (_C2 + x2 * (_C3 + x2 * (_C4 + x2 * (_C5 + x2 * (
            _C6 + x2 * _C7))))))
    else:
        sin_x = math.sin(x)
        cos_x = math.cos(x)
    return sin0 * cos_x + cos0 * sin_x, cos0 * cos_x - sin0 * sin_x


@inline
def ground_shifted(sin0, cos0, shift, p):
    if p[P_GROUND] == 0.0:
        return 0.0, 0.0
    sin_t, cos_t = phase_shifted(sin0, cos0, shift, p)
    return sin_t, cos_t / p[P_PERIOD_RATIO]


@inline
def ground_phase(t, p):
    if p[P_GROUND] == 0.0:
        return 0.0, 1.0
    arg = t / p[P_PERIOD_RATIO]
    return math.sin(arg), math.cos(arg)


@inline
def ground_at_phase(sin_x, cos_x, p):
    if p[P_GROUND] == 0.0:
        return 0.0, 0.0
    return sin_x, cos_x / p[P_PERIOD_RATIO]


# ===================================================== Hertz line contact (contact.py)
EPS_SERIES = 0.2
SERIES_RTOL = 1e-17
SERIES_MAX_TERMS = 80
_RECIP = 1.0 / np.arange(1.0, SERIES_MAX_TERMS + 5.0)
_RECIP = np.concatenate((np.array([np.inf]), _RECIP))


@kernel
def moments(j, d_lo, d_hi):
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, 0.0
    if d_lo <= 0.0 or d_hi <= 0.0:
        return _moments_partial(j, d_lo, d_hi)
    mean = 0.5 * (d_lo + d_hi)
    half_diff = 0.5 * (d_hi - d_lo)
    if abs(half_diff) < EPS_SERIES * mean:
        return _moments_series(j, mean, half_diff / mean)
    return _moments_skewed(j, d_lo, d_hi, mean)


@kernel
def _moments_series(j, mean, eps):
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    coef = 1.0
    eps_k = 1.0
    for k in range(0, SERIES_MAX_TERMS, 2):
        even = coef * eps_k
        s0 += even * _RECIP[k + 1]
        s2 += even * _RECIP[k + 3]
        coef *= (j - k) * _RECIP[k + 1]
        eps_k *= eps
        odd = coef * eps_k
        s1 += odd * _RECIP[k + 3]
        coef *= (j - k - 1.0) * _RECIP[k + 2]
        eps_k *= eps
        if abs(even) + abs(odd) <= SERIES_RTOL * abs(s0):
            break
    scale = power(mean, j)
    return scale * s0, 0.5 * scale * s1, 0.25 * scale * s2


@kernel
def _moments_partial(j, d_lo, d_hi):
    if d_hi > 0.0:
        p, q, sign = d_hi, d_lo, 1.0
    else:
        p, q, sign = d_lo, d_hi, -1.0
    m0, m1, frac = _partial_01(j, p, q, sign)
    m2 = m0 * (0.25 - frac / (j + 2.0) + 2.0 * frac * frac / ((j + 2.0) * (j + 3.0)))
    return m0, m1, m2


@inline
def _partial_01(j, p, q, sign):
    span = p - q
    frac = p / span
    rest = -q / span
    inv_12 = 1.0 / ((j + 1.0) * (j + 2.0))
    m0 = frac * power(p, j) * ((j + 2.0) * inv_12)
    m1 = sign * m0 * (j * frac + (j + 2.0) * rest) * (0.5 * (j + 1.0) * inv_12)
    return m0, m1, frac


@inline
def force_moments(j, d_lo, d_hi):
    if d_hi > 0.0 and d_lo <= 0.0:
        m0, m1, _ = _partial_01(j, d_hi, d_lo, 1.0)
        return m0, m1
    if d_lo > 0.0 and d_hi <= 0.0:
        m0, m1, _ = _partial_01(j, d_lo, d_hi, -1.0)
        return m0, m1
    m0, m1, _ = moments(j, d_lo, d_hi)
    return m0, m1


@kernel
def _moments_skewed(j, d_lo, d_hi, mean):
    delta = d_hi - d_lo
    hi1 = power(d_hi, j + 1.0)
    lo1 = power(d_lo, j + 1.0)
    hi2 = hi1 * d_hi
    lo2 = lo1 * d_lo
    diff1 = (hi1 - lo1) / (j + 1.0)
    diff2 = (hi2 - lo2) / (j + 2.0)
    diff3 = (hi2 * d_hi - lo2 * d_lo) / (j + 3.0)
    m0 = diff1 / delta
    m1 = (diff2 - mean * diff1) / (delta * delta)
    m2 = (diff3 - 2.0 * mean * diff2 + mean * mean * diff1) / (delta * delta * delta)
    return m0, m1, m2


@inline
def line_contact(d_c, slope, half_length, beta, chi):
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, d_lo, d_hi
    m0, m1 = force_moments(chi, d_lo, d_hi)
    return beta * m0, beta * 2.0 * half_length * m1, d_lo, d_hi


# ======================================================== towers model (models.py)


@inline
def _tower_accel(p, base, x, vx, yy, vy, th, vth, ug, vg, qx, qy, qth, out, off):
    om2 = p[base + T_OM2]
    mu = p[base + T_MU]
    ex = p[base + T_EX]
    ey = p[base + T_EY]
    xr = x - ug
    out[off] = vx
    out[off + 1] = -p[base + T_CX] * (vx - vg) - om2 * (xr + ey * th) + mu * qx
    out[off + 2] = vy
    out[off + 3] = -p[base + T_CY] * vy - om2 * (yy - ex * th) + mu * qy
    out[off + 4] = vth
    out[off + 5] = (
        -p[base + T_CT] * vth
        - p[base + T_KTH] * (ey * xr - ex * yy)
        - p[base + T_OMT2] * th
        + p[base + T_MU_RHO2] * qth
    )


@kernel
def towers_rhs(t, y, p, ug, vg, out):
    """``_rhs_towers`` of models.py as the out-of-line ``rhs_grounded`` (model bodies inlined)."""
    th_a = y[4]
    th_b = y[10]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
    d_c = y[0] - y[6] - p[P_GAP] - th_a * (y_c - y_ca) + th_b * (y_c - y_cb)
    force, moment, _, _ = line_contact(d_c, th_b - th_a, p[P_HALF_L], p[P_BETA], p[P_CHI])
    q_tha = moment - (y_ca - y_c) * force
    q_thb = -(moment - (y_cb - y_c) * force)
    _tower_accel(p, TOWER_A, y[0], y[1], y[2], y[3], th_a, y[5], ug, vg,
                 -force, -th_a * force, q_tha, out, 0)
    _tower_accel(p, TOWER_B, y[6], y[7], y[8], y[9], th_b, y[11], ug, vg,
                 force, th_b * force, q_thb, out, 6)


#: signature of a right-hand side: (t, y, p, u_g, u_g', out)
VEC = types.float64[::1]
RHS_SIG = types.void(types.float64, VEC, VEC, types.float64, types.float64, VEC)
RHS_TYPE = types.FunctionType(RHS_SIG)

#: (a) and the generated modules call the global name ``rhs``
rhs = towers_rhs

# ================================================= Dormand-Prince 5(4) (rk.py)
_A21 = 1 / 5
_A31, _A32 = 3 / 40, 9 / 40
_A41, _A42, _A43 = 44 / 45, -56 / 15, 32 / 9
_A51, _A52, _A53, _A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
_A61, _A62, _A63, _A64, _A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
_B1, _B3, _B4, _B5, _B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
_E1, _E3, _E4, _E5, _E6, _E7 = (-71 / 57600, 71 / 16695, -71 / 1920, 17253 / 339200,
                                -22 / 525, 1 / 40)
SAFETY = 0.9
BETA = 0.04
EXPONENT = 0.2 - 0.75 * BETA
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
ERR_FLOOR = 1.0e-4


@inline
def step_factor(err, err_prev):
    """rk.step_factor for DOPRI5."""
    rejected = not (err <= 1.0)
    if rejected:
        if math.isnan(err):
            return MIN_FACTOR
        factor = SAFETY * math.exp(-EXPONENT * math.log(err))
        return min(1.0, max(MIN_FACTOR, factor))
    if err == 0.0:
        return MAX_FACTOR
    prev = max(err_prev, ERR_FLOOR)
    factor = SAFETY * math.exp(BETA * math.log(prev) - EXPONENT * math.log(err))
    return min(MAX_FACTOR, max(MIN_FACTOR, factor))


# ---------------------------------------------------------- (a): direct calls
# The engine text of (a) is also the engine text of every generated module (d).


@kernel
def dp5_step(t, h, y, f0, p, rtol, atol, K, y_new, f_new, sin0, cos0):
    n = y.shape[0]
    sin1, cos1 = phase_shifted(sin0, cos0, h, p)
    ug_end, vg_end = ground_at_phase(sin1, cos1, p)
    for i in range(n):
        K[0, i] = f0[i]
        y_new[i] = y[i] + h * (_A21 * f0[i])
    ug, vg = ground_shifted(sin0, cos0, 0.2 * h, p)
    rhs(t + 0.2 * h, y_new, p, ug, vg, K[1])
    for i in range(n):
        y_new[i] = y[i] + h * (_A31 * K[0, i] + _A32 * K[1, i])
    ug, vg = ground_shifted(sin0, cos0, 0.3 * h, p)
    rhs(t + 0.3 * h, y_new, p, ug, vg, K[2])
    for i in range(n):
        y_new[i] = y[i] + h * (_A41 * K[0, i] + _A42 * K[1, i] + _A43 * K[2, i])
    ug, vg = ground_shifted(sin0, cos0, 0.8 * h, p)
    rhs(t + 0.8 * h, y_new, p, ug, vg, K[3])
    for i in range(n):
        y_new[i] = y[i] + h * (_A51 * K[0, i] + _A52 * K[1, i] + _A53 * K[2, i]
                               + _A54 * K[3, i])
    ug, vg = ground_shifted(sin0, cos0, (8.0 / 9.0) * h, p)
    rhs(t + (8.0 / 9.0) * h, y_new, p, ug, vg, K[4])
    for i in range(n):
        y_new[i] = y[i] + h * (_A61 * K[0, i] + _A62 * K[1, i] + _A63 * K[2, i]
                               + _A64 * K[3, i] + _A65 * K[4, i])
    rhs(t + h, y_new, p, ug_end, vg_end, K[5])
    for i in range(n):
        y_new[i] = y[i] + h * (_B1 * K[0, i] + _B3 * K[2, i] + _B4 * K[3, i]
                               + _B5 * K[4, i] + _B6 * K[5, i])
    rhs(t + h, y_new, p, ug_end, vg_end, f_new)
    total = 0.0
    for i in range(n):
        K[6, i] = f_new[i]
        err = h * (_E1 * K[0, i] + _E3 * K[2, i] + _E4 * K[3, i] + _E5 * K[4, i]
                   + _E6 * K[5, i] + _E7 * f_new[i])
        scale = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        total += (err / scale) ** 2
    return math.sqrt(total / n), sin1, cos1


@kernel
def solve_direct(y, p, t_end, rtol, atol, h, work, stats):
    """Adaptive DP5 from t = 0 to t_end; ``work`` (10, n); stats: accepted, rejected, t."""
    n = y.shape[0]
    K = work[0:7]
    f0 = work[7]
    y_new = work[8]
    f_new = work[9]
    t = 0.0
    sin0, cos0 = ground_phase(t, p)
    ug, vg = ground_at_phase(sin0, cos0, p)
    rhs(t, y, p, ug, vg, f0)
    err_prev = ERR_FLOOR
    accepted = 0
    rejected = 0
    while t < t_end:
        if t + h > t_end:
            h = t_end - t
        err, sin1, cos1 = dp5_step(t, h, y, f0, p, rtol, atol, K, y_new, f_new, sin0, cos0)
        factor = step_factor(err, err_prev)
        if err <= 1.0:
            t += h
            for i in range(n):
                y[i] = y_new[i]
                f0[i] = f_new[i]
            sin0 = sin1
            cos0 = cos1
            err_prev = max(err, ERR_FLOOR)
            accepted += 1
        else:
            rejected += 1
        h *= factor
        if h < 1e-14:
            break
    stats[0] = accepted
    stats[1] = rejected
    stats[2] = t


# ----------------------------------------- the same engine with rhs as an argument
# (b), (c) and (e) use it; line for line the text of (a) with ``rhs`` a parameter.


@kernel
def dp5_step_arg(rhs, t, h, y, f0, p, rtol, atol, K, y_new, f_new, sin0, cos0):
    n = y.shape[0]
    sin1, cos1 = phase_shifted(sin0, cos0, h, p)
    ug_end, vg_end = ground_at_phase(sin1, cos1, p)
    for i in range(n):
        K[0, i] = f0[i]
        y_new[i] = y[i] + h * (_A21 * f0[i])
    ug, vg = ground_shifted(sin0, cos0, 0.2 * h, p)
    rhs(t + 0.2 * h, y_new, p, ug, vg, K[1])
    for i in range(n):
        y_new[i] = y[i] + h * (_A31 * K[0, i] + _A32 * K[1, i])
    ug, vg = ground_shifted(sin0, cos0, 0.3 * h, p)
    rhs(t + 0.3 * h, y_new, p, ug, vg, K[2])
    for i in range(n):
        y_new[i] = y[i] + h * (_A41 * K[0, i] + _A42 * K[1, i] + _A43 * K[2, i])
    ug, vg = ground_shifted(sin0, cos0, 0.8 * h, p)
    rhs(t + 0.8 * h, y_new, p, ug, vg, K[3])
    for i in range(n):
        y_new[i] = y[i] + h * (_A51 * K[0, i] + _A52 * K[1, i] + _A53 * K[2, i]
                               + _A54 * K[3, i])
    ug, vg = ground_shifted(sin0, cos0, (8.0 / 9.0) * h, p)
    rhs(t + (8.0 / 9.0) * h, y_new, p, ug, vg, K[4])
    for i in range(n):
        y_new[i] = y[i] + h * (_A61 * K[0, i] + _A62 * K[1, i] + _A63 * K[2, i]
                               + _A64 * K[3, i] + _A65 * K[4, i])
    rhs(t + h, y_new, p, ug_end, vg_end, K[5])
    for i in range(n):
        y_new[i] = y[i] + h * (_B1 * K[0, i] + _B3 * K[2, i] + _B4 * K[3, i]
                               + _B5 * K[4, i] + _B6 * K[5, i])
    rhs(t + h, y_new, p, ug_end, vg_end, f_new)
    total = 0.0
    for i in range(n):
        K[6, i] = f_new[i]
        err = h * (_E1 * K[0, i] + _E3 * K[2, i] + _E4 * K[3, i] + _E5 * K[4, i]
                   + _E6 * K[5, i] + _E7 * f_new[i])
        scale = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        total += (err / scale) ** 2
    return math.sqrt(total / n), sin1, cos1


@kernel
def solve_arg(rhs, y, p, t_end, rtol, atol, h, work, stats):
    n = y.shape[0]
    K = work[0:7]
    f0 = work[7]
    y_new = work[8]
    f_new = work[9]
    t = 0.0
    sin0, cos0 = ground_phase(t, p)
    ug, vg = ground_at_phase(sin0, cos0, p)
    rhs(t, y, p, ug, vg, f0)
    err_prev = ERR_FLOOR
    accepted = 0
    rejected = 0
    while t < t_end:
        if t + h > t_end:
            h = t_end - t
        err, sin1, cos1 = dp5_step_arg(rhs, t, h, y, f0, p, rtol, atol, K, y_new, f_new,
                                       sin0, cos0)
        factor = step_factor(err, err_prev)
        if err <= 1.0:
            t += h
            for i in range(n):
                y[i] = y_new[i]
                f0[i] = f_new[i]
            sin0 = sin1
            cos0 = cos1
            err_prev = max(err, ERR_FLOOR)
            accepted += 1
        else:
            rejected += 1
        h *= factor
        if h < 1e-14:
            break
    stats[0] = accepted
    stats[1] = rejected
    stats[2] = t


# ----------------------------------------- (b): a plain dispatcher as argument
@kernel
def solve_dispatcher(rhs, y, p, t_end, rtol, atol, h, work, stats):
    solve_arg(rhs, y, p, t_end, rtol, atol, h, work, stats)


# ----------------------------------------- (c): a declared first-class function type
SOLVE_SIG = types.void(RHS_TYPE, VEC, VEC, types.float64, types.float64, types.float64,
                       types.float64, types.float64[:, ::1], VEC)


def _solve_ftype(rhs, y, p, t_end, rtol, atol, h, work, stats):
    solve_arg(rhs, y, p, t_end, rtol, atol, h, work, stats)


_TYPED = {}


def typed_engine():
    """(c)'s dispatchers, compiled (or loaded) on first use with their declared
    signatures: the right-hand side and the engine taking it as FunctionType."""
    if not _TYPED:
        opts = dict(cache=True, _nrt=False, error_model="numpy")
        _TYPED["rhs"] = njit(RHS_SIG, **opts)(towers_rhs.py_func)
        _TYPED["solve"] = njit(SOLVE_SIG, **opts)(_solve_ftype)
    return _TYPED["rhs"], _TYPED["solve"]


# ----------------------------------------- (e): a closure per right-hand side
def make_engine(rhs_fn):
    @kernel
    def solve_closure(y, p, t_end, rtol, atol, h, work, stats):
        solve_arg(rhs_fn, y, p, t_end, rtol, atol, h, work, stats)

    return solve_closure


# ----------------------------------------- (d): a generated module per composition
ENGINE_FUNCTIONS = (dp5_step, solve_direct)  #: the engine text, in callee-first order


def engine_source() -> str:
    return "\n\n".join(inspect.getsource(f.py_func) for f in ENGINE_FUNCTIONS)


def _file_digest(path: str) -> str:
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def compose(cache_root: str | Path, rhs_fn=towers_rhs):
    """Import (writing it first if absent) the engine module specialised to ``rhs_fn``.

    The module name is a hash of: the engine text, numba's version, and for the
    composed function its module, qualified name and the sha256 of its source
    file (so an edit anywhere in that file gives a new module; numba's own
    index only tracks the file of the function it compiles).
    """
    text = engine_source()
    fn_module = sys.modules[rhs_fn.py_func.__module__]
    parts = [text, numba.__version__, rhs_fn.py_func.__module__, rhs_fn.py_func.__qualname__,
             _file_digest(fn_module.__file__)]
    key = hashlib.sha256("\0".join(parts).encode()).hexdigest()[:20]
    name = f"engine_{key}"
    folder = Path(cache_root) / "composed"
    path = folder / f"{name}.py"
    if not path.exists():
        folder.mkdir(parents=True, exist_ok=True)
        names = {"kernel"}  # the decorator
        for f in ENGINE_FUNCTIONS:
            names.update(f.py_func.__code__.co_names)
        this = sys.modules[__name__]
        helpers = sorted(n for n in names if n != "rhs" and hasattr(this, n)
                         and not inspect.ismodule(getattr(this, n)))
        header = (
            f'"""Generated engine: rhs = {rhs_fn.py_func.__module__}.'
            f'{rhs_fn.py_func.__qualname__}; key {key}."""\n'
            "import math\n\n"
            f"from {__name__} import {', '.join(helpers)}\n"
            f"from {rhs_fn.py_func.__module__} import {rhs_fn.py_func.__name__} as rhs\n\n\n"
        )
        tmp = folder / f".{name}.{os.getpid()}.tmp"
        tmp.write_text(header + text + "\n")
        os.replace(tmp, path)  # atomic: concurrent processes write the same text
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
    return importlib.import_module(name)


# ================================================================ the runs
VARIANTS = ("a_direct", "b_dispatcher", "c_ftype", "d_generated", "e_closure")


def build_solver(variant: str, cache_root: str | Path):
    """A callable ``solve(y, p, t_end, rtol, atol, h, work, stats)`` and its dispatcher."""
    if variant == "a_direct":
        return solve_direct, solve_direct
    if variant == "b_dispatcher":
        return (lambda *a: solve_dispatcher(towers_rhs, *a)), solve_dispatcher
    if variant == "c_ftype":
        rhs_typed, solve_ftype = typed_engine()
        return (lambda *a: solve_ftype(rhs_typed, *a)), solve_ftype
    if variant == "d_generated":
        mod = compose(cache_root)
        return mod.solve_direct, mod.solve_direct
    if variant == "e_closure":
        engine = make_engine(towers_rhs)
        return engine, engine
    raise ValueError(variant)


def fig3a_problem(cycles: float, rtol: float):
    """Packed fig3a parameters, rest state, span, tolerances (atol = 1e-3 rtol)."""
    from chaospound.scene import load_preset

    scene = load_preset("fig3a")
    p = np.ascontiguousarray(scene.pack(), dtype=np.float64)
    return dict(p=[float(v) for v in p], y0=[0.0] * 12, t_end=cycles * float(p[P_PERIOD]),
                rtol=rtol, atol=1e-3 * rtol, h0=1e-3)


def run_once(solve, prob):
    y = np.array(prob["y0"], dtype=np.float64)
    p = np.array(prob["p"], dtype=np.float64)
    work = np.zeros((10, y.shape[0]))
    stats = np.zeros(3)
    t0 = time.perf_counter()
    solve(y, p, prob["t_end"], prob["rtol"], prob["atol"], prob["h0"], work, stats)
    elapsed = time.perf_counter() - t0
    return elapsed, y, stats


def _hits(dispatcher):
    s = dispatcher.stats
    return int(sum(s.cache_hits.values())), int(sum(s.cache_misses.values()))


# ------------------------------------------------------------ children
def child_first_result(variant: str, prob_path: str, cache_root: str) -> dict:
    """In a fresh process: build the solver, first (short) result; times and cache stats."""
    t_start = time.perf_counter()
    prob = json.loads(Path(prob_path).read_text())
    short = dict(prob, t_end=float(prob["p"][P_PERIOD]))  # one excitation period
    t_build0 = time.perf_counter()
    solve, dispatcher = build_solver(variant, cache_root)
    t_build = time.perf_counter() - t_build0
    t_call0 = time.perf_counter()
    _, y, stats = run_once(solve, short)
    t_call = time.perf_counter() - t_call0
    hits, misses = _hits(dispatcher)
    return dict(build_s=t_build, first_call_s=t_call, in_process_s=time.perf_counter() - t_start,
                cache_hits=hits, cache_misses=misses, steps=int(stats[0] + stats[1]),
                y_hex=[float(v).hex() for v in y])


def child_callgrind(variant: str, prob_path: str, cache_root: str, lib: str) -> dict:
    """Run the solve with callgrind instrumentation switched on around it only."""
    import ctypes

    cg = ctypes.CDLL(lib)
    prob = json.loads(Path(prob_path).read_text())
    solve, _ = build_solver(variant, cache_root)
    run_once(solve, dict(prob, t_end=1.0))  # dispatch warm-up outside the region
    y = np.array(prob["y0"], dtype=np.float64)
    p = np.array(prob["p"], dtype=np.float64)
    work = np.zeros((10, y.shape[0]))
    stats = np.zeros(3)
    args = (y, p, prob["t_end"], prob["rtol"], prob["atol"], prob["h0"], work, stats)
    cg.cg_start()
    solve(*args)
    cg.cg_stop()
    return dict(steps=int(stats[0] + stats[1]))


def child_builtin() -> dict:
    """Today's first run: import chaospound, simulate(fig3a); every compile timed."""
    import numba.core.event as ev

    t_start = time.perf_counter()
    stack = []
    records = []

    class Recorder(ev.Listener):
        def on_start(self, event):
            stack.append([time.perf_counter(), 0.0])

        def on_end(self, event):
            start, children = stack.pop()
            inclusive = time.perf_counter() - start
            if stack:
                stack[-1][1] += inclusive
            d = event.data["dispatcher"]
            records.append(dict(name=f"{d.py_func.__module__}.{d.py_func.__qualname__}",
                                args=str(event.data["args"]), inclusive_s=inclusive,
                                exclusive_s=inclusive - children, top=not stack))

    with ev.install_listener("numba:compile", Recorder()):
        from numba.core.registry import CPUDispatcher

        import chaospound

        t_imported = time.perf_counter()
        chaospound.simulate(chaospound.load_preset("fig3a"))
        t_done = time.perf_counter()
    hits = misses = 0
    cache_paths = set()
    for name, mod in list(sys.modules.items()):
        if not name.startswith("chaospound"):
            continue
        for obj in vars(mod).values():
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == name:
                h, m = _hits(obj)
                hits += h
                misses += m
                if h or m:
                    cache_paths.add(obj.stats.cache_path)
    return dict(import_s=t_imported - t_start, simulate_s=t_done - t_imported,
                in_process_s=t_done - t_start, cache_hits=hits, cache_misses=misses,
                cache_paths=sorted(cache_paths), compiles=records)


# ------------------------------------------------------------ parent side
def _child(args: list[str], cache_dir: str, prefix: list[str] | None = None) -> tuple[dict, float]:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir, PYTHONHASHSEED="0")
    cmd = (prefix or []) + [sys.executable, str(HERE / "bench_composition.py"), "--child"] + args
    t0 = time.perf_counter()
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=str(ROOT))
    wall = time.perf_counter() - t0
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
    if done.returncode != 0:
        raise RuntimeError(f"child {args} failed:\n{done.stderr[-3000:]}")
    line = [s for s in done.stdout.splitlines() if s.startswith("RESULT ")][-1]
    res = json.loads(line[len("RESULT "):])
    res["process_cpu_s"] = cpu  # user + system time of the child (and of valgrind)
    return res, wall


def measure_processes(prob_path: str, variants, reference_hex) -> dict:
    """Per variant: a fresh process on a cold cache dir, then a second one on the same dir."""
    out = {}
    for v in variants:
        cache = tempfile.mkdtemp(prefix=f"bench_composition_{v}_")
        first, wall1 = _child(["first", v, prob_path, cache], cache)
        second, wall2 = _child(["first", v, prob_path, cache], cache)
        out[v] = dict(
            first_process_wall_s=wall1, first_process=first,
            second_process_wall_s=wall2, second_process=second,
            second_bitwise_equal_first=second["y_hex"] == first["y_hex"],
            short_run_bitwise_equal_a=first["y_hex"] == reference_hex,
            cache_files=sorted(str(p.relative_to(cache)) for p in Path(cache).rglob("*")
                               if p.is_file()),
        )
        for rec in (first, second):
            rec.pop("y_hex")
        shutil.rmtree(cache, ignore_errors=True)
        print(f"  {v:13s} first process {wall1:6.2f} s (hits {first['cache_hits']}, misses "
              f"{first['cache_misses']}), second {wall2:6.2f} s (hits {second['cache_hits']}, "
              f"misses {second['cache_misses']})", flush=True)
    return out


def measure_builtin() -> dict:
    out = {}
    cache = tempfile.mkdtemp(prefix="bench_composition_builtin_")
    for label in ("cold", "warm"):
        rec, wall = _child(["builtin"], cache)
        rec["process_wall_s"] = wall
        compiles = rec.pop("compiles")
        by_name = {}
        for c in compiles:
            e = by_name.setdefault(c["name"], dict(exclusive_s=0.0, signatures=0))
            e["exclusive_s"] += c["exclusive_s"]
            e["signatures"] += 1
        rec["compile_exclusive_total_s"] = sum(c["exclusive_s"] for c in compiles)
        rec["top_level_compiles"] = [dict(name=c["name"], inclusive_s=c["inclusive_s"])
                                     for c in compiles if c["top"]]
        rec["by_dispatcher"] = dict(sorted(by_name.items(),
                                           key=lambda kv: -kv[1]["exclusive_s"]))
        out[label] = rec
        print(f"  built-in {label}: process {wall:.1f} s, simulate {rec['simulate_s']:.1f} s, "
              f"hits {rec['cache_hits']}, misses {rec['cache_misses']}", flush=True)
    shutil.rmtree(cache, ignore_errors=True)
    return out


CG_SOURCE = r"""
#include <valgrind/callgrind.h>
void cg_start(void) { CALLGRIND_ZERO_STATS; CALLGRIND_START_INSTRUMENTATION; }
void cg_stop(void) { CALLGRIND_STOP_INSTRUMENTATION; CALLGRIND_DUMP_STATS_AT("solve"); }
"""


def measure_callgrind(prob_path: str, variants) -> dict:
    if shutil.which("valgrind") is None or shutil.which("gcc") is None:
        return dict(skipped="valgrind or gcc not found")
    work = Path(tempfile.mkdtemp(prefix="bench_composition_cg_"))
    src = work / "cg.c"
    src.write_text(CG_SOURCE)
    lib = work / "libcg.so"
    subprocess.run(["gcc", "-O1", "-shared", "-fPIC", "-o", str(lib), str(src)], check=True)
    out = {}
    for v in variants:
        cache = tempfile.mkdtemp(prefix=f"bench_composition_cgc_{v}_", dir=work)
        _child(["first", v, prob_path, cache], cache)  # compile (and cache) outside valgrind
        cg_file = work / f"callgrind.{v}.out"
        prefix = ["valgrind", "--tool=callgrind", "--instr-atstart=no",
                  f"--callgrind-out-file={cg_file}"]
        rec, wall = _child(["callgrind", v, prob_path, cache, str(lib)], cache, prefix)
        total = None
        for f in sorted(work.glob(f"callgrind.{v}.out*")):
            for line in f.read_text(errors="replace").splitlines():
                if line.startswith("totals:") or line.startswith("summary:"):
                    value = int(line.split()[1])
                    total = value if total is None else max(total, value)
        rec.update(instructions=total, instructions_per_step=total / rec["steps"],
                   valgrind_wall_s=wall)
        out[v] = rec
        print(f"  {v:13s} {rec['instructions_per_step']:9.1f} instructions per step "
              f"({rec['steps']} steps)", flush=True)
    shutil.rmtree(work, ignore_errors=True)
    return out


def check_faithful(prob) -> dict:
    """The reduced copy against chaospound's own kernels, bitwise."""
    from chaospound.kernels import models, params, rk

    rng = np.random.default_rng(20240514)
    p = np.array(prob["p"])
    work = np.zeros((10, 12))
    ours = np.zeros(12)
    theirs = np.zeros(12)
    rhs_equal = step_equal = 0
    n_cases = 200
    for k in range(n_cases):
        y = rng.normal(scale=[1.0, 1.0, 0.1, 0.1, 0.01, 0.01] * 2)
        if k % 2:  # push the towers into contact: partial and full
            y[0] += 1.0 + abs(rng.normal(scale=0.05))
        t = rng.uniform(0.0, 5.0)
        ug, vg = math.sin(t / p[0]), math.cos(t / p[0]) / p[0]
        towers_rhs(t, y, p, ug, vg, ours)
        models.rhs_grounded(params.TOWERS, t, y, p, ug, vg, theirs)
        rhs_equal += np.array_equal(ours.view(np.uint64), theirs.view(np.uint64))
        f0 = np.empty(12)
        towers_rhs(t, y, p, ug, vg, f0)
        s0, c0 = math.sin(t / p[0]), math.cos(t / p[0])
        h = 1e-3
        K1 = np.zeros((16, 12))
        yn1 = np.zeros(12)
        fn1 = np.zeros(12)
        e1 = rk.dopri5_step(params.TOWERS, t, h, y, f0, p, 1e-6, 1e-9, K1, yn1, fn1, s0, c0)
        K2 = work[0:7]
        yn2 = work[8]
        fn2 = work[9]
        e2 = dp5_step(t, h, y, f0, p, 1e-6, 1e-9, K2, yn2, fn2, s0, c0)
        step_equal += (e1 == e2 and np.array_equal(yn1.view(np.uint64), yn2.view(np.uint64))
                       and np.array_equal(fn1.view(np.uint64), fn2.view(np.uint64)))
    return dict(cases=n_cases, rhs_bitwise_equal=int(rhs_equal),
                dopri5_step_bitwise_equal=int(step_equal))


def measure_steps(prob, variants, rounds: int, repeats: int, cache_root: str) -> dict:
    """Interleaved rounds in this process; per-step time and its ratio to a_direct.

    In every round each variant runs ``repeats`` times back to back and keeps its
    fastest run (the machine is shared: the minimum filters preemption); the
    ratio of a round is taken between the variants' minima of that round.
    """
    solvers = {v: build_solver(v, cache_root)[0] for v in variants}
    finals = {}
    for v in variants:  # compile, and the bitwise comparison
        _, y, stats = run_once(solvers[v], prob)
        finals[v] = (y, stats)
    ref_y, ref_stats = finals["a_direct"]
    times = {v: [] for v in variants}
    order = list(variants)
    for _round in range(rounds):
        order = order[1:] + order[:1]  # rotate, so no variant always runs first
        for v in order:
            best = math.inf
            for _ in range(repeats):
                elapsed, _, stats = run_once(solvers[v], prob)
                best = min(best, elapsed / (stats[0] + stats[1]))
            times[v].append(best)
    out = {}
    for v in variants:
        ratios = [t / ta for t, ta in zip(times[v], times["a_direct"], strict=True)]
        y, stats = finals[v]
        q = statistics.quantiles(ratios, n=4)
        out[v] = dict(
            ns_per_step_median=1e9 * statistics.median(times[v]),
            ns_per_step_min=1e9 * min(times[v]), ns_per_step_max=1e9 * max(times[v]),
            ratio_to_a_median=statistics.median(ratios), ratio_to_a_min=min(ratios),
            ratio_to_a_max=max(ratios), ratio_to_a_quartiles=[q[0], q[2]],
            accepted=int(stats[0]), rejected=int(stats[1]),
            bitwise_equal_a=bool(np.array_equal(y.view(np.uint64), ref_y.view(np.uint64))
                                 and np.array_equal(stats, ref_stats)),
        )
        print(f"  {v:13s} {out[v]['ns_per_step_median']:7.1f} ns/step, ratio "
              f"{out[v]['ratio_to_a_median']:.3f} (quartiles {q[0]:.3f}-{q[2]:.3f}, range "
              f"{out[v]['ratio_to_a_min']:.3f}-{out[v]['ratio_to_a_max']:.3f}), "
              f"{int(stats[0])}+{int(stats[1])} steps, bitwise {out[v]['bitwise_equal_a']}",
              flush=True)
    return out


def inlining_report(cache_root: str) -> dict:
    """Calls in each compiled engine's optimised LLVM IR: direct calls to the
    right-hand side, and calls through a function pointer."""
    import re

    out = {}
    for v, disp in (("a_direct", solve_direct), ("d_generated", compose(cache_root).solve_direct),
                    ("c_ftype", typed_engine()[1]), ("b_dispatcher", solve_dispatcher)):
        ir = "\n".join(disp.inspect_llvm().values())
        calls = [line for line in ir.splitlines() if re.search(r"\bcall\b", line)]
        out[v] = dict(
            direct_calls_to_towers_rhs=sum("towers_rhs" in c.split("(")[0]
                                           and "@" in c.split("(")[0] for c in calls),
            calls_through_pointer=sum(bool(re.search(r"call [^@(]*%[.\w]+\(", c)) for c in calls),
            functions_defined=sum(line.startswith("define") for line in ir.splitlines()),
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    parser.add_argument("--rounds", type=int, default=31, help="interleaved timing rounds")
    parser.add_argument("--repeats", type=int, default=5,
                        help="runs per variant per round, the fastest kept")
    parser.add_argument("--cycles", type=float, default=48.0,
                        help="excitation periods integrated per timed run (fig3a: 40 + 8)")
    parser.add_argument("--rtol", type=float, default=1e-6, help="rtol (atol = 1e-3 rtol)")
    parser.add_argument("--cg-cycles", type=float, default=48.0,
                        help="periods integrated under callgrind")
    parser.add_argument("--no-callgrind", action="store_true")
    parser.add_argument("--no-builtin", action="store_true")
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    args = parser.parse_args()

    if args.child:
        kind, rest = args.child[0], args.child[1:]
        if kind == "first":
            res = child_first_result(*rest)
        elif kind == "callgrind":
            res = child_callgrind(*rest)
        elif kind == "builtin":
            res = child_builtin()
        else:
            raise SystemExit(f"unknown child {kind}")
        print("RESULT " + json.dumps(res))
        return

    t_all = time.perf_counter()
    prob = fig3a_problem(args.cycles, args.rtol)
    scratch = tempfile.mkdtemp(prefix="bench_composition_run_")
    prob_path = os.path.join(scratch, "problem.json")
    Path(prob_path).write_text(json.dumps(prob))
    result = dict(
        machine=dict(python=platform.python_version(), numba=numba.__version__,
                     numpy=np.__version__, cpu_count=os.cpu_count(),
                     processor=platform.processor() or platform.machine()),
        timing=dict(rounds=args.rounds, repeats=args.repeats),
        problem=dict(preset="fig3a", cycles=args.cycles, rtol=args.rtol, atol=prob["atol"],
                     t_end=prob["t_end"], state_dim=12),
        command="python benchmarks/bench_composition.py " + " ".join(sys.argv[1:]),
    )
    print("faithfulness of the reduced copy (bitwise against chaospound.kernels):", flush=True)
    result["faithful"] = check_faithful(prob)
    print(f"  {result['faithful']}", flush=True)

    print("per-step cost, interleaved rounds:", flush=True)
    result["steps"] = measure_steps(prob, VARIANTS, args.rounds, args.repeats, scratch)
    result["inlining"] = inlining_report(scratch)
    print(f"  calls in the compiled engines: {result['inlining']}", flush=True)

    short = dict(prob, t_end=prob["p"][P_PERIOD])
    _, y_short, _ = run_once(solve_direct, short)
    reference_hex = [float(v).hex() for v in y_short]
    print("fresh processes on a cold NUMBA_CACHE_DIR (compile), then a second (load):",
          flush=True)
    result["processes"] = measure_processes(prob_path, VARIANTS, reference_hex)

    if not args.no_callgrind:
        print("callgrind, instructions per step:", flush=True)
        cg_prob = dict(prob, t_end=args.cg_cycles * prob["p"][P_PERIOD])
        cg_path = os.path.join(scratch, "problem_cg.json")
        Path(cg_path).write_text(json.dumps(cg_prob))
        # b and e are not cached: they would compile under valgrind (minutes)
        result["callgrind"] = measure_callgrind(cg_path, ("a_direct", "c_ftype", "d_generated"))
        result["callgrind_cycles"] = args.cg_cycles
    if not args.no_builtin:
        print("today's built-in kernels, simulate(fig3a) in a fresh process:", flush=True)
        result["builtin"] = measure_builtin()
    shutil.rmtree(scratch, ignore_errors=True)
    result["wall_s"] = time.perf_counter() - t_all
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.output}")
