"""Chau & Wei (2001): the two towers' translations X_A, X_B only (4 states).

docs/model.md section 9: the exact reduction of the towers model when both
towers are symmetric and the motion stays translational. State ``(X_A, X_A',
X_B, X_B')``, a point contact ``d = X_A - X_B - a``. A template, as
:mod:`chaospound.physics.models.towers`.
"""

from chaospound.kernels.free import (
    LAW,
    LAW_DISSIPATIVE,
    LAW_SHIFTED,
    law_point_force,
    law_point_force_rate,
    law_point_memory_force,
    law_point_potential,
    law_point_shift,
    law_point_stiffness,
)
from chaospound.kernels.jit import inline, kernel
from chaospound.kernels.params import P_GAP, T_CX, T_MU, T_OM2, TOWER_A, TOWER_B
from chaospound.physics.corners import CORNER_FACE
from chaospound.physics.towers import tower_energy

# ==== template ====
N_BASE = 4
N_ENDS = 1


@inline
def model_rhs(t, y, p, ug, vg, out):
    """Time derivative of the state, into ``out``."""
    d = y[0] - y[2] - p[P_GAP]
    force = law_point_force(p, LAW, d, y[1] - y[3])
    a = TOWER_A
    b = TOWER_B
    out[0] = y[1]
    out[1] = -p[a + T_CX] * (y[1] - vg) - p[a + T_OM2] * (y[0] - ug) - p[a + T_MU] * force
    out[2] = y[3]
    out[3] = -p[b + T_CX] * (y[3] - vg) - p[b + T_OM2] * (y[2] - ug) + p[b + T_MU] * force


@inline
def model_rate(t, y, p, y_at):
    """Closing velocity ``X_A' - X_B'``."""
    return y[1] - y[3]


@inline
def model_ends(t, y, p, out):
    """Both ends carry the single penetration d and its rate."""
    d = y[0] - y[2] - p[P_GAP]
    rate = y[1] - y[3]
    out[0] = d
    out[1] = d
    out[2] = rate
    out[3] = rate


@kernel
def model_forces(t, y, p, q_out):
    """Generalised contact forces (X_A, 0, 0, X_B, 0, 0); returns the force on A."""
    for i in range(6):
        q_out[i] = 0.0
    d = y[0] - y[2] - p[P_GAP]
    force = law_point_force(p, LAW, d, y[1] - y[3])
    q_out[0] = -force
    q_out[3] = force
    return -q_out[0]


@kernel
def model_force_rate(t, y, p, ends):
    """Time derivative of the contact force; ``ends`` from :func:`model_ends`."""
    if ends[0] <= 0.0 and ends[1] <= 0.0:
        return 0.0
    return law_point_force_rate(p, LAW, ends[0], ends[2])


@kernel
def model_potential(t, y, p):
    """Contact potential V_c, units of A_g^2 k_Ax."""
    return law_point_potential(p, LAW, y[0] - y[2] - p[P_GAP])


@kernel
def model_energy(y, p):
    """Structural, kinetic and contact energy (docs/model.md section 7)."""
    e = tower_energy(p, TOWER_A, y[0], y[1], 0.0, 0.0, 0.0, 0.0)
    e += tower_energy(p, TOWER_B, y[2], y[3], 0.0, 0.0, 0.0, 0.0)
    return e + model_potential(0.0, y, p)


@kernel
def model_trace(p):
    """Constant trace of the Jacobian."""
    tr = -p[TOWER_A + T_CX]
    tr -= p[TOWER_B + T_CX]
    return tr


@kernel
def model_linearize(t, y, p):
    """The contact stiffness dF/dd, damping dF/dd' and tangent shift (and 6 unused zeros).

    The shift s (units of K_Ax / omega_Ax) is nonzero only in the approach phase of a
    law whose point tangent is shifted (``LAW_SHIFTED``: Jankowski's, docs/contact_laws.md
    section 7).
    """
    d = y[0] - y[2] - p[P_GAP]
    stiffness, damping = law_point_stiffness(p, LAW, d, y[1] - y[3])
    shift = 0.0
    if LAW_SHIFTED:
        shift = law_point_shift(p, LAW, d)
    return stiffness, damping, shift, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@kernel
def model_jvp(p, lin, v, out):
    """``out = J v`` with the coefficients ``lin`` of :func:`model_linearize`.

    With a shift ``s = lin[2]`` (``LAW_SHIFTED`` only): ``J (v + s e_F (grad(d) . v))``,
    ``e_F = (0, -mu_A, 0, mu_B)``, ``grad(d) = (1, 0, -1, 0)``: the shifted tangent
    vectors' equations.
    """
    stiffness = lin[0]
    a = TOWER_A
    b = TOWER_B
    rate_a = v[1]
    rate_b = v[3]
    if LAW_SHIFTED:
        gap = lin[2] * (v[0] - v[2])
        rate_a -= p[a + T_MU] * gap
        rate_b += p[b + T_MU] * gap
    squeeze = stiffness * (v[0] - v[2])
    if LAW_DISSIPATIVE:
        squeeze += lin[1] * (rate_a - rate_b)
    out[0] = rate_a
    out[1] = -p[a + T_OM2] * v[0] - p[a + T_CX] * rate_a - p[a + T_MU] * squeeze
    out[2] = rate_b
    out[3] = -p[b + T_OM2] * v[2] - p[b + T_CX] * rate_b + p[b + T_MU] * squeeze


@kernel
def model_contact_point(t, state, p, ends):
    """``(face, 0, closing velocity)``: a point contact has no corners."""
    return CORNER_FACE, 0.0, ends[2]


# ---- a law's per-episode memory in the tangent dynamics (docs/contact_laws.md 7)


@kernel
def model_memory_linearize(t, y, p):
    """``(dF/dxi,)``: the contact force's derivative with respect to the law's memory."""
    return (law_point_memory_force(p, LAW, y[0] - y[2] - p[P_GAP], y[1] - y[3]),)


@kernel
def model_memory_jvp(p, mem, dxi, out):
    """``out += (df/dxi) dxi``."""
    out[1] -= p[TOWER_A + T_MU] * mem[0] * dxi
    out[3] += p[TOWER_B + T_MU] * mem[0] * dxi


@kernel
def model_onset_variation(t, y, p, v, y_at):
    """``(dd, dV)`` of the penetration and the closing velocity along ``v``."""
    return v[0] - v[2], v[1] - v[3]


@kernel
def model_onset_accel(t, y, p, f, y_at):
    """Closing acceleration ``X_A'' - X_B''`` along the flow ``f``."""
    return f[1] - f[3]
