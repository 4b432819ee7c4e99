"""The 12-state torsional model: two towers (X, Y, th each) pounding along a line.

docs/model.md sections 5-9. State ``(X_A, X_A', Y_A, Y_A', th_A, th_A', X_B, ...,
th_B')``. A model module is a template (:mod:`chaospound.engine.compose`): it
calls the contact law through ``law_*`` and the ground through ``ground_*``,
which each composition binds, so the model never imports a law or a motion.

Generalised contact forces ``Q = -dV/dq`` of the line contact (docs/model.md 6),
with ``I0 = (beta/L) int d+^chi dy`` and ``F1 = (beta/L) int d+^chi (y - y_c) dy``
for the Hertz law (any law: its resultant force and first moment)::

    Q_XA = -I0,          Q_XB = +I0
    Q_YA = -th_A I0,     Q_YB = +th_B I0
    Q_thA = F1 - (y_cA - y_c) I0,   Q_thB = -(F1 - (y_cB - y_c) I0)

The linearisation (variational equations, docs/model.md section 12)::

    dd_c  = dX_A + th_A dY_A + (y_cA - y_c) dth_A - dX_B - th_B dY_B - (y_cB - y_c) dth_B
    dslope = dth_B - dth_A
    dQ_XA = -dF,  dQ_YA = -th_A dF - F dth_A,  dQ_thA = dM - (y_cA - y_c) dF - F dY_A
    dQ_XB = +dF,  dQ_YB = +th_B dF + F dth_B,  dQ_thB = -dM + (y_cB - y_c) dF + F dY_B

with ``dF = F_c dd_c + F_s dslope`` and ``dM = M_c dd_c + M_s dslope``; a law that
depends on the penetration rate adds ``F_rc d rate_c + F_rs d rate_slope`` (and the
same for M), with ``rate_c = X_A' - X_B' + th_A' arm_A - th_B' arm_B + th_A Y_A'
- th_B Y_B'`` (``arm_i = y_ci - y_c``) and ``rate_slope = th_B' - th_A'``.
"""

from chaospound.kernels.free import (
    GROUND,
    GROUND_Y,
    LAW,
    LAW_DISSIPATIVE,
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
    P_Y_OFF,
    T_CT,
    T_CX,
    T_CY,
    T_EX,
    T_EY,
    T_L,
    T_MU,
    T_MU_RHO2,
    T_W,
    TOWER_A,
    TOWER_B,
)
from chaospound.physics.corners import (
    CORNER_A_MINUS,
    CORNER_A_PLUS,
    CORNER_B_MINUS,
    CORNER_B_PLUS,
    CORNER_FACE,
    FACE_TOL,
)
from chaospound.physics.towers import structural_jvp, tower_accel, tower_accel_xy, tower_energy

# ==== template ====
N_BASE = 12
N_ENDS = 2


@inline
def model_rhs(t, y, p, ug, vg, out):
    """Time derivative of the state (docs/model.md section 5), into ``out``.

    ``(ug, vg)`` is the ground's x motion at t; a composition with ``GROUND_Y``
    (a constant: the other branch compiles away) adds its y motion
    ``ground_at_y``, which drives both towers' Y equations.
    """
    th_a = y[4]
    th_b = y[10]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
    d_c = y[0] - y[6] - p[P_GAP] - th_a * (y_c - y_ca) + th_b * (y_c - y_cb)
    rate_c, rate_slope = _rates(t, y, p)
    force, moment, _, _ = law_line_force(p, LAW, d_c, th_b - th_a, rate_c, rate_slope,
                                         p[P_HALF_L])
    q_tha = moment - (y_ca - y_c) * force
    q_thb = -(moment - (y_cb - y_c) * force)
    if GROUND_Y:
        ugy, vgy = ground_at_y(t, p, GROUND)
        tower_accel_xy(p, TOWER_A, y[0], y[1], y[2], y[3], th_a, y[5], ug, vg, ugy, vgy,
                       -force, -th_a * force, q_tha, out, 0)
        tower_accel_xy(p, TOWER_B, y[6], y[7], y[8], y[9], th_b, y[11], ug, vg, ugy, vgy,
                       force, th_b * force, q_thb, out, 6)
    else:
        tower_accel(p, TOWER_A, y[0], y[1], y[2], y[3], th_a, y[5], ug, vg,
                    -force, -th_a * force, q_tha, out, 0)
        tower_accel(p, TOWER_B, y[6], y[7], y[8], y[9], th_b, y[11], ug, vg,
                    force, th_b * force, q_thb, out, 6)


