"""Contact events located on the dense output of a step (docs/model.md section 8).

A template (:mod:`.compose`). The event functions are the penetrations at the
two ends of the contact line, ``d_lo(t)`` and ``d_hi(t)``; their sign changes
are the force's kinks (contact onset and release of an end). Inside one step
the state is the step's interpolant ``y(t + theta h)``. A penetration's root
in theta is refined by Newton's method on the interpolant (its rate is the
derivative) to TIME_TOL in time; the other quantities (the rates, whose roots
are extrema, and the contact force's rate), and any Newton iterate that
leaves the bracket or fails to halve it, by the Illinois variant of regula
falsi safeguarded by bisection (:func:`locate_root`).

Grazes (an end that approaches, touches and leaves inside one step, with no
sign change at the step ends) are found from the rates: a rate that turns
towards zero inside the step marks an extremum, which is located as a root of
the rate, and the penetration there decides whether two crossings happened.

The event quantities are numbered (data, not kinds): 0, 1 the penetrations
d_lo, d_hi; 2, 3 their rates; 4 the rate of the resultant contact force; 5 a
point contact's switch function (Kelvin-Voigt's no-pull ``k d + c d'``,
Jankowski's rate ``d'``, whose zero a tangent run lands on: the Jacobian jumps
there).
"""

from chaospound.kernels.free import (
    DENSE_ROWS,
    LAW,
    N_BASE,
    POINT_SWITCH,
    law_point_switch,
    model_ends,
    model_force_rate,
)
from chaospound.kernels.jit import kernel
from chaospound.solvers.dense import dense_eval

TIME_TOL = 1e-13  #: absolute tolerance of located event times (normalised time)
#: tolerance in time of located extrema (roots of a rate, quantity >= 2): they give
#: peak values and graze decisions, which a time error delta changes by O(delta^2)
EXTREMUM_TOL = 1e-9
MAX_ITER = 200  #: iteration cap of the root finders (bisection halves 2^-200)
FORCE_RATE = 4  #: number of the contact force's rate among the event quantities
SWITCH = 5  #: number of a point contact's switch function (tangent runs, jumping or shifted laws)

# ==== template ====


@kernel
def end_value(q, y, t, h, theta, p, which, work, ends):
    """Event quantity ``which`` at t + theta h; the interpolated state is left in ``work``.

    Only the model's state (the first N_BASE components) is interpolated: the
    event quantities do not depend on the tangent vectors that follow it in a
    tangent run, whose part of ``work`` is left as it was.
    """
    dense_eval(DENSE_ROWS, q, y[:N_BASE], h, theta, work)
    model_ends(t + theta * h, work, p, ends)
    if which == FORCE_RATE:
        return model_force_rate(t + theta * h, work, p, ends)
    if POINT_SWITCH and which == SWITCH:
        return law_point_switch(p, LAW, ends[0], ends[2])
    return ends[which]


@kernel
def locate_root(q, y, t, h, p, which, lo, f_lo, hi, f_hi, slope_hi, work, ends):
    """Root in theta of event quantity ``which`` on [lo, hi] where the signs differ.

    ``f_lo`` and ``f_hi`` are the (possibly conventional) values at the bracket
    ends; they must have opposite signs. ``slope_hi`` is ``df/dtheta`` at ``hi``
    when known (0: unknown). Returns theta of the root, refined until the
    bracket is shorter than TIME_TOL in time (EXTREMUM_TOL for the rates).

    The penetrations (``which`` 0, 1) carry their rates, so their roots are
    refined by Newton's method on the interpolant, each iterate pushed half a
    tolerance past the estimated root so that, once converged, the next
    evaluation lands on the far side and closes the bracket (about 5
    evaluations instead of the ~20 of regula falsi started from a conventional
    end value). Other quantities, and any Newton iterate that leaves the
    bracket or fails to halve it, fall back to the Illinois variant of regula
    falsi, safeguarded by bisection; a switch function (``SWITCH``) to TIME_TOL
    too, without Newton (its rate needs the accelerations).
    """
    newton = which < 2  # penetrations: their rates are the derivatives
    tol = TIME_TOL if newton else EXTREMUM_TOL
    if POINT_SWITCH and which == SWITCH:
        tol = TIME_TOL  # where the Jacobian jumps: as sharp as a crossing
    theta_tol = tol / h if h > 0.0 else 1e-15
    side = 0
    x = hi  # last evaluated point, its value and slope (df/dtheta)
    f_x = f_hi
    g_x = slope_hi
    x_is_lo = False
    last_move = 2.0 * (hi - lo)  # length of the previous move of x
    for _ in range(MAX_ITER):
        if hi - lo <= theta_tol:
            break
        mid = -1.0
        if g_x != 0.0:
            push = 0.5 * theta_tol if x_is_lo else -0.5 * theta_tol
            mid = x - f_x / g_x + push
            if not (lo < mid < hi) or abs(mid - x) > 0.5 * last_move:
                mid = -1.0  # outside the bracket, or not converging: no Newton step
        if mid < 0.0:
            # Illinois step, falling back to bisection when it stalls at an end
            mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            if (not (lo < mid < hi) or (mid - lo) < 0.25 * theta_tol
                    or (hi - mid) < 0.25 * theta_tol):
                mid = 0.5 * (lo + hi)
        last_move = abs(mid - x)
        f_mid = end_value(q, y, t, h, mid, p, which, work, ends)
        if f_mid == 0.0:
            return mid
        x = mid
        f_x = f_mid
        g_x = h * ends[which + 2] if newton else 0.0
        if (f_mid > 0.0) == (f_hi > 0.0):
            hi = mid
            f_hi = f_mid
            x_is_lo = False
            if side == 1:
                f_lo *= 0.5
            side = 1
        else:
            lo = mid
            f_lo = f_mid
            x_is_lo = True
            if side == -1:
                f_hi *= 0.5
            side = -1
    # the root lies in [lo, hi]; the upper end is on the far side of zero
    return hi


@kernel
def locate_extremum(q, y, t, h, p, end, rate_lo, rate_hi, work, ends):
    """theta where the rate of end ``end`` (0 or 1) vanishes inside the step."""
    return locate_root(q, y, t, h, p, end + 2, 0.0, rate_lo, 1.0, rate_hi, 0.0, work, ends)
