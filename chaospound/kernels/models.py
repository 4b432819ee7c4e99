"""Right-hand sides, Jacobians and contact geometry of the four pounding models.

docs/model.md sections 5-9. Every function dispatches on the integer model id of
:mod:`chaospound.kernels.params` (WALL, TOWER_WALL, PAIR, TOWERS); state
layouts:

* WALL       (X_A, X_A')
* TOWER_WALL (X_A, X_A', Y_A, Y_A', th_A, th_A')
* PAIR       (X_A, X_A', X_B, X_B')
* TOWERS     (X_A, X_A', Y_A, Y_A', th_A, th_A', X_B, ..., th_B')

``t`` is the forcing time: the ground motion is ``u_g = sin(t / r)``. Callers
keep ``t`` reduced to within one excitation period of the section origin so
that the phase never drifts (see :mod:`chaospound.kernels.integrate`).

Generalised contact forces ``Q = -dV/dq`` of the line contact (docs/model.md 6),
with ``I0 = (beta/L) int d+^chi dy`` and ``F1 = (beta/L) int d+^chi (y - y_c) dy``::

    Q_XA = -I0,          Q_XB = +I0
    Q_YA = -th_A I0,     Q_YB = +th_B I0
    Q_thA = F1 - (y_cA - y_c) I0,   Q_thB = -(F1 - (y_cB - y_c) I0)
"""

import numpy as np

from .contact import line_contact, line_contact_gradient, line_potential
from .jit import driver, inline, kernel
from .params import (
    DUFFING,
    LORENZ,
    MODEL_DIMS,
    P_BETA,
    P_CHI,
    P_GAP,
    P_HALF_L,
    P_Y_C,
    P_Y_OFF,
    PAIR,
    REF_0,
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
    T_RHO2,
    TANGENT,
    TOWER_A,
    TOWER_B,
    TOWER_WALL,
    TOWERS,
    WALL,
)
from .powers import ground, power
from .reference import duffing_rhs, lorenz_rhs
from .tangent import apply_jvp, linearize


@kernel
def rhs(model, t, y, p, out):
    """Time derivative of the state (docs/model.md section 5), into ``out``.

    Model ids ``TANGENT + base`` integrate the state of ``base`` together with
    k tangent vectors stored after it (``y`` of length n (1 + k)): the
    variational equations ``V' = J V`` of docs/model.md section 12.
    """
    ug, vg = ground(t, p)
    rhs_grounded(model, t, y, p, ug, vg, out)


@kernel
def rhs_grounded(model, t, y, p, ug, vg, out):
    """:func:`rhs` with the ground motion ``(u_g, u_g')`` at t given.

    Lets a stepper that evaluates twice at one time (Dormand-Prince's last
    stage and its FSAL stage) compute the sine and cosine once. One out-of-line
    copy with the model bodies inlined, not inlined itself into each of the
    seven Dormand-Prince stages, which would double the compile time.
    """
    if model >= TANGENT:
        _rhs_tangent(model - TANGENT, t, y, p, ug, vg, out)
    else:
        _rhs_base(model, t, y, p, ug, vg, out)


