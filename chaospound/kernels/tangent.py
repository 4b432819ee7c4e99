"""Linearised dynamics: Jacobian-vector products of every model (docs/model.md section 12).

The variational equations ``V' = J(t, y) V`` need ``J v`` for several tangent
vectors per right-hand-side call. :func:`linearize` computes, once per call,
the handful of state-dependent scalars the product needs (for the towers: the
contact force, its four derivatives with respect to the centre penetration
and the slope, the rotations and lever arms); :func:`apply_jvp` then costs a
few dozen flops per vector and allocates nothing. The contact force is
continuous (chi >= 1), so no saltation matrix is needed at contact events.

The products follow the generalised contact forces of :mod:`.models`::

    dd_c  = dX_A + th_A dY_A + (y_cA - y_c) dth_A - dX_B - th_B dY_B - (y_cB - y_c) dth_B
    dslope = dth_B - dth_A
    dQ_XA = -dF,  dQ_YA = -th_A dF - F dth_A,  dQ_thA = dM - (y_cA - y_c) dF - F dY_A
    dQ_XB = +dF,  dQ_YB = +th_B dF + F dth_B,  dQ_thB = -dM + (y_cB - y_c) dF + F dY_B

with ``dF = F_c dd_c + F_s dslope`` and ``dM = M_c dd_c + M_s dslope``.
"""

from .contact import line_contact, line_contact_gradient
from .jit import kernel
from .params import (
    DUFFING,
    LORENZ,
    P_BETA,
    P_CHI,
    P_GAP,
    P_HALF_L,
    P_Y_C,
    P_Y_OFF,
    PAIR,
    REF_0,
    REF_1,
    REF_2,
    T_CT,
    T_CX,
    T_CY,
    T_EX,
    T_EY,
    T_KTH,
    T_MU,
    T_MU_RHO2,
    T_OM2,
    T_OMT2,
    TOWER_A,
    TOWER_B,
    TOWER_WALL,
    TOWERS,
    WALL,
)
from .powers import ground, power


@kernel
def linearize(model, t, y, p):
    """State-dependent coefficients of ``J(t, y)`` (a 9-tuple of floats)."""
    if model == TOWERS:
        th_a = y[4]
        th_b = y[10]
        y_c = p[P_Y_C]
        half = p[P_HALF_L]
        arm_a = y[2] + p[TOWER_A + T_EY] - y_c
        arm_b = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY] - y_c
        d_c = y[0] - y[6] - p[P_GAP] + th_a * arm_a - th_b * arm_b
        force, _, d_lo, d_hi = line_contact(d_c, th_b - th_a, half, p[P_BETA], p[P_CHI])
        fc, fs, mc, ms = line_contact_gradient(d_lo, d_hi, half, p[P_BETA], p[P_CHI])
        return force, fc, fs, mc, ms, th_a, th_b, arm_a, arm_b
    if model == TOWER_WALL:
        th_a = y[4]
        y_c = p[P_Y_C]
        half = p[P_HALF_L]
        arm_a = y[2] + p[TOWER_A + T_EY] - y_c
        ug, _ = ground(t, p)
        d_c = y[0] - ug - p[P_GAP] + th_a * arm_a
        force, _, d_lo, d_hi = line_contact(d_c, -th_a, half, p[P_BETA], p[P_CHI])
        fc, fs, mc, ms = line_contact_gradient(d_lo, d_hi, half, p[P_BETA], p[P_CHI])
        return force, fc, fs, mc, ms, th_a, 0.0, arm_a, 0.0
    if model == PAIR or model == WALL:
        if model == PAIR:
            d = y[0] - y[2] - p[P_GAP]
        else:
            d = y[0] - ground(t, p)[0] - p[P_GAP]
        chi = p[P_CHI]
        stiffness = p[P_BETA] * chi * power(d, chi - 1.0) if d > 0.0 else 0.0
        return stiffness, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if model == LORENZ:
        return y[0], y[1], y[2], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # DUFFING
    return y[0], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@kernel
