"""Error measures of the generic tableau steps (``<= 1`` means accept).

Each has the signature ``(h, y, f0, y_new, K, rtol, atol)``; a method names
its own (:class:`.tableaux.Method`). DOPRI5's RMS norm is computed inside its
unrolled step (:func:`.steppers.dopri5_step`).
"""

import math

from chaospound.kernels.jit import kernel
from chaospound.solvers.tableaux import CASH_KARP_E, CASH_KARP_TINY, DOP853_E3, DOP853_E5


@kernel
def press_error(h, y, f0, K, e, rtol, atol):
    """Numerical Recipes' errmax: ``max_i |yerr_i| / (|y_i| + |h f0_i| + floor) / rtol``.

    Press et al. use a floor of 1e-30; here it is ``atol`` (1e-6 at the paper's
    0.1 %, negligible beside the state's components), so that a component that
    is exactly zero with a zero derivative (a tangent vector's share of the
    other tower before the first contact couples them) is held to ``rtol atol``
    instead of an impossible relative tolerance.
    """
    errmax = 0.0
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(e.shape[0]):
            if e[j] != 0.0:
                acc += e[j] * K[j, i]
        ratio = abs(h * acc) / (abs(y[i]) + abs(h * f0[i]) + atol + CASH_KARP_TINY)
        if ratio > errmax or math.isnan(ratio):
            errmax = ratio
    return errmax / rtol


@kernel
def cash_karp_error(h, y, f0, y_new, K, rtol, atol):
    """Cash-Karp's embedded error in Press's scale (:func:`press_error`)."""
    return press_error(h, y, f0, K, CASH_KARP_E, rtol, atol)


@kernel
def no_error(h, y, f0, y_new, K, rtol, atol):
    """A fixed-step method has no error estimate: 0."""
    return 0.0


@kernel
def dop853_error(h, y, f0, y_new, K, rtol, atol):
    """Hairer's dop853 error: ``|h| e5^2 / sqrt(n (e5^2 + 0.01 e3^2))`` (scaled RMS sums)."""
    n = y.shape[0]
    sum5 = 0.0
    sum3 = 0.0
    for i in range(n):
        acc5 = 0.0
        acc3 = 0.0
        for j in range(DOP853_E5.shape[0]):
            acc5 += DOP853_E5[j] * K[j, i]
            acc3 += DOP853_E3[j] * K[j, i]
        scale = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        sum5 += (acc5 / scale) ** 2
        sum3 += (acc3 / scale) ** 2
    if sum5 == 0.0 and sum3 == 0.0:
        return 0.0
    return abs(h) * sum5 / math.sqrt((sum5 + 0.01 * sum3) * n)
