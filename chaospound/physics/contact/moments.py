"""Moments of a power of the penetration along a line contact (docs/model.md section 6).

The penetration along the contact line is linear in y, ``d(y) = d_c + c_1 (y - y_c)``,
over the rest overlap ``[y_c - L/2, y_c + L/2]``. With ``s = (y - y_lo) / L`` in
[0, 1], every contact quantity is one of three moments of ``max(d, 0)^j``::

    M0 = int_0^1 d+^j ds
    M1 = int_0^1 d+^j (s - 1/2) ds
    M2 = int_0^1 d+^j (s - 1/2)^2 ds

with ``d(s) = d_lo + (d_hi - d_lo) s``. The potential uses ``j = chi + 1``, the
forces ``j = chi`` and the force Jacobian ``j = chi - 1``. Every contact law whose
force per unit length is a power of d times a polynomial in its rate reduces to them
(:mod:`chaospound.physics.contact`).

Three regimes keep the moments accurate to a few ulps:

* nearly parallel faces in full contact (``|eps| < EPS_SERIES`` with
  ``eps = (d_hi - d_lo) / (d_hi + d_lo)``): binomial series in eps about the mean
  penetration, no cancellation;
* one end penetrating (partial contact): integrals over the penetrated
  sub-interval, written as sums of non-negative terms;
* clearly skewed faces in full contact: the antiderivatives at the end values
  divided by powers of ``d_hi - d_lo``, which is then at least
  ``2 EPS_SERIES`` times the mean, so the cancellation is bounded (~50).

No expression of the form ``(b^k - a^k) / (b - a)`` is evaluated near ``b = a``.
The functions are exactly (bitwise) mirror-symmetric: swapping ``d_lo`` and
``d_hi`` leaves M0 and M2 unchanged and negates M1.
"""

import numpy as np

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.powers import power

EPS_SERIES = 0.2  #: |eps| below which the series is used (full contact)
SERIES_RTOL = 1e-17  #: relative size of the last series term kept
SERIES_MAX_TERMS = 80  #: hard cap on series terms (|eps| < 0.2 needs < 30)
_RECIP = 1.0 / np.arange(1.0, SERIES_MAX_TERMS + 5.0)
_RECIP = np.concatenate((np.array([np.inf]), _RECIP))  #: _RECIP[k] = 1 / k


@kernel
def moments(j, d_lo, d_hi):
    """Moments M0, M1, M2 of ``max(d, 0)^j`` along the contact line.

    Parameters
    ----------
    j : float
        Exponent, >= 0 (chi - 1, chi or chi + 1).
    d_lo, d_hi : float
        Penetrations at the two ends of the rest overlap (units of A_g);
        positive means overlap.

    Returns
    -------
    (M0, M1, M2) : tuple of float
        ``int_0^1 d+^j (s - 1/2)^k ds`` for k = 0, 1, 2.
    """
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, 0.0
    if d_lo <= 0.0 or d_hi <= 0.0:
        return _moments_partial(j, d_lo, d_hi)
    mean = 0.5 * (d_lo + d_hi)
    half_diff = 0.5 * (d_hi - d_lo)
    if abs(half_diff) < EPS_SERIES * mean:
        return _moments_series(j, mean, half_diff / mean)
    return _moments_skewed(j, d_lo, d_hi, mean)


