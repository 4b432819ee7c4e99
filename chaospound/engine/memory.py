"""Laws with memory or jumps in the tangent dynamics (docs/contact_laws.md section 7).

A template (:mod:`.compose`), used only by a composition that carries tangent
vectors and whose law has memory (``LAW_MEMORY``: hertzdamp, hunt-crossley,
:func:`onset_tangent`) or whose point force jumps (``LAW_JUMPS`` on a point
contact: kelvin-voigt, :func:`saltation_tangent`).

**Memory.** The law's damping coefficient ``xi = zeta / v0`` is set at every
onset from the closing velocity ``v0 = V(t_e, x(t_e))`` at the end that
touches first, and stays constant through the episode. A perturbation ``dx`` of the state moves
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

**Jumps.** Kelvin-Voigt's point force ``k d + c d'`` jumps by ``dF`` where d
crosses 0 (``c d'`` at an onset, ``-c d'`` at a plain release), and the vector
field by ``f+ - f- = dF e_F``, ``e_F`` the force's column of the model (the
contact's generalised force per unit force). A tangent vector ``v`` is mapped
by the saltation matrix

    v -> v + (f+ - f-) (grad(d) . v) / d' = v + e_F s (grad(d) . v),   s = dF / d'

(``d' = grad(d) . f- + dd/dt|explicit``: the closing rate, a moving wall
included). That is the contact part of the model's Jacobian-vector product
with a contact stiffness s and no damping, so the models need nothing new:
``model_jvp(p, (s, 0, ...), v) - model_jvp(p, (0, ...), v)``.
"""

from chaospound.kernels.free import (
    LAW,
    LAW_DXI,
    law_onset_sensitivity,
    law_point_jump,
    model_jvp,
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


@kernel
def saltation_tangent(p, rate, onset, y, n_base, n_vectors, w):
    """Map each tangent vector across a jump of a point contact's force.

    ``v += e_F s (grad(d) . v)`` with ``s = dF / d'`` from the law
    (``law_point_jump``), computed as the difference of two Jacobian-vector
    products of the model, with the contact linearisation ``(s, 0, ...)`` and
    with none (the point models' :func:`model_linearize` returns ``(dF/dd,
    dF/dd', 0, ...)``, nine values). Nothing changes where s = 0 (a continuous
    release of the no-pull law).

    Parameters
    ----------
    p : ndarray
        Packed parameters.
    rate : float
        Closing rate d' at the event (units of A_g omega_Ax).
    onset : bool
        True at an onset (d becomes positive), False at a release.
    y : ndarray
        State followed by ``n_vectors`` tangent vectors of ``n_base`` values;
        the vectors are changed in place.
    w : ndarray
        Workspace of at least ``2 n_base`` values.
    """
    s = law_point_jump(p, LAW, rate, onset)
    if s == 0.0:
        return
    jump = (s, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    none = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    with_jump = w[:n_base]
    without = w[n_base:2 * n_base]
    for i in range(n_vectors):
        a = n_base * (i + 1)
        model_jvp(p, jump, y[a:a + n_base], with_jump)
        model_jvp(p, none, y[a:a + n_base], without)
        for c in range(n_base):
            y[a + c] += with_jump[c] - without[c]
