"""Hertz contact, ``F = beta d^chi`` (Davis 1992; Chau & Wei 2001): the elastic law.

A contact law is one module with this interface (docs/extending.md); the
engine binds it into a composition once (:mod:`chaospound.engine.compose`) and
never asks which law it runs. The law's parameters are the block
``p[base:base + len(PARAMETERS)]`` of the packed vector.

Force per unit length ``f(d) = beta d+^chi``, with ``d`` the local penetration
(units of A_g) and ``beta`` the stiffness per unit length in units of
``k_Ax / A_g^(chi - 1)``. A point contact (the translational models) carries
``beta d^chi``; a line contact (the towers) integrates ``f`` over the rest
overlap through the moments of :mod:`.moments` (docs/model.md section 6).
"""

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.contact.moments import force_moments, moments
from chaospound.physics.powers import power

NAME = "hertz"
PARAMETERS = ("beta", "chi")  #: the law's block, in order
CONSERVATIVE = True  #: the force has a potential (energy tests apply)
DISSIPATIVE = False  #: the force depends on the penetration rate
MEMORY = ()  #: per-episode memory slots after PARAMETERS (none)
JUMPS = False  #: the force is continuous across onset and release
SWITCHES = 0  #: no extra event surface while in contact


def block(e: float = 1.0, *, beta: float, chi: float = 1.5) -> dict[str, float]:
    """Block values from the physical inputs (docs/contact_laws.md).

    Parameters
    ----------
    e : float
        Coefficient of restitution; must be 1 (an elastic law: hertzdamp,
        hunt-crossley and jankowski add damping to this force).
    beta : float
        Hertz stiffness per unit length, units of ``K_Ax A_g^(1 - chi)``, > 0.
    chi : float
        Hertz exponent, >= 1.

    Returns
    -------
    dict
        ``{"beta": beta, "chi": chi}``.
    """
    if e != 1.0:
        raise ValueError(f"the hertz law is elastic (e = 1); got e = {e}: use hertzdamp, "
                         "hunt-crossley or jankowski")
    if not beta > 0.0 or not chi >= 1.0:
        raise ValueError(f"beta = {beta}, chi = {chi}: need beta > 0 and chi >= 1")
    return {"beta": float(beta), "chi": float(chi)}


@kernel
def on_onset(p, base, rate):
    """No memory: nothing to write (the interface of the laws with memory)."""
    return


@inline
def point_force(p, base, d, rate):
    """Contact force of a point contact with penetration ``d`` (0 when d <= 0)."""
    return p[base] * power(d, p[base + 1]) if d > 0.0 else 0.0


@inline
def point_stiffness(p, base, d, rate):
    """``(dF/dd, dF/drate)`` of :func:`point_force`."""
    chi = p[base + 1]
    return (p[base] * chi * power(d, chi - 1.0) if d > 0.0 else 0.0), 0.0


@kernel
def point_force_rate(p, base, d, rate, accel=0.0):
    """``dF/dt = dF/dd d'`` of a point contact in contact (``d > 0``); ``accel`` unused."""
    beta = p[base]
    chi = p[base + 1]
    return beta * chi * power(d, chi - 1.0) * rate


@kernel
def point_potential(p, base, d):
    """``V = beta d+^(chi + 1) / (chi + 1)``."""
    if d <= 0.0:
        return 0.0
    beta = p[base]
    chi = p[base + 1]
    return beta * power(d, chi + 1.0) / (chi + 1.0)


@inline
def line_force(p, base, d_c, slope, rate_c, rate_slope, half_length):
    """Resultant force and first moment of a Hertz line contact.

    Parameters
    ----------
    p : ndarray
        Packed parameters; ``p[base]`` is beta, ``p[base + 1]`` is chi.
    base : int
        First slot of the law's block.
    d_c : float
        Penetration at the centre of the rest overlap (units of A_g).
    slope : float
        ``dd/dy`` along the contact line (radians, difference of rotations).
    rate_c, rate_slope : float
        Their time derivatives (unused by an elastic law).
    half_length : float
        Half the rest-overlap length L_ref / 2 (units of A_g).

    Returns
    -------
    (force, moment, d_lo, d_hi) : tuple of float
        ``force = (beta / L) int d+^chi dy`` (units of A_g k_Ax),
        ``moment = (beta / L) int d+^chi (y - y_c) dy``, and the end
        penetrations.
    """
    beta = p[base]
    chi = p[base + 1]
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, d_lo, d_hi
    m0, m1 = force_moments(chi, d_lo, d_hi)
    return beta * m0, beta * 2.0 * half_length * m1, d_lo, d_hi


@kernel
def line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length):
    """Derivatives of (force, moment) of :func:`line_force`.

    Returns
    -------
    (F_dc, F_sl, M_dc, M_sl, F_rc, F_rs, M_rc, M_rs) : tuple of float
        Derivatives of the force and moment with respect to the centre
        penetration ``d_c`` and the slope, then with respect to their rates
        (0: an elastic law has no rate terms).
    """
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    beta = p[base]
    chi = p[base + 1]
    n0, n1, n2 = moments(chi - 1.0, d_lo, d_hi)
    length = 2.0 * half_length
    scale = beta * chi
    return (scale * n0, scale * length * n1, scale * length * n1, scale * length * length * n2,
            0.0, 0.0, 0.0, 0.0)


@kernel
def line_force_rate(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length, accel_lo=0.0,
                    accel_hi=0.0):
    """``dF/dt`` of the resultant: ``F_c (r_lo + r_hi) / 2 + F_s (r_hi - r_lo) / L``.

    The accelerations (the interface of the dissipative laws) are unused.
    """
    fc, fs, _, _, _, _, _, _ = line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length)
    return fc * 0.5 * (rate_lo + rate_hi) + fs * (rate_hi - rate_lo) / (2.0 * half_length)


@kernel
def line_potential(p, base, d_lo, d_hi):
    """Contact potential ``V = beta / (L (chi + 1)) int d+^(chi+1) dy``."""
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0
    beta = p[base]
    chi = p[base + 1]
    m0, _, _ = moments(chi + 1.0, d_lo, d_hi)
    return beta * m0 / (chi + 1.0)
