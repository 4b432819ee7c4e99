"""Tower A (X, Y, th) pounding on a rigid ground-borne wall along a line (6 states).

docs/model.md section 9 (the reduction of the towers model to one tower). State
``(X_A, X_A', Y_A, Y_A', th_A, th_A')``. A template, as
:mod:`chaospound.physics.models.towers`; the wall moves with the ground.

A ground motion's y component (``GROUND_Y``) drives the tower's Y equation
only: the wall is taken as long in y, so sliding along its own face it changes
neither the penetration nor the contact line (no friction is modelled), and the
contact terms are those of the x-only model (docs/ground_motions.md section 2).
"""

from chaospound.kernels.free import (
    GROUND,
    GROUND_Y,
    LAW,
    LAW_DISSIPATIVE,
    ground_acceleration,
    ground_at,
    ground_at_y,
    law_line_force,
    law_line_force_rate,
    law_line_gradient,
    law_line_memory_force,
    law_line_potential,
)
from chaospound.kernels.jit import inline, kernel
from chaospound.kernels.params import (
    P_GAP,
    P_HALF_L,
    P_Y_C,
    T_CT,
    T_CX,
    T_CY,
    T_EY,
    T_MU,
    T_MU_RHO2,
    TOWER_A,
)
from chaospound.physics.corners import CORNER_A_MINUS, CORNER_A_PLUS, CORNER_FACE, FACE_TOL
from chaospound.physics.towers import structural_jvp, tower_accel, tower_accel_xy, tower_energy

# ==== template ====
N_BASE = 6
N_ENDS = 2


@inline
def model_rhs(t, y, p, ug, vg, out):
    """Time derivative of the state, into ``out``."""
    th_a = y[4]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    d_c = y[0] - ug - p[P_GAP] - th_a * (y_c - y_ca)
    rate_c, rate_slope = _rates(t, y, p)
    force, moment, _, _ = law_line_force(p, LAW, d_c, -th_a, rate_c, rate_slope, p[P_HALF_L])
    if GROUND_Y:  # a constant of the composition: the other branch compiles away
        ugy, vgy = ground_at_y(t, p, GROUND)
        tower_accel_xy(p, TOWER_A, y[0], y[1], y[2], y[3], th_a, y[5], ug, vg, ugy, vgy,
                       -force, -th_a * force, moment - (y_ca - y_c) * force, out, 0)
    else:
        tower_accel(p, TOWER_A, y[0], y[1], y[2], y[3], th_a, y[5], ug, vg,
                    -force, -th_a * force, moment - (y_ca - y_c) * force, out, 0)


@inline
def _rates(t, y, p):
    """``(d d_c/dt, d slope/dt)`` for a law that depends on the penetration rate
    (against the moving wall); ``(0, 0)`` for an elastic law."""
    if LAW_DISSIPATIVE:
        return model_rate(t, y, p, p[P_Y_C]), -y[5]
    return 0.0, 0.0


@inline
def _gap_at(y, p, ug, y_at):
    """Penetration d(y) at global height ``y_at``."""
    y_ca = y[2] + p[TOWER_A + T_EY]
    return y[0] - ug - p[P_GAP] - y[4] * (y_at - y_ca)


@inline
def model_rate(t, y, p, y_at):
    """Impact velocity ``partial d / partial t`` at ``y_at`` against the moving wall."""
    _, vg = ground_at(t, p, GROUND)
    y_ca = y[2] + p[TOWER_A + T_EY]
    return y[1] - vg - y[5] * (y_at - y_ca) + y[4] * y[3]


@inline
def model_ends(t, y, p, out):
    """``out = (d_lo, d_hi, d d_lo/dt, d d_hi/dt)`` at the ends of the contact line."""
    ug, vg = ground_at(t, p, GROUND)
    half = p[P_HALF_L]
    y_c = p[P_Y_C]
    out[0] = _gap_at(y, p, ug, y_c - half)
    out[1] = _gap_at(y, p, ug, y_c + half)
    out[2] = model_rate(t, y, p, y_c - half)
    out[3] = model_rate(t, y, p, y_c + half)


@kernel
def model_forces(t, y, p, q_out):
    """Generalised contact forces on A into q_out[0:3] (the rest 0); returns ``-Q_XA``."""
    ug, _ = ground_at(t, p, GROUND)
    for i in range(6):
        q_out[i] = 0.0
    th_a = y[4]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    d_c = y[0] - ug - p[P_GAP] - th_a * (y_c - y_ca)
    rate_c, rate_slope = _rates(t, y, p)
    force, moment, _, _ = law_line_force(p, LAW, d_c, -th_a, rate_c, rate_slope, p[P_HALF_L])
    q_out[0] = -force
    q_out[1] = -th_a * force
    q_out[2] = moment - (y_ca - y_c) * force
    return -q_out[0]


@kernel
def model_force_rate(t, y, p, ends):
    """Time derivative of the resultant contact force; ``ends`` from :func:`model_ends`."""
    if ends[0] <= 0.0 and ends[1] <= 0.0:
        return 0.0
    return law_line_force_rate(p, LAW, ends[0], ends[1], ends[2], ends[3], p[P_HALF_L])


@kernel
def model_potential(t, y, p):
    """Contact potential V_c, units of A_g^2 k_Ax."""
    ug, _ = ground_at(t, p, GROUND)
    half = p[P_HALF_L]
    y_c = p[P_Y_C]
    return law_line_potential(p, LAW, _gap_at(y, p, ug, y_c - half),
                              _gap_at(y, p, ug, y_c + half))


