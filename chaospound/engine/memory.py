"""Laws with memory, jumps or a shift in the tangent dynamics (docs/contact_laws.md section 7).

A template (:mod:`.compose`), used only by a composition that carries tangent
vectors and whose law has memory (``LAW_MEMORY``: hertzdamp, hunt-crossley,
:func:`onset_tangent`), whose point force jumps (``LAW_JUMPS`` on a point
contact: kelvin-voigt, :func:`saltation_tangent`) or whose point Jacobian is
singular after an onset (``LAW_SHIFTED``: jankowski, :func:`shift_tangent`).

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

**Shift.** Jankowski's point force ``beta d^chi + c(d) d'`` (approaching;
``c(d) = c_s d^(1/4)``) is continuous, but ``dF/dd`` has the term ``c'(d) d'
~ d^(-3/4)``. While approaching, the engine integrates ``w = P v``, ``P = I -
c(d) e_F grad(d)^T`` instead of the vectors v: ``grad(d) . e_F = 0`` and
``grad(d') = J_free^T grad(d)`` give ``P J + P' = J_el = J_free + k_e e_F
grad(d)^T`` (``k_e = chi beta d^(chi - 1)``: ``P'`` cancels the singular
term), so ``w' = J_el P^-1 w``, bounded, with ``P^-1 = I + c(d) e_F
grad(d)^T`` (the point models' :func:`model_jvp` with the shift ``lin[2] =
c(d)``). ``P = I`` at an onset (c(0) = 0); :func:`shift_tangent` converts
where the phase changes inside the contact (the switch d' = 0) and where the
vectors are read or reset (sections).
"""

from chaospound.kernels.free import (
    LAW,
    LAW_DXI,
    law_onset_sensitivity,
    law_point_jump,
    law_shift_scale,
    model_jvp,
    model_onset_accel,
    model_onset_variation,
    rhs,
)
from chaospound.kernels.jit import inline, kernel

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
    _add_force_column(p, s, y, n_base, n_vectors, w)


@kernel
def shift_tangent(p, d, unshift, y, n_base, n_vectors, w):
    """Convert each tangent vector between the plain and the approach phase's shifted form.

    ``w = v - c(d) e_F (grad(d) . v)`` (``unshift`` False: into the approach
    phase), ``v = w + c(d) e_F (grad(d) . w)`` (True: out of it), with ``c(d)``
    the law's ``law_shift_scale`` (Jankowski's damping coefficient ``c_s d^q``,
    0 for d <= 0) and the same difference of the model's Jacobian-vector
    products as :func:`saltation_tangent`.

    Parameters
    ----------
    p : ndarray
        Packed parameters.
    d : float
        Penetration of the point contact where the vectors are converted (units of A_g).
    unshift : bool
        True: shifted to plain vectors; False: plain to shifted.
    y : ndarray
        State followed by ``n_vectors`` tangent vectors of ``n_base`` values;
        the vectors are changed in place.
    w : ndarray
        Workspace of at least ``2 n_base`` values.
    """
    c = law_shift_scale(p, LAW, d)
    if c == 0.0:
        return
    _add_force_column(p, c if unshift else -c, y, n_base, n_vectors, w)


@inline
def _add_force_column(p, s, y, n_base, n_vectors, w):
    """``v += e_F s (grad(d) . v)`` for every tangent vector of ``y`` (s in K_Ax / omega_Ax)."""
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
