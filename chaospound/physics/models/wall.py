"""Davis (1992): tower A's translation X_A against a rigid ground-borne wall (2 states).

docs/model.md section 9. State ``(X_A, X_A')``, a point contact ``d = X_A - u_g - a``.
A template, as :mod:`chaospound.physics.models.towers`.
"""

from chaospound.kernels.free import (
    GROUND,
    LAW,
    LAW_DISSIPATIVE,
    LAW_SHIFTED,
    ground_acceleration,
    ground_at,
    law_point_force,
    law_point_force_rate,
    law_point_memory_force,
    law_point_potential,
    law_point_shift,
    law_point_stiffness,
)
from chaospound.kernels.jit import inline, kernel
from chaospound.kernels.params import P_GAP, T_CX, T_MU, T_OM2, TOWER_A
from chaospound.physics.corners import CORNER_FACE
from chaospound.physics.towers import tower_energy

# ==== template ====
N_BASE = 2
N_ENDS = 1


@inline
def model_rhs(t, y, p, ug, vg, out):
    """Time derivative of the state, into ``out``."""
    d = y[0] - ug - p[P_GAP]
    force = law_point_force(p, LAW, d, y[1] - vg)
    a = TOWER_A
    out[0] = y[1]
    out[1] = -p[a + T_CX] * (y[1] - vg) - p[a + T_OM2] * (y[0] - ug) - p[a + T_MU] * force


@inline
def model_rate(t, y, p, y_at):
    """Closing velocity against the moving wall, ``X_A' - u_g'``."""
    _, vg = ground_at(t, p, GROUND)
    return y[1] - vg


@inline
def model_ends(t, y, p, out):
    """Both ends carry the single penetration d and its rate."""
    ug, vg = ground_at(t, p, GROUND)
    d = y[0] - ug - p[P_GAP]
    rate = y[1] - vg
    out[0] = d
    out[1] = d
    out[2] = rate
    out[3] = rate


@kernel
def model_forces(t, y, p, q_out):
    """Generalised contact force (X_A, 0, ...); returns the force on A."""
    ug, vg = ground_at(t, p, GROUND)
    for i in range(6):
        q_out[i] = 0.0
    d = y[0] - ug - p[P_GAP]
    force = law_point_force(p, LAW, d, y[1] - vg)
    q_out[0] = -force
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
    ug, _ = ground_at(t, p, GROUND)
    return law_point_potential(p, LAW, y[0] - ug - p[P_GAP])


@kernel
def model_energy(y, p):
    """Structural, kinetic and contact energy (docs/model.md section 7)."""
    e = tower_energy(p, TOWER_A, y[0], y[1], 0.0, 0.0, 0.0, 0.0)
    return e + model_potential(0.0, y, p)


@kernel
def model_trace(p):
    """Constant trace of the Jacobian."""
    return -p[TOWER_A + T_CX]


@kernel
def model_linearize(t, y, p):
    """The contact stiffness dF/dd, damping dF/dd' and tangent shift (and 6 unused zeros).

    The shift s (units of K_Ax / omega_Ax) is nonzero only in the approach phase of a
    law whose point tangent is shifted (``LAW_SHIFTED``: Jankowski's, docs/contact_laws.md
    section 7).
    """
    ug, vg = ground_at(t, p, GROUND)
    d = y[0] - ug - p[P_GAP]
    stiffness, damping = law_point_stiffness(p, LAW, d, y[1] - vg)
    shift = 0.0
    if LAW_SHIFTED:
        shift = law_point_shift(p, LAW, d)
    return stiffness, damping, shift, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@kernel
def model_jvp(p, lin, v, out):
    """``out = J v`` with the coefficients ``lin`` of :func:`model_linearize`.

    With a shift ``s = lin[2]`` (``LAW_SHIFTED`` only): ``J (v + s e_F (grad(d) . v))``,
    ``e_F = (0, -mu_A)``, ``grad(d) = (1, 0)``: the shifted tangent vectors' equations.
    """
    a = TOWER_A
    rate = v[1]
    if LAW_SHIFTED:
        rate -= p[a + T_MU] * lin[2] * v[0]
    out[0] = rate
    out[1] = -(p[a + T_OM2] + p[a + T_MU] * lin[0]) * v[0] - p[a + T_CX] * rate
    if LAW_DISSIPATIVE:
        out[1] -= p[a + T_MU] * lin[1] * rate


@kernel
def model_contact_point(t, state, p, ends):
    """``(face, 0, closing velocity)``: a point contact has no corners."""
    return CORNER_FACE, 0.0, ends[2]


# ---- a law's per-episode memory in the tangent dynamics (docs/contact_laws.md 7)


@kernel
def model_memory_linearize(t, y, p):
    """``(dF/dxi,)``: the contact force's derivative with respect to the law's memory."""
    ug, vg = ground_at(t, p, GROUND)
    return (law_point_memory_force(p, LAW, y[0] - ug - p[P_GAP], y[1] - vg),)


@kernel
def model_memory_jvp(p, mem, dxi, out):
    """``out += (df/dxi) dxi``."""
    out[1] -= p[TOWER_A + T_MU] * mem[0] * dxi


@kernel
def model_onset_variation(t, y, p, v, y_at):
    """``(dd, dV)`` of the penetration and the closing velocity along ``v`` (fixed t)."""
    return v[0], v[1]


@kernel
def model_onset_accel(t, y, p, f, y_at):
    """Closing acceleration ``X_A'' - u_g''`` along the flow ``f``."""
    return f[1] - ground_acceleration(t, p, GROUND)
