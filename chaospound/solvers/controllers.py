"""Step-size controllers: the factor on h for the next attempt, from this attempt's error.

``err_prev`` is the error of the previous accepted step (the caller keeps
``max(err, 1e-4)``; only the PI controller uses it). A NaN error gives the
smallest factor. A method names its controller (:class:`.tableaux.Method`).
"""

import math

from chaospound.kernels.jit import kernel
from chaospound.solvers.tableaux import (
    CASH_KARP_ERRCON,
    CASH_KARP_MAX_FACTOR,
    CASH_KARP_MIN_FACTOR,
    CASH_KARP_PGROW,
    CASH_KARP_PSHRNK,
    DOP853_EXPONENT,
    DOP853_MAX_FACTOR,
    DOP853_MIN_FACTOR,
    DOPRI5_BETA,
    DOPRI5_EXPONENT,
    DOPRI5_MAX_FACTOR,
    DOPRI5_MIN_FACTOR,
    ERR_FLOOR,
    SAFETY,
)


@kernel
def pi_factor(err, err_prev):
    """Hairer's PI controller (dopri5): ``0.9 err^-(0.2 - 0.75 beta) err_prev^beta``.

    beta = 0.04, in [0.2, 10]; on rejection ``min(1, max(0.2, 0.9 err^-(0.2 - 0.75 beta)))``.
    """
    rejected = not (err <= 1.0)
    # powers as exp(log): a third cheaper than pow here, and the step
    # controller needs no last-ulp accuracy (every accepted step runs this)
    if rejected:
        if math.isnan(err):
            return DOPRI5_MIN_FACTOR
        factor = SAFETY * math.exp(-DOPRI5_EXPONENT * math.log(err))
        return min(1.0, max(DOPRI5_MIN_FACTOR, factor))
    if err == 0.0:
        return DOPRI5_MAX_FACTOR
    prev = max(err_prev, ERR_FLOOR)
    factor = SAFETY * math.exp(DOPRI5_BETA * math.log(prev) - DOPRI5_EXPONENT * math.log(err))
    return min(DOPRI5_MAX_FACTOR, max(DOPRI5_MIN_FACTOR, factor))


@kernel
def dop853_factor(err, err_prev):
    """dop853: ``0.9 err^(-1/8)`` in [1/3, 6] (no PI), ``<= 1`` on rejection."""
    rejected = not (err <= 1.0)
    if rejected:
        if math.isnan(err):
            return DOP853_MIN_FACTOR
        return min(1.0, max(DOP853_MIN_FACTOR, SAFETY * err ** -DOP853_EXPONENT))
    if err == 0.0:
        return DOP853_MAX_FACTOR
    return min(DOP853_MAX_FACTOR, max(DOP853_MIN_FACTOR, SAFETY * err ** -DOP853_EXPONENT))


@kernel
def rkqs_factor(err, err_prev):
    """Numerical Recipes' rkqs: rejection ``max(0.1, 0.9 err^-0.25)``; acceptance
    ``0.9 err^-0.2``, or 5 when ``err < 1.89e-4``."""
    rejected = not (err <= 1.0)
    if rejected:
        if math.isnan(err):
            return CASH_KARP_MIN_FACTOR
        return max(CASH_KARP_MIN_FACTOR, SAFETY * err ** CASH_KARP_PSHRNK)
    if err > CASH_KARP_ERRCON:
        return SAFETY * err ** CASH_KARP_PGROW
    return CASH_KARP_MAX_FACTOR


@kernel
def fixed_factor(err, err_prev):
    """A fixed-step method: 1."""
    return 1.0
