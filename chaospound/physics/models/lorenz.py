"""Lorenz (1963), a validation case of the engine (no contact, no ground motion).

A template of the model interface (:mod:`chaospound.physics.models.towers`) with
``N_ENDS = 0``: the event machinery compiles away.
"""

import numpy as np

from chaospound.kernels.jit import inline, kernel
from chaospound.kernels.params import REF_0, REF_1, REF_2
from chaospound.kernels.reference import lorenz_rhs
from chaospound.physics.models.no_contact import (  # noqa: F401  (bound by the composition)
    model_contact_point,
    model_ends,
    model_force_rate,
    model_forces,
    model_potential,
    model_rate,
)

# ==== template ====
N_BASE = 3
N_ENDS = 0


@inline
def model_rhs(t, y, p, ug, vg, out):
    lorenz_rhs(t, y, p, out)


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


