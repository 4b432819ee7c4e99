"""Fast real powers for the Hertz exponents and the ground motion.

``power(x, e)`` is ``x**e`` for ``x >= 0``; the exponents that the default Hertz
law needs (chi = 1.5 gives 0.5, 1.5, 2.5) and the integer ones go through
``sqrt`` and products (within 2 ulp of ``pow``, several times cheaper).
"""

import math

from .jit import inline
from .params import P_GROUND, P_PERIOD_RATIO


@inline
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


@inline
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

# Taylor coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!: the truncation
# error at |x| = SHIFT_MAX is below 1e-19, so sin x and cos x equal the
# library's to rounding. Products only: without fastmath a division by a
# constant stays a division, and the 13 divisions of a nested form would sit
# on the critical path of every Runge-Kutta stage.
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
    """``(sin, cos)`` of the ground's phase at ``t + shift`` from their values at t.

    Angle addition with ``x = shift / r``; for ``|x| <= SHIFT_MAX`` sin x and cos x
    are their Taylor polynomials to x^13 and x^14 in Horner form (truncation
    below 1e-19, so the result equals the direct evaluation to a few ulps),
    else the library's. ``(0, 1)`` without ground motion, as :func:`ground_phase`.
    """
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
    """Ground motion ``(u_g, u_g')`` at ``t + shift`` from ``sin(t/r)`` and ``cos(t/r)``.

    See :func:`phase_shifted`; ``(0, 0)`` without ground motion.
    """
    if p[P_GROUND] == 0.0:
        return 0.0, 0.0
    sin_t, cos_t = phase_shifted(sin0, cos0, shift, p)
    return sin_t, cos_t / p[P_PERIOD_RATIO]


@inline
def ground_phase(t, p):
    """``(sin(t/r), cos(t/r))``, the anchor of :func:`ground_shifted` (0, 1 without ground)."""
    if p[P_GROUND] == 0.0:
        return 0.0, 1.0
    arg = t / p[P_PERIOD_RATIO]
    return math.sin(arg), math.cos(arg)


@inline
def ground_at_phase(sin_x, cos_x, p):
    """``(u_g, u_g')`` from ``(sin(t/r), cos(t/r))`` of :func:`ground_phase`.

    Bitwise what :func:`ground` returns at the same t.
    """
    if p[P_GROUND] == 0.0:
        return 0.0, 0.0
    return sin_x, cos_x / p[P_PERIOD_RATIO]