def apply_jvp(model, p, lin, v, out):
    """``out = J v`` with the coefficients ``lin`` of :func:`linearize`."""
    if model == TOWERS:
        _structural_jvp(p, TOWER_A, v, out, 0)
        _structural_jvp(p, TOWER_B, v, out, 6)
        force, fc, fs, mc, ms, th_a, th_b, arm_a, arm_b = lin
        if force == 0.0 and fc == 0.0:
            return
        ddc = v[0] + th_a * v[2] + arm_a * v[4] - v[6] - th_b * v[8] - arm_b * v[10]
        dsl = v[10] - v[4]
        d_force = fc * ddc + fs * dsl
        d_moment = mc * ddc + ms * dsl
        mu_a = p[TOWER_A + T_MU]
        mu_b = p[TOWER_B + T_MU]
        out[1] -= mu_a * d_force
        out[3] += mu_a * (-th_a * d_force - force * v[4])
        out[5] += p[TOWER_A + T_MU_RHO2] * (d_moment - arm_a * d_force - force * v[2])
        out[7] += mu_b * d_force
        out[9] += mu_b * (th_b * d_force + force * v[10])
        out[11] += p[TOWER_B + T_MU_RHO2] * (-d_moment + arm_b * d_force + force * v[8])
    elif model == TOWER_WALL:
        _structural_jvp(p, TOWER_A, v, out, 0)
        force, fc, fs, mc, ms, th_a, _, arm_a, _ = lin
        if force == 0.0 and fc == 0.0:
            return
        ddc = v[0] + th_a * v[2] + arm_a * v[4]
        dsl = -v[4]
        d_force = fc * ddc + fs * dsl
        d_moment = mc * ddc + ms * dsl
        mu_a = p[TOWER_A + T_MU]
        out[1] -= mu_a * d_force
        out[3] += mu_a * (-th_a * d_force - force * v[4])
        out[5] += p[TOWER_A + T_MU_RHO2] * (d_moment - arm_a * d_force - force * v[2])
    elif model == PAIR:
        stiffness = lin[0]
        a = TOWER_A
        b = TOWER_B
        squeeze = stiffness * (v[0] - v[2])
        out[0] = v[1]
        out[1] = -p[a + T_OM2] * v[0] - p[a + T_CX] * v[1] - p[a + T_MU] * squeeze
        out[2] = v[3]
        out[3] = -p[b + T_OM2] * v[2] - p[b + T_CX] * v[3] + p[b + T_MU] * squeeze
    elif model == WALL:
        a = TOWER_A
        out[0] = v[1]
        out[1] = -(p[a + T_OM2] + p[a + T_MU] * lin[0]) * v[0] - p[a + T_CX] * v[1]
    elif model == LORENZ:
        x, yy, z = lin[0], lin[1], lin[2]
        out[0] = p[REF_0] * (v[1] - v[0])
        out[1] = (p[REF_1] - z) * v[0] - v[1] - x * v[2]
        out[2] = yy * v[0] + x * v[1] - p[REF_2] * v[2]
    elif model == DUFFING:
        x = lin[0]
        out[0] = v[1]
        out[1] = -(p[REF_1] + 3.0 * p[REF_2] * x * x) * v[0] - p[REF_0] * v[1]


@kernel
def _structural_jvp(p, base, v, out, off):
    """Contact-free part of one tower's block of ``J v`` (docs/model.md section 5)."""
    om2 = p[base + T_OM2]
    ex = p[base + T_EX]
    ey = p[base + T_EY]
    vx = v[off]
    vy = v[off + 2]
    vth = v[off + 4]
    out[off] = v[off + 1]
    out[off + 1] = -om2 * (vx + ey * vth) - p[base + T_CX] * v[off + 1]
    out[off + 2] = v[off + 3]
    out[off + 3] = -om2 * (vy - ex * vth) - p[base + T_CY] * v[off + 3]
    out[off + 4] = v[off + 5]
    out[off + 5] = (-p[base + T_CT] * v[off + 5] - p[base + T_KTH] * (ey * vx - ex * vy)
                    - p[base + T_OMT2] * vth)