@kernel
def model_energy(y, p):
    """Structural, kinetic and contact energy (docs/model.md section 7)."""
    e = tower_energy(p, TOWER_A, y[0], y[1], y[2], y[3], y[4], y[5])
    return e + model_potential(0.0, y, p)


@kernel
def model_trace(p):
    """Constant trace of the Jacobian."""
    tr = -p[TOWER_A + T_CX]
    tr -= p[TOWER_A + T_CY] + p[TOWER_A + T_CT]
    return tr


@kernel
def model_linearize(t, y, p):
    """State-dependent coefficients of ``J(t, y)`` (a 9-tuple of floats)."""
    th_a = y[4]
    y_c = p[P_Y_C]
    half = p[P_HALF_L]
    arm_a = y[2] + p[TOWER_A + T_EY] - y_c
    ug, _ = ground_at(t, p, GROUND)
    d_c = y[0] - ug - p[P_GAP] + th_a * arm_a
    rate_c, rate_slope = _rates(t, y, p)
    force, _, d_lo, d_hi = law_line_force(p, LAW, d_c, -th_a, rate_c, rate_slope, half)
    r_lo = rate_c - rate_slope * half
    r_hi = rate_c + rate_slope * half
    fc, fs, mc, ms, frc, frs, mrc, mrs = law_line_gradient(p, LAW, d_lo, d_hi, r_lo, r_hi, half)
    return (force, fc, fs, mc, ms, th_a, 0.0, arm_a, 0.0, frc, frs, mrc, mrs,
            y[3], 0.0, y[5], 0.0)


@kernel
def model_jvp(p, lin, v, out):
    """``out = J v`` with the coefficients ``lin`` of :func:`model_linearize`."""
    structural_jvp(p, TOWER_A, v, out, 0)
    force, fc, fs, mc, ms, th_a, _, arm_a, _ = lin[:9]
    if force == 0.0 and fc == 0.0:
        return
    ddc = v[0] + th_a * v[2] + arm_a * v[4]
    dsl = -v[4]
    d_force = fc * ddc + fs * dsl
    d_moment = mc * ddc + ms * dsl
    if LAW_DISSIPATIVE:
        frc, frs, mrc, mrs, vy_a, _, vth_a, _ = lin[9:]
        drc = v[1] + arm_a * v[5] + vth_a * v[2] + vy_a * v[4] + th_a * v[3]
        drs = -v[5]
        d_force += frc * drc + frs * drs
        d_moment += mrc * drc + mrs * drs
    mu_a = p[TOWER_A + T_MU]
    out[1] -= mu_a * d_force
    out[3] += mu_a * (-th_a * d_force - force * v[4])
    out[5] += p[TOWER_A + T_MU_RHO2] * (d_moment - arm_a * d_force - force * v[2])


@kernel
def model_contact_point(t, state, p, ends):
    """``(corner code, global y, impact velocity)`` of an onset; ``ends`` at (t, state)."""
    d_lo = ends[0]
    d_hi = ends[1]
    d_max = max(d_lo, d_hi)
    y_c = p[P_Y_C]
    half = p[P_HALF_L]
    if abs(d_lo - d_hi) < FACE_TOL * max(1.0, abs(d_max)):
        corner = CORNER_FACE
        y_at = y_c
    elif d_hi > d_lo:
        y_at = y_c + half
        corner = CORNER_A_PLUS
    else:
        y_at = y_c - half
        corner = CORNER_A_MINUS
    return corner, y_at, model_rate(t, state, p, y_at)


# ---- a law's per-episode memory in the tangent dynamics (docs/contact_laws.md 7)


@kernel
def model_memory_linearize(t, y, p):
    """``(F_xi, M_xi, th_A, arm_A)``: the contact resultants' derivatives with respect
    to the law's memory xi, and the geometry that maps them."""
    th_a = y[4]
    y_c = p[P_Y_C]
    arm_a = y[2] + p[TOWER_A + T_EY] - y_c
    ug, _ = ground_at(t, p, GROUND)
    d_c = y[0] - ug - p[P_GAP] + th_a * arm_a
    rate_c, rate_slope = _rates(t, y, p)
    f_xi, m_xi = law_line_memory_force(p, LAW, d_c, -th_a, rate_c, rate_slope, p[P_HALF_L])
    return f_xi, m_xi, th_a, arm_a


@kernel
def model_memory_jvp(p, mem, dxi, out):
    """``out += (df/dxi) dxi`` with the coefficients of :func:`model_memory_linearize`."""
    f_xi, m_xi, th_a, arm_a = mem
    if dxi == 0.0 or (f_xi == 0.0 and m_xi == 0.0):
        return
    d_force = f_xi * dxi
    mu_a = p[TOWER_A + T_MU]
    out[1] -= mu_a * d_force
    out[3] -= mu_a * th_a * d_force
    out[5] += p[TOWER_A + T_MU_RHO2] * (m_xi * dxi - arm_a * d_force)


@kernel
def model_onset_variation(t, y, p, v, y_at):
    """``(dd, dV)``: variations of the penetration and of the closing velocity
    (:func:`model_rate`) at height ``y_at`` along the state variation ``v``, at fixed t."""
    lever = y_at - (y[2] + p[TOWER_A + T_EY])
    dd = v[0] - v[4] * lever + y[4] * v[2]
    dv = v[1] - v[5] * lever + y[5] * v[2] + v[4] * y[3] + y[4] * v[3]
    return dd, dv


@kernel
def model_onset_accel(t, y, p, f, y_at):
    """Closing acceleration ``dV/dt`` at ``y_at`` along the flow ``f``, the wall's
    acceleration included (V holds ``-u_g'(t)``)."""
    _, dv = model_onset_variation(t, y, p, f, y_at)
    return dv - ground_acceleration(t, p, GROUND)
