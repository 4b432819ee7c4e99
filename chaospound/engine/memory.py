"""Laws with memory or jumps in the tangent dynamics (docs/contact_laws.md section 7).

A template (:mod:`.compose`), used only by a composition whose law has memory
(``LAW_MEMORY``: hertzdamp, hunt-crossley) and carries tangent vectors. The
law's damping coefficient ``xi = zeta / v0`` is set at every onset from the
closing velocity ``v0 = V(t_e, x(t_e))`` at the end that touches first, and
stays constant through the episode. A perturbation ``dx`` of the state moves
the onset (the root of the end's penetration ``d(t, x) = 0``) by
``dt_e = -dd / V`` (``d' = V`` there), so

    dv0 = dV + (dV/dt) dt_e = dV - a dd / V,     dxi = (dxi/dv0) dv0

with ``dd`` and ``dV`` the variations of the penetration and of the closing
velocity at the contact point along ``dx`` (at fixed t) and ``a = dV/dt`` the
closing acceleration along the flow. The vector field itself is continuous at
the onset (the force is 0 at d = 0), so the saltation matrix of the state is
the identity; what the onset adds is ``dxi``, one number per tangent vector
(the law's block holds it, ``p[LAW_DXI + i]``), which then drives the
variational equations through ``(df/dxi) dxi`` until the next onset
(:func:`chaospound.engine.glue.rhs_tangent`).
"""

from chaospound.kernels.free import (
    LAW,
    LAW_DXI,
    law_onset_sensitivity,
    model_onset_accel,
    model_onset_variation,
    rhs,
)
from chaospound.kernels.jit import kernel

# ==== template ====


@kernel
def onset_tangent(t, y, p, y_at, rate, n_base, n_vectors, f):
    """Write each tangent vector's memory sensitivity at an onset.

    ``y`` is the full state at the onset (state and tangent vectors), ``y_at``
    and ``rate`` the contact point and its closing velocity (the law's v0
    before the floor), ``f`` a workspace of y's size. Call it with the law's
    memory already written (the rhs at the onset does not depend on it: the
    force is 0 there).
    """
    s = law_onset_sensitivity(p, LAW, rate)
    if s == 0.0:  # below the floor: v0 is a constant
        for i in range(n_vectors):
            p[LAW_DXI + i] = 0.0
        return
    rhs(t, y, p, f)
    accel = model_onset_accel(t, y, p, f[:n_base], y_at)
    for i in range(n_vectors):
        a = n_base * (i + 1)
        dd, dv = model_onset_variation(t, y, p, y[a:a + n_base], y_at)
        p[LAW_DXI + i] = s * (dv - accel * dd / rate)


@kernel
def reset_tangent_memory(p, n_vectors):
    """Zero the memory sensitivities: a run starts at fixed memory (the packed one)."""
    for i in range(n_vectors):
        p[LAW_DXI + i] = 0.0

