"""Shared pieces of the dissipative contact laws (issue 15, docs/contact_laws.md).

* :func:`moment3`: the third moment ``M3 = int_0^1 d+^j (s - 1/2)^3 ds`` in the
  three regimes of :mod:`.moments` (the Jacobian of a rate term needs it);
* :func:`rate_moments`: ``int d+^j r (s - 1/2)^k ds`` for k = 0, 1, 2, 3 with the
  penetration ``d`` and its rate ``r`` both linear along the line
  (docs/design/engine.md 4.2): ``r_m M_k + dr M_(k+1)`` with ``r_m`` the mean
  rate and ``dr = r_hi - r_lo``;
* :func:`approach_rate_moments`: the same restricted to the part of the line
  where ``r > 0`` (Jankowski's approach phase), by splitting the line at
  ``r(s) = 0`` and rescaling each piece's moments;
* :func:`effective_mass`, :func:`onset_velocity`: the definitions of m_eff and
  v0 shared by every law (Python, used by the laws' ``block``).

Units: the dimensionless model (docs/model.md section 2): penetrations in A_g,
rates in A_g omega_Ax, masses in m_A (tower A's mass is 1; a force F gives
tower i the acceleration mu_i F, so its mass is 1 / mu_i).
"""

from __future__ import annotations

import math

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.contact.moments import EPS_SERIES, SERIES_MAX_TERMS, SERIES_RTOL, moments
from chaospound.physics.powers import power

V0_FLOOR = 1e-6  #: default floor of the onset velocity v0 (units of A_g omega_Ax)
#: tangent vectors whose memory sensitivity a law with memory keeps (its block's slots):
#: the largest state dimension of a model that carries them (towers, 12)
MAX_TANGENT_VECTORS = 12


# ------------------------------------------------------------------ moments


@kernel
def moment3(j, d_lo, d_hi):
    """Third moment ``int_0^1 d+^j (s - 1/2)^3 ds`` of the penetration along the line.

    Parameters
    ----------
    j : float
        Exponent, > -1.
    d_lo, d_hi : float
        End penetrations (units of A_g).

    Returns
    -------
    float
        M3, in units of A_g^j; odd under swapping the ends (bitwise).
    """
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0
    if d_lo <= 0.0 or d_hi <= 0.0:
        if d_hi > 0.0:
            p, q, sign = d_hi, d_lo, 1.0
        else:
            p, q, sign = d_lo, d_hi, -1.0
        span = p - q
        f = p / span
        # f p^j int_0^1 (1 - w)^j (1/2 - f w)^3 dw, Beta integrals of (1 - w)^j w^n
        b0 = 1.0 / (j + 1.0)
        b1 = b0 / (j + 2.0)
        b2 = 2.0 * b1 / (j + 3.0)
        b3 = 3.0 * b2 / (j + 4.0)
        inner = 0.125 * b0 - 0.75 * f * b1 + 1.5 * f * f * b2 - f * f * f * b3
        return sign * f * power(p, j) * inner
    mean = 0.5 * (d_lo + d_hi)
    half_diff = 0.5 * (d_hi - d_lo)
    if abs(half_diff) < EPS_SERIES * mean:
        eps = half_diff / mean
        s3 = 0.0  # sum over odd n of C(j, n) eps^n / (n + 4)
        s0 = 0.0
        coef = 1.0
        eps_k = 1.0
        for k in range(0, SERIES_MAX_TERMS, 2):
            even = coef * eps_k
            s0 += even / (k + 1.0)
            coef *= (j - k) / (k + 1.0)
            eps_k *= eps
            odd = coef * eps_k
            s3 += odd / (k + 5.0)
            coef *= (j - k - 1.0) / (k + 2.0)
            eps_k *= eps
            if abs(even) + abs(odd) <= SERIES_RTOL * abs(s0):
                break
        return 0.125 * power(mean, j) * s3
    delta = d_hi - d_lo
    hi1 = power(d_hi, j + 1.0)
    lo1 = power(d_lo, j + 1.0)
    diff1 = (hi1 - lo1) / (j + 1.0)
    diff2 = (hi1 * d_hi - lo1 * d_lo) / (j + 2.0)
    diff3 = (hi1 * d_hi * d_hi - lo1 * d_lo * d_lo) / (j + 3.0)
    diff4 = (hi1 * d_hi * d_hi * d_hi - lo1 * d_lo * d_lo * d_lo) / (j + 4.0)
    num = diff4 - 3.0 * mean * diff3 + 3.0 * mean * mean * diff2 - mean * mean * mean * diff1
    return num / (delta * delta * delta * delta)