@inline
def _rates(t, y, p):
    """``(d d_c/dt, d slope/dt)`` for a law that depends on the penetration rate.

    d(y, t) is linear in y, and so is its time derivative at fixed y: its value
    at the overlap's centre (:func:`model_rate`) and its slope ``th_B' - th_A'``.
    An elastic law does not read them (``LAW_DISSIPATIVE`` is a constant of the
    composition, so the branch compiles away).
    """
    if LAW_DISSIPATIVE:
        return model_rate(t, y, p, p[P_Y_C]), y[11] - y[5]
    return 0.0, 0.0


@inline
def _gap_at(y, p, y_at):
    """Penetration d(y) at global height ``y_at``."""
    y_ca = y[2] + p[TOWER_A + T_EY]
    y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
    return y[0] - y[6] - p[P_GAP] - y[4] * (y_at - y_ca) + y[10] * (y_at - y_cb)


@inline
def model_rate(t, y, p, y_at):
    """Relative impact velocity ``partial d / partial t`` at global height ``y_at``.

    ``V = X_A' - X_B' - th_A' (y - y_cA) + th_B' (y - y_cB) + th_A Y_A' - th_B Y_B'``
    (units of A_g omega_Ax).
    """
    y_ca = y[2] + p[TOWER_A + T_EY]
    y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
    return (
        y[1] - y[7] - y[5] * (y_at - y_ca) + y[11] * (y_at - y_cb) + y[4] * y[3] - y[10] * y[9]
    )


@inline
def model_ends(t, y, p, out):
    """Penetrations and their rates at the two ends of the contact line.

    ``out = (d_lo, d_hi, d d_lo/dt, d d_hi/dt)`` (rates at fixed y: the relative
    velocity of the material points, docs/model.md section 8).
    """
    half = p[P_HALF_L]
    y_c = p[P_Y_C]
    out[0] = _gap_at(y, p, y_c - half)
    out[1] = _gap_at(y, p, y_c + half)
    out[2] = model_rate(t, y, p, y_c - half)
    out[3] = model_rate(t, y, p, y_c + half)


@kernel
def model_forces(t, y, p, q_out):
    """Generalised contact forces ``Q = -dV/dq`` into q_out (X_A, Y_A, th_A, X_B, Y_B, th_B).

    Returns the resultant compressive force ``-Q_XA`` (units of A_g k_Ax).
    """
    th_a = y[4]
    th_b = y[10]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
    d_c = y[0] - y[6] - p[P_GAP] - th_a * (y_c - y_ca) + th_b * (y_c - y_cb)
    rate_c, rate_slope = _rates(t, y, p)
    force, moment, _, _ = law_line_force(p, LAW, d_c, th_b - th_a, rate_c, rate_slope,
                                         p[P_HALF_L])
    q_out[0] = -force
    q_out[1] = -th_a * force
    q_out[2] = moment - (y_ca - y_c) * force
    q_out[3] = force
    q_out[4] = th_b * force
    q_out[5] = -(moment - (y_cb - y_c) * force)
    return -q_out[0]


@kernel
def model_force_rate(t, y, p, ends):
    """Time derivative of the resultant contact force; ``ends`` from :func:`model_ends`."""
    if ends[0] <= 0.0 and ends[1] <= 0.0:
        return 0.0
    return law_line_force_rate(p, LAW, ends[0], ends[1], ends[2], ends[3], p[P_HALF_L])


