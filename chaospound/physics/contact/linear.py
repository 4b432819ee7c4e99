"""Linear elastic contact, ``F = k d`` (Maison & Kasai 1990).

The elastic parent of :mod:`.kelvin_voigt`. Force per unit length
``f(d) = k d+`` with ``d`` the local penetration (units of A_g) and ``k`` the
contact stiffness per unit length in units of ``K_Ax`` (a point contact carries
``k d``, units of A_g K_Ax). The line resultants are the moments of
:mod:`.moments` with ``j = 1`` (force), ``j = 0`` (Jacobian) and ``j = 2``
(potential). The interface is that of :mod:`.hertz` (docs/contact_laws.md).
"""

from __future__ import annotations

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.contact.moments import force_moments, moments

NAME = "linear"
PARAMETERS = ("k",)  #: the law's block, in order
MEMORY = ()  #: no per-episode memory
CONSERVATIVE = True  #: the force has a potential
DISSIPATIVE = False  #: the force does not depend on the penetration rate
JUMPS = False  #: the force is continuous across onset and release
SWITCHES = 0  #: no extra event surface while in contact


def block(e: float = 1.0, *, k: float) -> dict[str, float]:
    """Block values from the physical inputs.

    Parameters
    ----------
    e : float
        Coefficient of restitution; must be 1 (an elastic law).
    k : float
        Contact stiffness, units of K_Ax (dimensionless model), > 0.

    Returns
    -------
    dict
        ``{"k": k}``.
    """
    if e != 1.0:
        raise ValueError(f"the linear law is elastic (e = 1); got e = {e}: use kelvin-voigt")
    if not k > 0.0:
        raise ValueError(f"k = {k}: need > 0")
    return {"k": float(k)}


@inline
def point_force(p, base, d, rate):
    """Contact force ``k d`` of a point contact (0 when d <= 0), units of A_g K_Ax."""
    return p[base] * d if d > 0.0 else 0.0


@inline
def point_stiffness(p, base, d, rate):
    """``(dF/dd, dF/drate)`` of :func:`point_force`."""
    return (p[base] if d > 0.0 else 0.0), 0.0


@kernel
def point_force_rate(p, base, d, rate, accel=0.0):
    """``dF/dt = k d'`` in contact (``d > 0``); ``accel`` is unused."""
    return p[base] * rate


@kernel
def point_potential(p, base, d):
    """``V = k d+^2 / 2`` (units of A_g^2 K_Ax)."""
    if d <= 0.0:
        return 0.0
    return 0.5 * p[base] * d * d


@kernel
def on_onset(p, base, rate):
    """No memory: nothing to write."""
    return


@inline
def line_force(p, base, d_c, slope, rate_c, rate_slope, half_length):
    """Resultant force and first moment of a linear line contact.

    Parameters as :func:`chaospound.physics.contact.hertz.line_force`.

    Returns
    -------
    (force, moment, d_lo, d_hi) : tuple of float
        ``force = (k / L) int d+ dy`` (units of A_g K_Ax),
        ``moment = (k / L) int d+ (y - y_c) dy`` (units of A_g^2 K_Ax) and the
        end penetrations.
    """
    k = p[base]
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, d_lo, d_hi
    m0, m1 = force_moments(1.0, d_lo, d_hi)
    return k * m0, k * 2.0 * half_length * m1, d_lo, d_hi


@kernel
def line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length):
    """Derivatives of (force, moment) of :func:`line_force`.

    Returns
    -------
    tuple of 8 float
        ``(F_dc, F_sl, M_dc, M_sl, F_rc, F_rs, M_rc, M_rs)``: with respect to the
        centre penetration, the slope, the centre rate and the rate's slope (the
        last four are 0 for an elastic law).
    """
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    k = p[base]
    n0, n1, n2 = moments(0.0, d_lo, d_hi)
    length = 2.0 * half_length
    return k * n0, k * length * n1, k * length * n1, k * length * length * n2, 0.0, 0.0, 0.0, 0.0


@kernel
def line_force_rate(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length, accel_lo=0.0,
                    accel_hi=0.0):
    """``dF/dt`` of the resultant: ``F_c r_m + F_s dr / L`` (accelerations unused)."""
    fc, fs, _, _, _, _, _, _ = line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length)
    return fc * 0.5 * (rate_lo + rate_hi) + fs * (rate_hi - rate_lo) / (2.0 * half_length)


@kernel
def line_potential(p, base, d_lo, d_hi):
    """Contact potential ``V = k / (2 L) int d+^2 dy`` (units of A_g^2 K_Ax)."""
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0
    m0, _, _ = moments(2.0, d_lo, d_hi)
    return 0.5 * p[base] * m0
