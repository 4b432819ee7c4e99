"""The contact half of the model interface for systems without contact (Lorenz, Duffing).

Plain kernels (no free names): the reference models import them into their
templates, so each composition binds them by name and they compile once.
Their ends are ``(-1, -1, 0, 0)``, so the event machinery never fires.
"""

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.corners import CORNER_FACE


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
def model_contact_point(t, state, p, ends):
    return CORNER_FACE, 0.0, ends[2]
