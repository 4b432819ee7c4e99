"""No ground motion: ``u_g = 0`` (free vibration, energy tests).

The interface of :mod:`.sine` with zero motion; its carried state is the
constant ``(0, 1)``. No parameters.
"""

from chaospound.kernels.jit import inline

NAME = "none"
PARAMETERS = ()
PERIODIC = False  #: any section interval will do


@inline
def at(t, p, base):
    """``(u_g, u_g') = (0, 0)``."""
    return 0.0, 0.0


@inline
def anchor(t, p, base):
    return 0.0, 1.0


@inline
def shifted(c0, c1, shift, p, base):
    return 0.0, 1.0


@inline
def at_anchor(c0, c1, p, base):
    return 0.0, 0.0
