"""Fast real powers for the Hertz exponents and the ground motion.

``power(x, e)`` is ``x**e`` for ``x >= 0``; the exponents that the default Hertz
law needs (chi = 1.5 gives 0.5, 1.5, 2.5) and the integer ones go through
``sqrt`` and products (within 2 ulp of ``pow``, several times cheaper).
"""

import math

from numba import njit

from .params import P_GROUND, P_PERIOD_RATIO


@njit(cache=True)
def power(x, e):
    """``x**e`` for x >= 0, with fast paths for half-integer and small integer e."""
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


@njit(cache=True)
def ground(t, p):
    """Ground displacement and velocity ``(u_g, u_g')`` at forcing time t.

    ``u_g = sin(t / r)`` (units of A_g), or 0 for ground motion "none".
    """
    if p[P_GROUND] == 0.0:
        return 0.0, 0.0
    r = p[P_PERIOD_RATIO]
    arg = t / r
    return math.sin(arg), math.cos(arg) / r


SHIFT_MAX = 0.3  #: |x| up to which sin/cos(x) come from the Taylor series below


@njit(cache=True)
def ground_shifted(sin0, cos0, shift, p):
    """Ground motion at ``t + shift`` from ``sin(t/r)`` and ``cos(t/r)``.

    Angle addition with ``x = shift / r``; for ``|x| <= SHIFT_MAX`` sin x and cos x
    are their Taylor series to x^13 and x^14 (truncation below 1e-19, so the
    result equals the direct evaluation to rounding), else the library's.
    """
    if p[P_GROUND] == 0.0:
        return 0.0, 0.0
    r = p[P_PERIOD_RATIO]
    x = shift / r
    if abs(x) <= SHIFT_MAX:
        x2 = x * x
        sin_x = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (
            1.0 - x2 / 72.0 * (1.0 - x2 / 110.0 * (1.0 - x2 / 156.0))))))
        cos_x = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0 * (
            1.0 - x2 / 90.0 * (1.0 - x2 / 132.0 * (1.0 - x2 / 182.0))))))
    else:
        sin_x = math.sin(x)
        cos_x = math.cos(x)
    return sin0 * cos_x + cos0 * sin_x, (cos0 * cos_x - sin0 * sin_x) / r


@njit(cache=True)
def ground_phase(t, p):
    """``(sin(t/r), cos(t/r))``, the anchor of :func:`ground_shifted` (0, 1 without ground)."""
    if p[P_GROUND] == 0.0:
        return 0.0, 1.0
    arg = t / p[P_PERIOD_RATIO]
    return math.sin(arg), math.cos(arg)
