"""Stand-ins for the optional functions of a user system."""

from chaospound.kernels.jit import kernel


@kernel
def no_gap(t, y, q):
    """A system without contact: always apart (``g = 1``, ``dg/dt = 0``)."""
    return 1.0, 0.0