@kernel
def model_potential(t, y, p):
    """Contact potential V_c (docs/model.md section 6), units of A_g^2 k_Ax."""
    half = p[P_HALF_L]
    y_c = p[P_Y_C]
    return law_line_potential(p, LAW, _gap_at(y, p, y_c - half), _gap_at(y, p, y_c + half))


@kernel
def model_energy(y, p):
    """Structural, kinetic and contact energy (docs/model.md section 7)."""
    e = tower_energy(p, TOWER_A, y[0], y[1], y[2], y[3], y[4], y[5])
    e += tower_energy(p, TOWER_B, y[6], y[7], y[8], y[9], y[10], y[11])
    return e + model_potential(0.0, y, p)


@kernel
def model_trace(p):
    """Constant trace of the Jacobian: the sum of all exponents (docs/model.md 12)."""
    tr = -p[TOWER_A + T_CX]
    tr -= p[TOWER_A + T_CY] + p[TOWER_A + T_CT]
    tr -= p[TOWER_B + T_CX] + p[TOWER_B + T_CY] + p[TOWER_B + T_CT]
    return tr


@inline
def model_linearize(t, y, p):
    """State-dependent coefficients of ``J(t, y)`` (a 17-tuple of floats), inlined into
    the tangent right-hand side."""
    th_a = y[4]
    th_b = y[10]
    y_c = p[P_Y_C]
    half = p[P_HALF_L]
    arm_a = y[2] + p[TOWER_A + T_EY] - y_c
    arm_b = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY] - y_c
    d_c = y[0] - y[6] - p[P_GAP] + th_a * arm_a - th_b * arm_b
    rate_c, rate_slope = _rates(t, y, p)
    force, _, d_lo, d_hi = law_line_force(p, LAW, d_c, th_b - th_a, rate_c, rate_slope, half)
    r_lo = rate_c - rate_slope * half
    r_hi = rate_c + rate_slope * half
    fc, fs, mc, ms, frc, frs, mrc, mrs = law_line_gradient(p, LAW, d_lo, d_hi, r_lo, r_hi, half)
    return (force, fc, fs, mc, ms, th_a, th_b, arm_a, arm_b, frc, frs, mrc, mrs,
            y[3], y[9], y[5], y[11])


@inline
def model_jvp(p, lin, v, out):
    """``out = J v`` with the coefficients ``lin`` of :func:`model_linearize`.

    Inlined into the tangent right-hand side's loop over the vectors: a call
    would pass the 17 coefficients and three arrays field by field for each
    vector (benchmarks/bench_lyapunov.py, results/bench_lyapunov.json).
    """
    structural_jvp(p, TOWER_A, v, out, 0)
    structural_jvp(p, TOWER_B, v, out, 6)
    force, fc, fs, mc, ms, th_a, th_b, arm_a, arm_b = lin[:9]
    if force == 0.0 and fc == 0.0:
        return
    ddc = v[0] + th_a * v[2] + arm_a * v[4] - v[6] - th_b * v[8] - arm_b * v[10]
    dsl = v[10] - v[4]
    d_force = fc * ddc + fs * dsl
    d_moment = mc * ddc + ms * dsl
    if LAW_DISSIPATIVE:
        frc, frs, mrc, mrs, vy_a, vy_b, vth_a, vth_b = lin[9:]
        drc = (v[1] - v[7] + arm_a * v[5] + vth_a * v[2] - arm_b * v[11] - vth_b * v[8]
               + vy_a * v[4] + th_a * v[3] - vy_b * v[10] - th_b * v[9])
        drs = v[11] - v[5]
        d_force += frc * drc + frs * drs
        d_moment += mrc * drc + mrs * drs
    mu_a = p[TOWER_A + T_MU]
    mu_b = p[TOWER_B + T_MU]
    out[1] -= mu_a * d_force
    out[3] += mu_a * (-th_a * d_force - force * v[4])
    out[5] += p[TOWER_A + T_MU_RHO2] * (d_moment - arm_a * d_force - force * v[2])
    out[7] += mu_b * d_force
    out[9] += mu_b * (th_b * d_force + force * v[10])
    out[11] += p[TOWER_B + T_MU_RHO2] * (-d_moment + arm_b * d_force + force * v[8])


