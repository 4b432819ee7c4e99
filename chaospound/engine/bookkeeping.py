"""Small kernels of the integration loop that know neither the physics nor the method.

Event bookkeeping (graze pre-test, landing checks, sorting), QR of the tangent
vectors and trajectory samples (docs/model.md sections 8, 10, 12).
"""

import numpy as np

from chaospound.kernels.jit import kernel

GRAZE_MARGIN = 0.25  #: relative margin of the graze pre-test (see may_cross)
GRAZE_FLOOR = 1e-6  #: absolute margin of the graze pre-test (units of A_g)
LAND_SLACK = 1e-8  #: a landing may miss its crossing by this much time, no more
LAND_ERR = 4.0  #: ... or by this many units of atol + rtol max(1, |y|) (see landed_short)
LAND_SHIFT_MAX = 1e-3  #: largest move of a landed event onto its crossing, in steps


@kernel
def may_cross(d0, d1, slope0, slope1):
    """Whether an extremum of d inside a step can reach the other side of 0.

    ``slope0`` and ``slope1`` are ``h d'`` at the step ends. For a parabola the
    two end tangents meet exactly at the extremum's value; the departure of d
    from a parabola over one step is O(h^3) times its third derivative and is
    covered by a margin of GRAZE_MARGIN times the spread of the slopes (plus a
    floor), so only an
    excursion that stays clearly on one side of 0 skips the dense-output search.
    """
    spread = abs(slope0) + abs(slope1)
    if spread == 0.0:
        return False
    theta = (d1 - slope1 - d0) / (slope0 - slope1)
    extreme = d0 + slope0 * theta
    margin = GRAZE_MARGIN * spread + GRAZE_FLOOR
    if d0 < 0.0:  # outside: a maximum, can it reach d > 0?
        return extreme > -margin
    return extreme < margin  # inside: a minimum, can it reach d < 0?


@kernel
def orthonormalize(y, n_base, n_vectors, log_out, row):
    """Modified Gram-Schmidt on the tangent vectors stored after the state.

    Stores ``log R_ii`` (the log of each vector's norm after removing its
    projections on the previous ones) in ``log_out[row]`` when ``row`` is a
    valid row, and replaces the vectors by the orthonormal basis.
    """
    store = 0 <= row < log_out.shape[0]
    for i in range(n_vectors):
        a = n_base * (i + 1)
        for j in range(i):
            b = n_base * (j + 1)
            dot = 0.0
            for c in range(n_base):
                dot += y[a + c] * y[b + c]
            for c in range(n_base):
                y[a + c] -= dot * y[b + c]
        norm = 0.0
        for c in range(n_base):
            norm += y[a + c] * y[a + c]
        norm = np.sqrt(norm)
        if store:
            log_out[row, i] = np.log(norm)
        for c in range(n_base):
            y[a + c] /= norm


@kernel
def landed_short(ends, end, inside, y, n_base, rtol, atol):
    """Whether a step landed on a located crossing actually stopped before it.

    The root was located on the long step's interpolant and the step redone to
    end there, so the landed state misses the surface by about the local
    error (up to ~2.4 units of ``atol + rtol S``, ``S = max(1, |y|)``, measured
    at rtol 1e-6). Within LAND_ERR such units, or LAND_SLACK in time, of the
    surface, and moving towards it, the crossing counts: the force is
    ``max(d, 0)^chi`` whatever the flag says, so only the bookkeeping changes.
    Further away, or moving away from 0, it has not happened yet and the next
    step will find it (a re-detection costs a root search and a tiny step).
    """
    d = ends[end]
    rate = ends[end + 2]
    if d == 0.0 or (d > 0.0) != inside:
        return False
    towards = rate < 0.0 if inside else rate > 0.0
    size = 1.0
    for i in range(n_base):
        size = max(size, abs(y[i]))
    slack = max(abs(rate) * LAND_SLACK, LAND_ERR * (atol + rtol * size))
    return not towards or abs(d) > slack


@kernel
def crossing_shift(d, rate, h):
    """Time from a landed state to its end's crossing, ``-d / d'`` (first order).

    A landing ends on the root of the long step's interpolant, which misses the
    true crossing by about the local error (a few ``atol + rtol |y|`` in d); the
    event is recorded at ``t + shift`` with the state ``y + shift y'``, which
    leaves an O(shift^2) error. 0 when the shift would not be small against the
    step (a rate near 0: a graze, whose root the linearisation cannot find).
    """
    if d == 0.0 or rate == 0.0:
        return 0.0
    shift = -d / rate
    if abs(shift) > LAND_SHIFT_MAX * h:
        return 0.0
    return shift


@kernel
def all_finite(v, n):
    for i in range(n):
        if not np.isfinite(v[i]):
            return False
    return True


@kernel
def sort_events(theta, end, n_ev):
    """Insertion sort of the (few) events of a step by theta."""
    for i in range(1, n_ev):
        th = theta[i]
        en = end[i]
        j = i - 1
        while j >= 0 and theta[j] > th:
            theta[j + 1] = theta[j]
            end[j + 1] = end[j]
            j -= 1
        theta[j + 1] = th
        end[j + 1] = en


@kernel
def store_sample(traj, row, t, state, n):
    traj[row, 0] = t
    for i in range(n):
        traj[row, i + 1] = state[i]


@kernel
def store_propagator(y, n_base, n_vectors, out, row):
    """Store the tangent vectors after the state in ``out[row]`` and reset them to e_i.

    Started from the unit vectors at the previous section, vector i is then
    column i of the propagator of the last section interval (``out[row]``
    reshaped to (n_vectors, n_base) is its transpose). Nothing is stored when
    ``row`` is not a valid row (the tangent transient).
    """
    store = 0 <= row < out.shape[0]
    for i in range(n_vectors):
        a = n_base * (i + 1)
        for c in range(n_base):
            if store:
                out[row, i * n_base + c] = y[a + c]
            y[a + c] = 1.0 if c == i else 0.0


@kernel
def orthonormalize_memory(y, p, slot, n_base, n_vectors, log_out, row):
    """:func:`orthonormalize`, carrying each vector's memory sensitivity along.

    A law with per-episode memory keeps, in ``p[slot + i]``, the sensitivity of
    its memory (d xi) to tangent vector i (docs/contact_laws.md section 7): a
    hidden component of the vector, which Gram-Schmidt must combine exactly as
    the vector's state components (``V_new = V R^-1``), but which takes no part
    in the norms and projections (the exponents measure the state's growth).
    """
    store = 0 <= row < log_out.shape[0]
    for i in range(n_vectors):
        a = n_base * (i + 1)
        for j in range(i):
            b = n_base * (j + 1)
            dot = 0.0
            for c in range(n_base):
                dot += y[a + c] * y[b + c]
            for c in range(n_base):
                y[a + c] -= dot * y[b + c]
            p[slot + i] -= dot * p[slot + j]
        norm = 0.0
        for c in range(n_base):
            norm += y[a + c] * y[a + c]
        norm = np.sqrt(norm)
        if store:
            log_out[row, i] = np.log(norm)
        for c in range(n_base):
            y[a + c] /= norm
        p[slot + i] /= norm


@kernel
def store_propagator_memory(y, p, slot, n_base, n_vectors, out, row):
    """:func:`store_propagator`, resetting each vector's memory sensitivity to 0.

    The propagator of one section interval is the derivative of the
    stroboscopic map at fixed memory (the packed vector's, as a run started at
    the section uses it): unit vectors with no memory sensitivity.
    """
    store_propagator(y, n_base, n_vectors, out, row)
    for i in range(n_vectors):
        p[slot + i] = 0.0