@kernel
def _moments_series(j, mean, eps):
    """Binomial series about the mean penetration (full contact, |eps| small).

    ``(1/2) int_{-1}^{1} (1 + eps z)^j z^k dz`` expanded in powers of eps.
    """
    s0 = 0.0  # sum_n C(j, 2n) eps^2n / (2n + 1)
    s1 = 0.0  # sum_n C(j, 2n+1) eps^(2n+1) / (2n + 3)
    s2 = 0.0  # sum_n C(j, 2n) eps^2n / (2n + 3)
    coef = 1.0  # generalised binomial coefficient C(j, k)
    eps_k = 1.0  # eps^k
    for k in range(0, SERIES_MAX_TERMS, 2):
        even = coef * eps_k  # k even
        s0 += even * _RECIP[k + 1]
        s2 += even * _RECIP[k + 3]
        coef *= (j - k) * _RECIP[k + 1]
        eps_k *= eps
        odd = coef * eps_k  # k + 1
        s1 += odd * _RECIP[k + 3]
        coef *= (j - k - 1.0) * _RECIP[k + 2]
        eps_k *= eps
        if abs(even) + abs(odd) <= SERIES_RTOL * abs(s0):
            break
    scale = power(mean, j)
    return scale * s0, 0.5 * scale * s1, 0.25 * scale * s2


@kernel
def _moments_partial(j, d_lo, d_hi):
    """One end in contact: integrate over the penetrated sub-interval only.

    With ``p > 0`` the penetrating end and ``q <= 0`` the other, the contact covers
    a fraction ``f = p / (p - q)`` of the line on which d falls linearly from p
    to 0; every term below is a sum of non-negative numbers.
    """
    if d_hi > 0.0:
        p, q, sign = d_hi, d_lo, 1.0
    else:
        p, q, sign = d_lo, d_hi, -1.0
    m0, m1, frac = _partial_01(j, p, q, sign)
    m2 = m0 * (0.25 - frac / (j + 2.0) + 2.0 * frac * frac / ((j + 2.0) * (j + 3.0)))
    return m0, m1, m2


@inline
def _partial_01(j, p, q, sign):
    """M0, M1 and the contact fraction f for one end in contact (see above).

    ``M0 = f p^j / (j + 1)`` and ``M1 = sign M0 (j f + (j + 2) g) / (2 (j + 2))``
    with ``g = -q / (p - q) >= 0``: sums of non-negative terms, and no
    reciprocal of the span (it overflows when both ends are subnormal). The
    right-hand side of every contact step runs this.
    """
    span = p - q
    frac = p / span
    rest = -q / span
    inv_12 = 1.0 / ((j + 1.0) * (j + 2.0))
    m0 = frac * power(p, j) * ((j + 2.0) * inv_12)
    m1 = sign * m0 * (j * frac + (j + 2.0) * rest) * (0.5 * (j + 1.0) * inv_12)
    return m0, m1, frac


@inline
def force_moments(j, d_lo, d_hi):
    """M0 and M1 of ``max(d, 0)^j`` (what the forces need), see :func:`moments`.

    The partial-contact case, the one of corner impacts, is written out here
    so that it inlines into the right-hand side; full contact calls
    :func:`moments`.
    """
    if d_hi > 0.0 and d_lo <= 0.0:
        m0, m1, _ = _partial_01(j, d_hi, d_lo, 1.0)
        return m0, m1
    if d_lo > 0.0 and d_hi <= 0.0:
        m0, m1, _ = _partial_01(j, d_lo, d_hi, -1.0)
        return m0, m1
    m0, m1, _ = moments(j, d_lo, d_hi)
    return m0, m1


@kernel
def _moments_skewed(j, d_lo, d_hi, mean):
    """Full contact, clearly non-parallel faces: antiderivatives at the ends.

    ``|d_hi - d_lo| >= 2 EPS_SERIES mean`` here, which bounds the cancellation.
    """
    delta = d_hi - d_lo
    hi1 = power(d_hi, j + 1.0)
    lo1 = power(d_lo, j + 1.0)
    hi2 = hi1 * d_hi
    lo2 = lo1 * d_lo
    diff1 = (hi1 - lo1) / (j + 1.0)
    diff2 = (hi2 - lo2) / (j + 2.0)
    diff3 = (hi2 * d_hi - lo2 * d_lo) / (j + 3.0)
    m0 = diff1 / delta
    m1 = (diff2 - mean * diff1) / (delta * delta)
    m2 = (diff3 - 2.0 * mean * diff2 + mean * mean * diff1) / (delta * delta * delta)
    return m0, m1, m2
