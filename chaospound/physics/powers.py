"""Fast real powers for the contact laws' exponents.

``power(x, e)`` is ``x**e`` for ``x >= 0``; the exponents that the default Hertz
law needs (chi = 1.5 gives 0.5, 1.5, 2.5) and the integer ones go through
``sqrt`` and products (within 2 ulp of ``pow``, several times cheaper).
"""

import math

from chaospound.kernels.jit import inline


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