@inline
def rate_moments(j, d_lo, d_hi, r_lo, r_hi):
    """``(I0, I1) = int_0^1 d+^j r (s - 1/2)^k ds`` for k = 0, 1.

    ``r(s) = r_lo + (r_hi - r_lo) s``, so ``I_k = r_m M_k + dr M_(k+1)``
    (docs/design/engine.md 4.2). Units: A_g^j times the rate's.
    """
    m0, m1, m2 = moments(j, d_lo, d_hi)
    r_m = 0.5 * (r_lo + r_hi)
    dr = r_hi - r_lo
    return r_m * m0 + dr * m1, r_m * m1 + dr * m2


@kernel
def rate_moments_2(j, d_lo, d_hi, r_lo, r_hi):
    """``(I0, I1, I2)``: as :func:`rate_moments` with also ``I2 = r_m M2 + dr M3``."""
    m0, m1, m2 = moments(j, d_lo, d_hi)
    m3 = moment3(j, d_lo, d_hi)
    r_m = 0.5 * (r_lo + r_hi)
    dr = r_hi - r_lo
    return r_m * m0 + dr * m1, r_m * m1 + dr * m2, r_m * m2 + dr * m3


@kernel
def _piece(j, d_lo, d_hi, r_lo, r_hi, s_a, s_b):
    """Moments over the piece ``[s_a, s_b]`` of the line.

    Returns ``int_piece d+^j (s - 1/2)^k ds`` (k = 0, 1, 2) and the same with
    the factor r. On the piece, ``s = s_a + l u`` and ``s - 1/2 = c + l (u - 1/2)``
    with ``c`` the piece's centre offset; d and r are again linear in u, so the
    piece's moments are the rescaled, re-centred moments of its end values.
    """
    length = s_b - s_a
    d_a = d_lo + (d_hi - d_lo) * s_a
    d_b = d_lo + (d_hi - d_lo) * s_b
    if length <= 0.0 or (d_a <= 0.0 and d_b <= 0.0):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    c = 0.5 * (s_a + s_b) - 0.5
    p0, p1, p2 = moments(j, d_a, d_b)
    p3 = moment3(j, d_a, d_b)
    q0 = length * p0
    q1 = length * (c * p0 + length * p1)
    q2 = length * (c * c * p0 + 2.0 * c * length * p1 + length * length * p2)
    q3 = length * (c * c * c * p0 + 3.0 * c * c * length * p1 + 3.0 * c * length * length * p2
                   + length * length * length * p3)
    r_a = r_lo + (r_hi - r_lo) * s_a
    r_b = r_lo + (r_hi - r_lo) * s_b
    # on the piece r = r_mid + (r_b - r_a) (u - 1/2) = r_mid + slope ((s - 1/2) - c)
    slope = (r_b - r_a) / length
    r_mid = 0.5 * (r_a + r_b) - slope * c
    return (q0, q1, q2, r_mid * q0 + slope * q1, r_mid * q1 + slope * q2,
            r_mid * q2 + slope * q3)


@kernel
def approach_rate_moments(j, d_lo, d_hi, r_lo, r_hi):
    """Moments over the approaching part of the line (``r > 0``).

    Returns
    -------
    (A0, A1, A2, I0, I1, I2) : tuple of float
        ``A_k = int_{r>0} d+^j (s - 1/2)^k ds`` and
        ``I_k = int_{r>0} d+^j r (s - 1/2)^k ds``.
    """
    if r_lo <= 0.0 and r_hi <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if r_lo > 0.0 and r_hi > 0.0:
        m0, m1, m2 = moments(j, d_lo, d_hi)
        m3 = moment3(j, d_lo, d_hi)
        r_m = 0.5 * (r_lo + r_hi)
        dr = r_hi - r_lo
        return m0, m1, m2, r_m * m0 + dr * m1, r_m * m1 + dr * m2, r_m * m2 + dr * m3
    s_star = r_lo / (r_lo - r_hi)
    if r_hi > 0.0:
        return _piece(j, d_lo, d_hi, r_lo, r_hi, s_star, 1.0)
    return _piece(j, d_lo, d_hi, r_lo, r_hi, 0.0, s_star)


