"""The forced Duffing oscillator ``x'' + d x' + a x + b x^3 = g cos(w t)``, a validation case.

A template of the model interface (:mod:`chaospound.physics.models.towers`) with
``N_ENDS = 0``; the forcing is the oscillator's own (its ground motion is "none").
"""

import numpy as np

from chaospound.kernels.jit import inline, kernel
from chaospound.kernels.params import REF_0, REF_1, REF_2
from chaospound.kernels.reference import duffing_rhs
from chaospound.physics.models.no_contact import (  # noqa: F401  (bound by the composition)
    model_contact_point,
    model_ends,
    model_force_rate,
    model_forces,
    model_potential,
    model_rate,
)

# ==== template ====
N_BASE = 2
N_ENDS = 0


@inline
def model_rhs(t, y, p, ug, vg, out):
    duffing_rhs(t, y, p, out)


@kernel
def model_energy(y, p):
    """Not a conservative system: NaN."""
    return np.nan


@kernel
def model_trace(p):
    """``-d``, the constant sum of the exponents."""
    return -p[REF_0]


@kernel
def model_linearize(t, y, p):
    return y[0], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@kernel
def model_jvp(p, lin, v, out):
    x = lin[0]
    out[0] = v[1]
    out[1] = -(p[REF_1] + 3.0 * p[REF_2] * x * x) * v[0] - p[REF_0] * v[1]


