"""Reference systems with published Lyapunov spectra, to validate the engine.

* Lorenz (1963): ``x' = s (y - x)``, ``y' = x (r - z) - y``, ``z' = x y - b z``;
  for s = 10, r = 28, b = 8/3 the spectrum is about (0.906, 0, -14.57).
* Forced Duffing: ``x'' + d x' + a x + b x^3 = g cos(w t)``.

They run through the same steppers, integrator and Lyapunov code as the
pounding models (the model templates :mod:`chaospound.physics.models.lorenz` and ``duffing``).
"""

import math

from chaospound.kernels.jit import kernel
from chaospound.kernels.params import REF_0, REF_1, REF_2, REF_3, REF_4


@kernel
def lorenz_rhs(t, y, p, out):
    out[0] = p[REF_0] * (y[1] - y[0])
    out[1] = y[0] * (p[REF_1] - y[2]) - y[1]
    out[2] = y[0] * y[1] - p[REF_2] * y[2]


@kernel
def duffing_rhs(t, y, p, out):
    x = y[0]
    out[0] = y[1]
    out[1] = (-p[REF_0] * y[1] - p[REF_1] * x - p[REF_2] * x * x * x
              + p[REF_3] * math.cos(p[REF_4] * t))