@kernel
def _corner_label(p, s, plus_end):
    """Whose corner is the inner one at the + (y_hi) or - (y_lo) end (docs/model.md 8)."""
    a = TOWER_A
    b = TOWER_B
    sign = 1.0 if plus_end else -1.0
    h_a = s[2] + sign * 0.5 * p[a + T_L] + s[4] * (0.5 * p[a + T_W] - p[a + T_EX])
    h_b = s[8] + p[P_Y_OFF] + sign * 0.5 * p[b + T_L] - s[10] * (0.5 * p[b + T_W] + p[b + T_EX])
    if plus_end:
        return CORNER_A_PLUS if h_a <= h_b else CORNER_B_PLUS
    return CORNER_A_MINUS if h_a >= h_b else CORNER_B_MINUS


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
        corner = _corner_label(p, state, True)
    else:
        y_at = y_c - half
        corner = _corner_label(p, state, False)
    return corner, y_at, model_rate(t, state, p, y_at)


# ---- a law's per-episode memory in the tangent dynamics (docs/contact_laws.md 7)


@kernel
def model_memory_linearize(t, y, p):
    """``(F_xi, M_xi, th_A, th_B, arm_A, arm_B)``: the contact resultants' derivatives
    with respect to the law's memory xi, and the geometry that maps them."""
    th_a = y[4]
    th_b = y[10]
    y_c = p[P_Y_C]
    arm_a = y[2] + p[TOWER_A + T_EY] - y_c
    arm_b = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY] - y_c
    d_c = y[0] - y[6] - p[P_GAP] + th_a * arm_a - th_b * arm_b
    rate_c, rate_slope = _rates(t, y, p)
    f_xi, m_xi = law_line_memory_force(p, LAW, d_c, th_b - th_a, rate_c, rate_slope,
                                       p[P_HALF_L])
    return f_xi, m_xi, th_a, th_b, arm_a, arm_b


@kernel
def model_memory_jvp(p, mem, dxi, out):
    """``out += (df/dxi) dxi`` with the coefficients of :func:`model_memory_linearize`."""
    f_xi, m_xi, th_a, th_b, arm_a, arm_b = mem
    if dxi == 0.0 or (f_xi == 0.0 and m_xi == 0.0):
        return
    d_force = f_xi * dxi
    d_moment = m_xi * dxi
    mu_a = p[TOWER_A + T_MU]
    mu_b = p[TOWER_B + T_MU]
    out[1] -= mu_a * d_force
    out[3] -= mu_a * th_a * d_force
    out[5] += p[TOWER_A + T_MU_RHO2] * (d_moment - arm_a * d_force)
    out[7] += mu_b * d_force
    out[9] += mu_b * th_b * d_force
    out[11] += p[TOWER_B + T_MU_RHO2] * (-d_moment + arm_b * d_force)


@kernel
def model_onset_variation(t, y, p, v, y_at):
    """``(dd, dV)``: variations of the penetration and of the closing velocity
    (:func:`model_rate`) at height ``y_at`` along the state variation ``v``, at fixed t."""
    lever_a = y_at - (y[2] + p[TOWER_A + T_EY])
    lever_b = y_at - (y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY])
    dd = v[0] - v[6] - v[4] * lever_a + y[4] * v[2] + v[10] * lever_b - y[10] * v[8]
    dv = (v[1] - v[7] - v[5] * lever_a + y[5] * v[2] + v[11] * lever_b - y[11] * v[8]
          + v[4] * y[3] + y[4] * v[3] - v[10] * y[9] - y[10] * v[9])
    return dd, dv


@kernel
def model_onset_accel(t, y, p, f, y_at):
    """Closing acceleration ``dV/dt`` at ``y_at`` along the flow ``f`` (V has no
    explicit time dependence: the towers' relative motion)."""
    _, dv = model_onset_variation(t, y, p, f, y_at)
    return dv
