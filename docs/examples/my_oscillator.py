"""The oscillator of docs/custom_systems.md, as a file the command line can load.

    chaospound classify docs/examples/my_oscillator.py:system
    chaospound sweep docs/examples/my_oscillator.py:system --param r=0.5:1.0#11 -o x.h5

A unit oscillator (damping c) against a stop at distance ``gap`` that moves with
the ground u_g = sin(t / r), Hertz contact of stiffness ``beta``: its three
functions are the right-hand side, the Jacobian and the gap (``g < 0``: contact).
"""

import math

from numba import njit

from chaospound import custom_system


@njit
def rhs(t, y, q, out):
    c, gap, beta, r = q[0], q[1], q[2], q[3]
    ug, vg = math.sin(t / r), math.cos(t / r) / r
    d = y[0] - ug - gap
    out[0] = y[1]
    out[1] = -c * (y[1] - vg) - (y[0] - ug) - (beta * d**1.5 if d > 0.0 else 0.0)


@njit
def jacobian(t, y, q, jac):
    d = y[0] - math.sin(t / q[3]) - q[1]
    jac[0, 0], jac[0, 1] = 0.0, 1.0
    jac[1, 0] = -1.0 - (1.5 * q[2] * math.sqrt(d) if d > 0.0 else 0.0)
    jac[1, 1] = -q[0]


@njit
def gap(t, y, q):
    r = q[3]
    return q[1] - (y[0] - math.sin(t / r)), -(y[1] - math.cos(t / r) / r)


system = custom_system(rhs, jacobian, gap,
                       params={"c": 0.06, "gap": 1.0, "beta": 1000.0, "r": 0.7},
                       period=lambda q: 2 * math.pi * q["r"], initial_state=(0.0, 0.0),
                       state_names=("x", "dx"), rtol=1e-9, atol=1e-11)
