"""A user's own system, ``rhs``, ``jacobian`` and optionally ``gap``, as a model.

docs/extending.md. The user's numba functions are bound into the composition
by name (``user_rhs``, ``user_jacobian``, ``user_gap``) together with the
constants ``N_BASE`` (the dimension), ``USER_HAS_GAP`` and ``USER_BASE``, where
the user's parameters ``q`` start in the packed vector. An ``n x n`` scratch
block that receives the Jacobian during a tangent run closes the vector (the
kernels allocate nothing), so ``q`` ends where that block begins: read from the
vector's length at run time, so that one engine serves a system whatever the
number of its parameters.

Impacts of a user system: onsets of ``g < 0`` with the velocity ``-dg/dt``
(the closing speed) and the corner label "face"; peaks of the contact force
are not known (0).
"""

import numpy as np

from chaospound.kernels.free import (
    N_BASE,
    USER_BASE,
    user_gap,
    user_jacobian,
    user_rhs,
)
from chaospound.kernels.jit import inline, kernel
from chaospound.physics.corners import CORNER_FACE

USER_HAS_GAP = False  #: bound by the composition

# ==== template ====


@inline
def _user_end(p):
    """Where the user's parameters ``q = p[USER_BASE:end]`` end: at the ``n x n``
    Jacobian scratch block that closes ``p``."""
    return p.shape[0] - N_BASE * N_BASE


@inline
def model_rhs(t, y, p, ug, vg, out):
    user_rhs(t, y[:N_BASE], p[USER_BASE:_user_end(p)], out[:N_BASE])


@inline
def model_rate(t, y, p, y_at):
    if USER_HAS_GAP:
        _, rate = user_gap(t, y[:N_BASE], p[USER_BASE:_user_end(p)])
        return -rate
    return 0.0


@inline
def model_ends(t, y, p, out):
    """``(-g, -g, -dg/dt, -dg/dt)``, or ``(-1, -1, 0, 0)`` without a gap function."""
    if USER_HAS_GAP:
        g, rate = user_gap(t, y[:N_BASE], p[USER_BASE:_user_end(p)])
        out[0] = -g
        out[1] = -g
        out[2] = -rate
        out[3] = -rate
    else:
        out[0] = -1.0
        out[1] = -1.0
        out[2] = 0.0
        out[3] = 0.0


@kernel
def model_forces(t, y, p, q_out):
    for i in range(q_out.shape[0]):
        q_out[i] = 0.0
    return 0.0


@kernel
def model_force_rate(t, y, p, ends):
    return 0.0


@kernel
def model_potential(t, y, p):
    return 0.0


@kernel
def model_energy(y, p):
    return np.nan


@kernel
def model_trace(p):
    return np.nan


@kernel
def model_linearize(t, y, p):
    """The user's Jacobian into the scratch block of ``p``; no coefficients."""
    end = _user_end(p)
    jac = p[end:end + N_BASE * N_BASE].reshape((N_BASE, N_BASE))
    user_jacobian(t, y[:N_BASE], p[USER_BASE:end], jac)
    return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@kernel
def model_jvp(p, lin, v, out):
    """``out = J v`` from the Jacobian :func:`model_linearize` left in ``p``."""
    end = _user_end(p)
    jac = p[end:end + N_BASE * N_BASE].reshape((N_BASE, N_BASE))
    for i in range(N_BASE):
        acc = 0.0
        for j in range(N_BASE):
            acc += jac[i, j] * v[j]
        out[i] = acc


@kernel
def model_contact_point(t, state, p, ends):
    return CORNER_FACE, 0.0, ends[2]
