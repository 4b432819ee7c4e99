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
