"""Evaluation of the dense output of a step (the nested form of Hairer's contd5/contd8).

With ``x = theta`` and coefficient rows ``F_0, F_1, ...`` of ``Q``::

    u(x) = y + x (F_0 + (1 - x) (F_1 + x (F_2 + (1 - x) (F_3 + ...))))

``F_0 = y_new - y``, ``F_1 = h f0 - F_0``, ``F_2 = 2 F_0 - h (f0 + f_new)`` (the
cubic Hermite interpolant); DOPRI5 adds one row, DOP853 four. Hence
``u(0) = y`` exactly and ``u(1) = y_new`` to rounding, with ``u'(0) = f0`` and
``u'(1) = f_new``. The rows are prepared by the method's template
(:mod:`.steppers`); ``rows`` is the method's ``dense_rows``.
"""

from chaospound.kernels.jit import kernel


@kernel
def dense_eval(rows, Q, y, h, theta, out):
    """Interpolated state at ``t + theta h`` (0 <= theta <= 1), into ``out``.

    ``y`` is the state at the start of the step; ``h`` is unused (kept for a
    signature common with :func:`dense_eval_derivative`).
    """
    one_minus = 1.0 - theta
    for i in range(y.shape[0]):
        value = 0.0
        for k in range(rows - 1, -1, -1):
            value += Q[k, i]
            if k % 2 == 0:
                value *= theta
            else:
                value *= one_minus
        out[i] = y[i] + value


@kernel
def dense_eval_derivative(rows, Q, y, h, theta, out):
    """Time derivative ``du/dt`` of the interpolant at ``t + theta h``, into ``out``."""
    one_minus = 1.0 - theta
    for i in range(y.shape[0]):
        value = 0.0
        slope = 0.0
        for k in range(rows - 1, -1, -1):
            value += Q[k, i]
            if k % 2 == 0:
                slope = value + theta * slope
                value *= theta
            else:
                slope = one_minus * slope - value
                value *= one_minus
        out[i] = slope / h
