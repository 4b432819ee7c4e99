"""Hertz line contact: closed forms against high-precision quadrature and gradients."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kernels_by_name import (
    EPS_SERIES,
    contact_forces,
    contact_potential,
    line_contact,
    line_potential,
    moments,
)

from chaospound.kernels.params import TOWERS
from chaospound.scene import load_preset

RATIOS = [1.0, 0.999999, 0.9, 0.7, 0.5, 0.3, 0.1, 1e-3, 1e-6, 1e-9, 1e-12]


def moments_reference(j: float, d_lo: float, d_hi: float, dps: int = 40) -> np.ndarray:
    """High-precision moments M0, M1, M2 by mpmath quadrature."""
    import mpmath

    with mpmath.workdps(dps):
        lo = mpmath.mpf(d_lo)
        hi = mpmath.mpf(d_hi)

        def pen(s):
            d = lo + (hi - lo) * s
            return d**j if d > 0 else mpmath.mpf(0)

        points = [0, 1]
        if (lo > 0) != (hi > 0):
            points = [0, lo / (lo - hi), 1]
        res = [
            mpmath.quad(lambda s, k=k: pen(s) * (s - mpmath.mpf(1) / 2) ** k, points)
            for k in range(3)
        ]
        return np.array([float(v) for v in res])


def _check(j, d_lo, d_hi, rtol0=2e-15, rtol12=5e-14):
    got = np.array(moments(j, d_lo, d_hi))
    ref = moments_reference(j, d_lo, d_hi)
    assert abs(got[0] - ref[0]) <= rtol0 * abs(ref[0]) + 1e-300
    # M1 vanishes for parallel faces: measure it against the scale of M0 as well
    assert abs(got[1] - ref[1]) <= rtol12 * (abs(ref[1]) + 1e-3 * abs(ref[0]) * 1e-12) + 1e-300
    assert abs(got[2] - ref[2]) <= rtol12 * abs(ref[2]) + 1e-300


@pytest.mark.parametrize("chi", [1.0, 1.5, 2.0, 3.0])
@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_moments_match_mpmath(chi, ratio, sign):
    """d_lo / d_hi from 1e-12 to 1, both signs, exponents chi - 1, chi, chi + 1."""
    for j in (chi - 1.0, chi, chi + 1.0):
        d_hi = 0.37
        d_lo = sign * ratio * d_hi
        _check(j, d_lo, d_hi)
        _check(j, d_hi, d_lo)  # the other end penetrating


@pytest.mark.parametrize("j", [0.5, 1.5, 2.5])
def test_moments_continuous_at_series_threshold(j):
    """Series and closed form agree where the algorithm switches between them."""
    mean = 0.8
    for eps in (EPS_SERIES * (1 - 1e-12), EPS_SERIES * (1 + 1e-12)):
        d_lo, d_hi = mean * (1 - eps), mean * (1 + eps)
        _check(j, d_lo, d_hi)


def test_moments_mirror_symmetric_bitwise():
    rng = np.random.default_rng(1)
    for _ in range(200):
        j = rng.choice([0.0, 0.5, 1.5, 2.5])
        a, b = rng.normal(size=2) * 10.0 ** rng.uniform(-6, 0, size=2)
        m_ab = moments(j, a, b)
        m_ba = moments(j, b, a)
        assert m_ab[0] == m_ba[0] and m_ab[2] == m_ba[2] and m_ab[1] == -m_ba[1]


@pytest.mark.parametrize("chi", [1.0, 1.5, 3.0])
def test_uniform_penetration_is_hertz(chi):
    """Uniform penetration over the overlap gives F = beta d^chi (Chau & Wei 2001)."""
    for d in (1e-9, 1e-3, 0.25, 2.0):
        force, moment, _, _ = line_contact(d, 0.0, 50.0, 1000.0, chi)
        assert force == pytest.approx(1000.0 * d**chi, rel=1e-15)
        assert moment == 0.0
        assert line_potential(d, d, 1000.0, chi) == pytest.approx(
            1000.0 * d ** (chi + 1) / (chi + 1), rel=1e-15
        )


def test_no_force_without_overlap():
    force, moment, _, _ = line_contact(-1e-3, 1e-6, 50.0, 1000.0, 1.5)
    assert force == 0.0 and moment == 0.0


# ------------------------------------------------------------------ gradient
_SCENE = load_preset("fig3a").with_params(
    ecc_x_A=-3.0, ecc_y_B=-5.0, offset_y=7.0, length_B=90.0, width_B=40.0
)
_P = _SCENE.pack(TOWERS)
_POS = (0, 2, 4, 6, 8, 10)  # X_A, Y_A, th_A, X_B, Y_B, th_B


def _potential(y):
    return contact_potential(TOWERS, 0.3, y, _P)


@settings(max_examples=150, deadline=None)
@given(
    pen=st.floats(-0.02, 0.6),
    th_a=st.floats(-3e-3, 3e-3),
    tilt=st.one_of(st.just(0.0), st.floats(-1e-9, 1e-9), st.floats(-4e-3, 4e-3)),
    y_a=st.floats(-0.5, 0.5),
    y_b=st.floats(-0.5, 0.5),
    x_b=st.floats(-1.0, 1.0),
)
def test_forces_are_minus_gradient_of_potential(pen, th_a, tilt, y_a, y_b, x_b):
    """Q = -dV/dq by central differences, incl. parallel faces and grazing ends."""
    y = np.zeros(12)
    y[2], y[4], y[6], y[8], y[10] = y_a, th_a, x_b, y_b, th_a + tilt
    # place X_A so that the centre penetration is `pen`
    probe = y.copy()
    ends = np.zeros(4)
    from kernels_by_name import contact_ends

    contact_ends(TOWERS, 0.3, probe, _P, ends)
    y[0] = pen - 0.5 * (ends[0] + ends[1])
    q = np.zeros(6)
    contact_forces(TOWERS, 0.3, y, _P, q)
    scale = max(np.abs(q).max(), 1e-12)
    for k, idx in enumerate(_POS):
        step = 1e-6 if idx != 4 and idx != 10 else 1e-8
        yp, ym = y.copy(), y.copy()
        yp[idx] += step
        ym[idx] -= step
        fd = -(_potential(yp) - _potential(ym)) / (2 * step)
        # central differences straddling the kink d = 0 err by ~ beta * (dd)^chi
        kink = 1000.0 * (step * (50.0 if idx in (4, 10) else 1.0)) ** 1.5
        assert abs(fd - q[k]) <= 2e-5 * scale + 4 * kink, (k, fd, q[k])
