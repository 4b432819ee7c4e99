"""Lorenz (1963), a validation case of the engine (no contact, no ground motion).

A template of the model interface (:mod:`chaospound.physics.models.towers`) with
``N_ENDS = 0``: the event machinery compiles away.
"""

import numpy as np

from chaospound.kernels.jit import inline, kernel
from chaospound.kernels.params import REF_0, REF_1, REF_2
from chaospound.kernels.reference import lorenz_rhs
from chaospound.physics.corners import CORNER_FACE

# ==== template ====
N_BASE = 3
N_ENDS = 0


@inline
def model_rhs(t, y, p, ug, vg, out):
    lorenz_rhs(t, y, p, out)


@inline
def model_rate(t, y, p, y_at):
    return 0.0


@inline
def model_ends(t, y, p, out):
    """No contact: ``(-1, -1, 0, 0)``."""
    out[0] = -1.0
    out[1] = -1.0
    out[2] = 0.0
    out[3] = 0.0


@kernel
def model_forces(t, y, p, q_out):
    for i in range(6):
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
    """Not a mechanical system: NaN."""
    return np.nan


@kernel
def model_trace(p):
    """``-sigma - 1 - b``, the constant sum of the exponents."""
    return -p[REF_0] - 1.0 - p[REF_2]


@kernel
def model_linearize(t, y, p):
    return y[0], y[1], y[2], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@kernel
def model_jvp(p, lin, v, out):
    x, yy, z = lin[0], lin[1], lin[2]
    out[0] = p[REF_0] * (v[1] - v[0])
    out[1] = (p[REF_1] - z) * v[0] - v[1] - x * v[2]
    out[2] = yy * v[0] + x * v[1] - p[REF_2] * v[2]


@kernel
def model_contact_point(t, state, p, ends):
    return CORNER_FACE, 0.0, ends[2]
