"""One tower's structural equations, energy and linearisation (docs/model.md sections 5, 7, 12).

Shared by the models that contain towers (:mod:`chaospound.physics.models`);
nothing here knows the contact law or the ground motion: the contact enters as
generalised forces, the ground as ``(u_g, u_g')`` (and ``(u_gy, u_gy')`` along y,
:func:`tower_accel_xy`).
"""

from chaospound.kernels.jit import inline, kernel
from chaospound.kernels.params import (
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
)


@inline
def tower_accel(p, base, x, vx, yy, vy, th, vth, ug, vg, qx, qy, qth, out, off):
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
def tower_accel_xy(p, base, x, vx, yy, vy, th, vth, ug, vg, ugy, vgy, qx, qy, qth, out, off):
    """:func:`tower_accel` under a bi-directional ground motion: ``(u_gy, u_gy')``
    along y too (docs/model.md section 5).

    Y relative to the ground replaces Y in the Y equation and in the torsion's
    stiffness coupling, and the y damping acts on ``Y' - u_gy'``. A separate
    function, not :func:`tower_accel` with zeros, so that a composition
    without a y component compiles exactly the x-only arithmetic.
    """
    om2 = p[base + T_OM2]
    mu = p[base + T_MU]
    ex = p[base + T_EX]
    ey = p[base + T_EY]
    xr = x - ug
    yr = yy - ugy
    out[off] = vx
    out[off + 1] = -p[base + T_CX] * (vx - vg) - om2 * (xr + ey * th) + mu * qx
    out[off + 2] = vy
    out[off + 3] = -p[base + T_CY] * (vy - vgy) - om2 * (yr - ex * th) + mu * qy
    out[off + 4] = vth
    out[off + 5] = (
        -p[base + T_CT] * vth
        - p[base + T_KTH] * (ey * xr - ex * yr)
        - p[base + T_OMT2] * th
        + p[base + T_MU_RHO2] * qth
    )


@kernel
def tower_energy(p, base, x, vx, yy, vy, th, vth):
    """Kinetic plus structural energy of one tower (units of A_g^2 k_Ax)."""
    rho2 = p[base + T_RHO2]
    om2 = p[base + T_OM2]
    kinetic = 0.5 * (vx * vx + vy * vy + rho2 * vth * vth)
    structural = 0.5 * om2 * (
        x * x + yy * yy + 2.0 * p[base + T_EY] * x * th - 2.0 * p[base + T_EX] * yy * th
    ) + 0.5 * rho2 * p[base + T_OMT2] * th * th
    return (kinetic + structural) / p[base + T_MU]


@kernel
def structural_jvp(p, base, v, out, off):
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
