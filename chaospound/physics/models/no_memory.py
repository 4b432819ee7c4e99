"""The memory kernels of a model that does not carry a law's memory in its tangent.

Bound by :mod:`chaospound.engine.compose` into every composition whose model
template does not define them, so that all engines resolve the same names;
:func:`chaospound.engine.compose.check_tangent` refuses tangent dynamics with a
law that has memory on such a model, so these are never reached with one.
"""

from chaospound.kernels.jit import kernel


@kernel
def model_memory_linearize(t, y, p):
    """No memory term."""
    return (0.0,)


@kernel
def model_memory_jvp(p, mem, dxi, out):
    """Adds nothing."""
    return


@kernel
def model_onset_variation(t, y, p, v, y_at):
    """``(0, 0)``."""
    return 0.0, 0.0


@kernel
def model_onset_accel(t, y, p, f, y_at):
    """0."""
    return 0.0