@kernel
def _rhs_tangent(base, t, y, p, ug, vg, out):
    """State and tangent vectors: ``y' = f(y)``, ``V' = J(y) V``."""
    _rhs_base(base, t, y, p, ug, vg, out)
    n = MODEL_DIMS[base]
    lin = linearize(base, t, y, p)
    for i in range(1, y.shape[0] // n):
        apply_jvp(base, p, lin, y[i * n:(i + 1) * n], out[i * n:(i + 1) * n])


@inline
def _rhs_base(model, t, y, p, ug, vg, out):
    if model == TOWERS:
        _rhs_towers(y, p, ug, vg, out)
    elif model == PAIR:
        _rhs_pair(y, p, ug, vg, out)
    elif model == TOWER_WALL:
        _rhs_tower_wall(y, p, ug, vg, out)
    elif model == WALL:
        _rhs_wall(y, p, ug, vg, out)
    elif model == LORENZ:
        lorenz_rhs(t, y, p, out)
    else:
        duffing_rhs(t, y, p, out)


@driver
def jacobian(model, t, y, p, jac):
    """Analytic Jacobian ``d rhs / d y`` of a base model (n x n), into ``jac``.

    Built column by column from the Jacobian-vector product of
    :mod:`.tangent` (the one the variational equations use); allocates two
    vectors, so it is meant for tests and users, not inner loops.
    """
    n = MODEL_DIMS[model]
    lin = linearize(model, t, y, p)
    unit = np.zeros(n)
    column = np.zeros(n)
    for c in range(n):
        unit[c] = 1.0
        apply_jvp(model, p, lin, unit, column)
        unit[c] = 0.0
        for r in range(n):
            jac[r, c] = column[r]


@inline
def base_model(model):
    """The base model of a (possibly tangent) model id."""
    return model - TANGENT if model >= TANGENT else model


@inline
def contact_ends(model, t, y, p, out):
    """Penetrations and their rates at the two ends of the contact line.

    Writes ``out[0] = d_lo``, ``out[1] = d_hi``, ``out[2] = d d_lo/dt``,
    ``out[3] = d d_hi/dt`` (rates at fixed y: the relative velocity of the
    material points, docs/model.md section 8). For the translational models both
    ends carry the single penetration d; the reference systems have no
    contact: (-1, -1, 0, 0).
    """
    model = base_model(model)
    if model == LORENZ or model == DUFFING:
        out[0] = -1.0
        out[1] = -1.0
        out[2] = 0.0
        out[3] = 0.0
        return
    if model == TOWERS:
        ug = 0.0  # the towers' penetration does not involve the ground
    else:
        ug, vg = ground(t, p)
    if model == TOWERS or model == TOWER_WALL:
        half = p[P_HALF_L]
        y_c = p[P_Y_C]
        out[0] = _towers_gap(model, y, p, ug, y_c - half)
        out[1] = _towers_gap(model, y, p, ug, y_c + half)
        out[2] = penetration_rate(model, t, y, p, y_c - half)
        out[3] = penetration_rate(model, t, y, p, y_c + half)
    else:
        if model == PAIR:
            d = y[0] - y[2] - p[P_GAP]
            rate = y[1] - y[3]
        else:
            d = y[0] - ug - p[P_GAP]
            rate = y[1] - vg
        out[0] = d
        out[1] = d
        out[2] = rate
        out[3] = rate


@inline
def penetration_rate(model, t, y, p, y_at):
    """Relative impact velocity ``partial d / partial t`` at global height ``y_at``.

    ``V = X_A' - X_B' - th_A' (y - y_cA) + th_B' (y - y_cB) + th_A Y_A' - th_B Y_B'``
    (units of A_g omega_Ax); the wall models use the wall's velocity u_g'.
    """
    model = base_model(model)
    if model == TOWERS:
        y_ca = y[2] + p[TOWER_A + T_EY]
        y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
        return (
            y[1] - y[7] - y[5] * (y_at - y_ca) + y[11] * (y_at - y_cb) + y[4] * y[3] - y[10] * y[9]
        )
    _, vg = ground(t, p)
    if model == TOWER_WALL:
        y_ca = y[2] + p[TOWER_A + T_EY]
        return y[1] - vg - y[5] * (y_at - y_ca) + y[4] * y[3]
    if model == PAIR:
        return y[1] - y[3]
    return y[1] - vg


@kernel
def contact_potential(model, t, y, p):
    """Contact potential V_c (docs/model.md section 6), units of A_g^2 k_Ax."""
    model = base_model(model)
    if model == LORENZ or model == DUFFING:
        return 0.0
    ug, _ = ground(t, p)
    beta = p[P_BETA]
    chi = p[P_CHI]
    if model == TOWERS or model == TOWER_WALL:
        half = p[P_HALF_L]
        y_c = p[P_Y_C]
        d_lo = _towers_gap(model, y, p, ug, y_c - half)
        d_hi = _towers_gap(model, y, p, ug, y_c + half)
        return line_potential(d_lo, d_hi, beta, chi)
    if model == PAIR:
        d = y[0] - y[2] - p[P_GAP]
    else:
        d = y[0] - ug - p[P_GAP]
    if d <= 0.0:
        return 0.0
    return beta * power(d, chi + 1.0) / (chi + 1.0)


@kernel
def contact_forces(model, t, y, p, q_out):
    """Generalised contact forces ``Q = -dV/dq``.

    ``q_out`` has 6 entries in the order (X_A, Y_A, th_A, X_B, Y_B, th_B);
    entries a model does not have are set to 0. Returns the resultant
    compressive force ``-Q_XA`` (units of A_g k_Ax).
    """
    model = base_model(model)
    ug, _ = ground(t, p)
    for i in range(6):
        q_out[i] = 0.0
    if model == LORENZ or model == DUFFING:
        return 0.0
    if model == TOWERS:
        _towers_forces(y, p, q_out)
    elif model == TOWER_WALL:
        _tower_wall_forces(y, p, ug, q_out)
    else:
        if model == PAIR:
            d = y[0] - y[2] - p[P_GAP]
        else:
            d = y[0] - ug - p[P_GAP]
        force = p[P_BETA] * power(d, p[P_CHI]) if d > 0.0 else 0.0
        q_out[0] = -force
        if model == PAIR:
            q_out[3] = force
    return -q_out[0]


@kernel
def contact_force_rate(model, t, y, p, ends):
    """Time derivative of the resultant contact force ``-Q_XA``.

    ``ends`` must hold :func:`contact_ends` at (t, y). The force depends on the
    centre penetration and the slope, whose rates follow from the end rates:
    ``dF/dt = F_c (r_lo + r_hi) / 2 + F_s (r_hi - r_lo) / L``.
    """
    model = base_model(model)
    if ends[0] <= 0.0 and ends[1] <= 0.0:
        return 0.0
    beta = p[P_BETA]
    chi = p[P_CHI]
    if model == TOWERS or model == TOWER_WALL:
        half = p[P_HALF_L]
        fc, fs, _, _ = line_contact_gradient(ends[0], ends[1], half, beta, chi)
        return fc * 0.5 * (ends[2] + ends[3]) + fs * (ends[3] - ends[2]) / (2.0 * half)
    return beta * chi * power(ends[0], chi - 1.0) * ends[2]


@kernel
def energy(model, y, p):
    """Total mechanical energy (docs/model.md section 7), ground motion "none".

    ``E = sum_i (1/mu_i) [(X'^2 + Y'^2 + rho^2 th'^2)/2 + Om^2 (X^2 + Y^2
    + 2 e_y X th - 2 e_x Y th)/2 + rho^2 Om_t^2 th^2 / 2] + V``.
    Conserved when all damping ratios are 0 and the ground does not move.
    """
    if model == TOWERS:
        e = _tower_energy(p, TOWER_A, y[0], y[1], y[2], y[3], y[4], y[5])
        e += _tower_energy(p, TOWER_B, y[6], y[7], y[8], y[9], y[10], y[11])
    elif model == TOWER_WALL:
        e = _tower_energy(p, TOWER_A, y[0], y[1], y[2], y[3], y[4], y[5])
    elif model == PAIR:
        e = _tower_energy(p, TOWER_A, y[0], y[1], 0.0, 0.0, 0.0, 0.0)
        e += _tower_energy(p, TOWER_B, y[2], y[3], 0.0, 0.0, 0.0, 0.0)
    else:
        e = _tower_energy(p, TOWER_A, y[0], y[1], 0.0, 0.0, 0.0, 0.0)
    return e + contact_potential(model, 0.0, y, p)


@kernel
def jacobian_trace(model, p):
    """Constant trace of the Jacobian (docs/model.md section 12): sum of all exponents."""
    model = base_model(model)
    if model == LORENZ:
        return -p[REF_0] - 1.0 - p[REF_2]
    if model == DUFFING:
        return -p[REF_0]
    tr = -p[TOWER_A + T_CX]
    if model == TOWERS or model == TOWER_WALL:
        tr -= p[TOWER_A + T_CY] + p[TOWER_A + T_CT]
    if model == TOWERS:
        tr -= p[TOWER_B + T_CX] + p[TOWER_B + T_CY] + p[TOWER_B + T_CT]
    if model == PAIR:
        tr -= p[TOWER_B + T_CX]
    return tr


# --------------------------------------------------------------------- helpers


@inline
def _towers_gap(model, y, p, ug, y_at):
    """Penetration d(y) at global height ``y_at`` (TOWERS or TOWER_WALL)."""
    y_ca = y[2] + p[TOWER_A + T_EY]
    if model == TOWERS:
        y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
        return y[0] - y[6] - p[P_GAP] - y[4] * (y_at - y_ca) + y[10] * (y_at - y_cb)
    return y[0] - ug - p[P_GAP] - y[4] * (y_at - y_ca)


@kernel
def _towers_forces(y, p, q):
    """Line-contact forces between the two towers, into q (6 entries)."""
    th_a = y[4]
    th_b = y[10]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
    d_c = y[0] - y[6] - p[P_GAP] - th_a * (y_c - y_ca) + th_b * (y_c - y_cb)
    force, moment, _, _ = line_contact(d_c, th_b - th_a, p[P_HALF_L], p[P_BETA], p[P_CHI])
    q[0] = -force
    q[1] = -th_a * force
    q[2] = moment - (y_ca - y_c) * force
    q[3] = force
    q[4] = th_b * force
    q[5] = -(moment - (y_cb - y_c) * force)


@kernel
def _tower_wall_forces(y, p, ug, q):
    """Line-contact forces between tower A and the ground-borne wall."""
    th_a = y[4]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    d_c = y[0] - ug - p[P_GAP] - th_a * (y_c - y_ca)
    force, moment, _, _ = line_contact(d_c, -th_a, p[P_HALF_L], p[P_BETA], p[P_CHI])
    q[0] = -force
    q[1] = -th_a * force
    q[2] = moment - (y_ca - y_c) * force


@inline
def _tower_accel(p, base, x, vx, yy, vy, th, vth, ug, vg, qx, qy, qth, out, off):
    """Equations of motion of one tower (docs/model.md section 5) into out[off:off+6]."""
    om2 = p[base + T_OM2]
    mu = p[base + T_MU]
    ex = p[base + T_EX]
    ey = p[base + T_EY]
    xr = x - ug
    out[off] = vx
    out[off + 1] = -p[base + T_CX] * (vx - vg) - om2 * (xr + ey * th) + mu * qx
    out[off + 2] = vy
    out[off + 3] = -p[base + T_CY] * vy - om2 * (yy - ex * th) + mu * qy
    out[off + 4] = vth
    out[off + 5] = (
        -p[base + T_CT] * vth
        - p[base + T_KTH] * (ey * xr - ex * yy)
        - p[base + T_OMT2] * th
        + p[base + T_MU_RHO2] * qth
    )


@inline
def _rhs_towers(y, p, ug, vg, out):
    th_a = y[4]
    th_b = y[10]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    y_cb = y[8] + p[P_Y_OFF] + p[TOWER_B + T_EY]
    d_c = y[0] - y[6] - p[P_GAP] - th_a * (y_c - y_ca) + th_b * (y_c - y_cb)
    force, moment, _, _ = line_contact(d_c, th_b - th_a, p[P_HALF_L], p[P_BETA], p[P_CHI])
    q_tha = moment - (y_ca - y_c) * force
    q_thb = -(moment - (y_cb - y_c) * force)
    _tower_accel(p, TOWER_A, y[0], y[1], y[2], y[3], th_a, y[5], ug, vg,
                 -force, -th_a * force, q_tha, out, 0)
    _tower_accel(p, TOWER_B, y[6], y[7], y[8], y[9], th_b, y[11], ug, vg,
                 force, th_b * force, q_thb, out, 6)


@inline
def _rhs_tower_wall(y, p, ug, vg, out):
    th_a = y[4]
    y_c = p[P_Y_C]
    y_ca = y[2] + p[TOWER_A + T_EY]
    d_c = y[0] - ug - p[P_GAP] - th_a * (y_c - y_ca)
    force, moment, _, _ = line_contact(d_c, -th_a, p[P_HALF_L], p[P_BETA], p[P_CHI])
    _tower_accel(p, TOWER_A, y[0], y[1], y[2], y[3], th_a, y[5], ug, vg,
                 -force, -th_a * force, moment - (y_ca - y_c) * force, out, 0)


@inline
def _rhs_pair(y, p, ug, vg, out):
    d = y[0] - y[2] - p[P_GAP]
    force = p[P_BETA] * power(d, p[P_CHI]) if d > 0.0 else 0.0
    a = TOWER_A
    b = TOWER_B
    out[0] = y[1]
    out[1] = -p[a + T_CX] * (y[1] - vg) - p[a + T_OM2] * (y[0] - ug) - p[a + T_MU] * force
    out[2] = y[3]
    out[3] = -p[b + T_CX] * (y[3] - vg) - p[b + T_OM2] * (y[2] - ug) + p[b + T_MU] * force


@inline
def _rhs_wall(y, p, ug, vg, out):
    d = y[0] - ug - p[P_GAP]
    force = p[P_BETA] * power(d, p[P_CHI]) if d > 0.0 else 0.0
    a = TOWER_A
    out[0] = y[1]
    out[1] = -p[a + T_CX] * (y[1] - vg) - p[a + T_OM2] * (y[0] - ug) - p[a + T_MU] * force


@kernel
def _tower_energy(p, base, x, vx, yy, vy, th, vth):
    rho2 = p[base + T_RHO2]
    om2 = p[base + T_OM2]
    kinetic = 0.5 * (vx * vx + vy * vy + rho2 * vth * vth)
    structural = 0.5 * om2 * (
        x * x + yy * yy + 2.0 * p[base + T_EY] * x * th - 2.0 * p[base + T_EX] * yy * th
    ) + 0.5 * rho2 * p[base + T_OMT2] * th * th
    return (kinetic + structural) / p[base + T_MU]