@inline
def approach_rate_force(j, d_lo, d_hi, r_lo, r_hi):
    """``(I0, I1)`` of :func:`approach_rate_moments` without the third moment
    (what the force needs: ``I1`` uses M2 at most)."""
    if r_lo > 0.0 and r_hi > 0.0:
        return rate_moments(j, d_lo, d_hi, r_lo, r_hi)
    if r_hi > 0.0:
        s_a = r_lo / (r_lo - r_hi)
        s_b = 1.0
    else:
        s_a = 0.0
        s_b = r_lo / (r_lo - r_hi)
    length = s_b - s_a
    d_a = d_lo + (d_hi - d_lo) * s_a
    d_b = d_lo + (d_hi - d_lo) * s_b
    if length <= 0.0 or (d_a <= 0.0 and d_b <= 0.0):
        return 0.0, 0.0
    c = 0.5 * (s_a + s_b) - 0.5
    p0, p1, p2 = moments(j, d_a, d_b)
    q0 = length * p0
    q1 = length * (c * p0 + length * p1)
    q2 = length * (c * c * p0 + 2.0 * c * length * p1 + length * length * p2)
    r_a = r_lo + (r_hi - r_lo) * s_a
    r_b = r_lo + (r_hi - r_lo) * s_b
    slope = (r_b - r_a) / length
    r_mid = 0.5 * (r_a + r_b) - slope * c
    return r_mid * q0 + slope * q1, r_mid * q1 + slope * q2


# ------------------------------------------------------- physical definitions


def effective_mass(mu_a: float, mu_b: float | None = None) -> float:
    """Effective mass of the pounding pair, in units of m_A.

    Parameters
    ----------
    mu_a, mu_b : float
        Force factors of the two towers (docs/model.md section 4: a force F
        gives tower i the acceleration mu_i F, so its mass is 1 / mu_i; mu_A = 1,
        mu_B = m_A / m_B). ``mu_b = None``: tower A against a rigid wall.

    Returns
    -------
    float
        ``m_eff = 1 / (mu_A + mu_B)`` (``1 / mu_A`` against a wall): the mass of
        the relative translation ``d'' = -(mu_A + mu_B) F``. For a rotating tower
        this is the translational (centre-of-mass) value, not the local mass at
        the contact corner (docs/contact_laws.md, "m_eff").
    """
    if mu_a <= 0.0 or (mu_b is not None and mu_b <= 0.0):
        raise ValueError(f"force factors must be > 0, got mu_a={mu_a}, mu_b={mu_b}")
    return 1.0 / (mu_a + (mu_b if mu_b is not None else 0.0))


def onset_velocity(rate: float, floor: float = V0_FLOOR) -> float:
    """The v0 rule: ``max(rate, floor)`` with ``rate`` the closing velocity at onset.

    Parameters
    ----------
    rate : float
        Closing velocity (units of A_g omega_Ax) at the end that first touches.
    floor : float
        Lower bound (units of A_g omega_Ax), > 0.
    """
    if not floor > 0.0:
        raise ValueError(f"v0_floor must be > 0, got {floor}")
    return max(rate, floor)


def restitution_log(e: float) -> float:
    """``-ln e / sqrt(pi^2 + ln^2 e)``, the damping ratio of a linear oscillator whose
    half-cycle ends with the speed ratio e (Anagnostopoulos 1988)."""
    check_restitution(e)
    le = abs(math.log(e))  # +0.0 at e = 1 (not -0.0: zero damping is bitwise the parent)
    return le / math.sqrt(math.pi**2 + le * le)


def check_restitution(e: float) -> None:
    """Raise ValueError unless 0 < e <= 1."""
    if not 0.0 < e <= 1.0:
        raise ValueError(f"coefficient of restitution e = {e}: need 0 < e <= 1")
