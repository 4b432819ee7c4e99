"""The dissipative contact laws of issue 15 (docs/contact_laws.md): their physics.

* zero damping (e = 1) gives the elastic parent bitwise (linear, hertz);
* the line resultants against an mpmath quadrature of their defining integrals,
  in the three regimes of the moments (partial contact, near-parallel faces,
  skewed faces in full contact), and their mirror symmetry;
* the Jacobians (point and line) against central finite differences;
* a single free impact of two bodies integrated by scipy: the measured
  coefficient of restitution against the target (Kelvin-Voigt exactly, the
  others within their formulas' known deviations, the same at every approach
  speed: the laws are self-similar);
* the energy balance of a mass on a spring pounding a wall.

``analysis/contact_laws_restitution.py`` imports :func:`free_impact` and
:data:`DAMPED` from here to write the table of docs/contact_laws.md.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from chaospound.physics.contact import hertz, hertzdamp, hunt_crossley, jankowski, kelvin_voigt
from chaospound.physics.contact import linear as linear_law
from chaospound.physics.contact.dissipation import effective_mass, moment3

BASE = 3  #: the law's block starts here; the slots before are NaN (a wrong index shows)
M_EFF = effective_mass(1.0, 2.25)  #: the paper's pair, m_A / m_B = 2.25
K_LIN = 100.0  #: linear stiffness (units of K_Ax)
BETA = 1000.0  #: Hertz stiffness (units of K_Ax A_g^-0.5)
HALF = 50.0  #: half the rest overlap (units of A_g), the paper's towers

#: the dissipative laws and their blocks as a function of e: (module, block(e))
DAMPED = {
    "kelvin-voigt": (kelvin_voigt, lambda e: kelvin_voigt.block(e, k=K_LIN, m_eff=M_EFF)),
    "kelvin-voigt no-pull": (kelvin_voigt, lambda e: kelvin_voigt.block(
        e, k=K_LIN, m_eff=M_EFF, no_pull=True)),
    "hertzdamp": (hertzdamp, lambda e: hertzdamp.block(e, beta=BETA)),
    "hertzdamp ye": (hertzdamp, lambda e: hertzdamp.block(e, beta=BETA, variant="ye")),
    "hunt-crossley": (hunt_crossley, lambda e: hunt_crossley.block(e, beta=BETA)),
    "jankowski": (jankowski, lambda e: jankowski.block(e, beta=BETA, m_eff=M_EFF)),
}


def pack(values: dict[str, float]) -> np.ndarray:
    """A parameter vector with the block at BASE (the memory slots included)."""
    p = np.full(BASE + len(values), np.nan)
    p[BASE:] = list(values.values())
    return p


def law_p(name: str, e: float, v0: float = 0.8) -> tuple[object, np.ndarray]:
    """``(module, p)`` of a damped law at e, its memory set by an onset at ``v0``."""
    module, make = DAMPED[name]
    p = pack(make(e))
    module.on_onset(p, BASE, v0)
    return module, p


def bits(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float64).view(np.int64)


# ------------------------------------------------------------ strategies

_mag = st.floats(-6.0, 0.0)
_rate = st.tuples(st.sampled_from([-1.0, 1.0]), st.floats(-3.0, 1.0)).map(
    lambda t: t[0] * 10.0 ** t[1])


@st.composite
def ends(draw, regime: str) -> tuple[float, float]:
    """``(d_lo, d_hi)`` in one regime of the moments."""
    mean = 10.0 ** draw(_mag)
    if regime == "partial":
        p = mean
        q = -p * 10.0 ** draw(st.floats(-6.0, 2.0))
        d_lo, d_hi = (q, p) if draw(st.booleans()) else (p, q)
    elif regime == "parallel":
        eps = draw(st.sampled_from([-1.0, 1.0])) * 10.0 ** draw(st.floats(-12.0, math.log10(0.2)))
        d_lo, d_hi = mean * (1.0 - eps), mean * (1.0 + eps)
    else:
        eps = draw(st.sampled_from([-1.0, 1.0])) * draw(st.floats(0.2, 0.999))
        d_lo, d_hi = mean * (1.0 - eps), mean * (1.0 + eps)
    return d_lo, d_hi


def line_args(d_lo: float, d_hi: float, r_lo: float, r_hi: float) -> tuple[float, ...]:
    """``(d_c, slope, rate_c, rate_slope, half)`` of end values, half = HALF."""
    return (0.5 * (d_lo + d_hi), (d_hi - d_lo) / (2.0 * HALF), 0.5 * (r_lo + r_hi),
            (r_hi - r_lo) / (2.0 * HALF), HALF)


# ------------------------------------------------- zero damping: the parents

ELASTIC_CHILDREN = [("hertzdamp", hertz), ("hertzdamp ye", hertz), ("hunt-crossley", hertz),
                    ("jankowski", hertz), ("kelvin-voigt", linear_law),
                    ("kelvin-voigt no-pull", linear_law)]


@pytest.mark.parametrize("name,parent", ELASTIC_CHILDREN)
@pytest.mark.parametrize("regime", ["partial", "parallel", "skewed"])
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_zero_damping_is_the_elastic_parent_bitwise(name, parent, regime, data):
    """e = 1: every kernel of the damped law gives its parent's bits."""
    module, p = law_p(name, 1.0, v0=data.draw(st.floats(1e-3, 10.0)))
    d_lo, d_hi = data.draw(ends(regime))
    r_lo, r_hi = data.draw(_rate), data.draw(_rate)
    args = line_args(d_lo, d_hi, r_lo, r_hi)
    got = module.line_force(p, BASE, *args)
    ref = parent.line_force(p, BASE, *args)
    assert np.array_equal(bits(got), bits(ref))
    grad = module.line_gradient(p, BASE, got[2], got[3], r_lo, r_hi, HALF)
    ref_grad = parent.line_gradient(p, BASE, got[2], got[3], r_lo, r_hi, HALF)
    assert np.array_equal(bits(grad[:4]), bits(ref_grad[:4]))
    assert module.line_potential(p, BASE, d_lo, d_hi) == parent.line_potential(p, BASE, d_lo, d_hi)
    for d in (d_lo, d_hi):
        for r in (r_lo, r_hi):
            f_child = module.point_force(p, BASE, d, r)
            assert bits(f_child) == bits(parent.point_force(p, BASE, d, r))
            assert np.array_equal(bits(module.point_stiffness(p, BASE, d, r)),
                                  bits(parent.point_stiffness(p, BASE, d, r)))
        assert module.point_potential(p, BASE, d) == parent.point_potential(p, BASE, d)


def test_zero_damping_blocks():
    """e = 1 gives a zero damping coefficient in every block; e outside (0, 1] is refused."""
    assert kelvin_voigt.block(1.0, k=1.0, m_eff=1.0)["c"] == 0.0
    assert hertzdamp.block(1.0, beta=1.0)["zeta"] == 0.0
    assert hertzdamp.block(1.0, beta=1.0, variant="ye")["zeta"] == 0.0
    assert hunt_crossley.block(1.0, beta=1.0)["zeta"] == 0.0
    assert jankowski.block(1.0, beta=1.0, m_eff=1.0)["c_scale"] == 0.0
    for bad in (0.0, -0.5, 1.5, float("nan")):
        with pytest.raises(ValueError):
            hertzdamp.block(bad, beta=1.0)
        with pytest.raises(ValueError):
            kelvin_voigt.block(bad, k=1.0, m_eff=1.0)
    with pytest.raises(ValueError):
        hertzdamp.block(0.5, beta=1.0, variant="nope")
    # OpenSees' xiNorm = zeta / beta: Ye's recommended value gives Ye's block
    ye = hertzdamp.block(0.6, beta=BETA, variant="ye")
    assert hertzdamp.block(0.6, beta=BETA, xi_norm=8 * 0.4 / (5 * 0.6)) == pytest.approx(ye)
    with pytest.raises(ValueError):
        linear_law.block(0.5, k=1.0)


def test_interface_names():
    """Every law module exports the interface the composition binds (docs/contact_laws.md)."""
    import importlib

    from chaospound.engine.compose import LAW_FUNCTIONS, LAWS

    for name, path in LAWS.items():
        module = importlib.import_module(path)
        assert module.NAME == name
        for attr in LAW_FUNCTIONS + ("on_onset", "block", "PARAMETERS", "MEMORY",
                                     "CONSERVATIVE", "DISSIPATIVE", "JUMPS"):
            assert hasattr(module, attr), (name, attr)
        assert module.DISSIPATIVE != module.CONSERVATIVE
    # block() lists the block's slots in order: PARAMETERS, then MEMORY
    blocks = [(hertz, hertz.block(beta=BETA)), (linear_law, linear_law.block(k=K_LIN))]
    blocks += [(module, make(0.5)) for module, make in DAMPED.values()]
    for module, values in blocks:
        assert tuple(values) == module.PARAMETERS + module.MEMORY, module.NAME


def test_onset_memory_and_floor():
    """v0 = max(rate, floor) and xi = zeta / v0 are written at onset, nothing else moves."""
    p = pack(hertzdamp.block(0.5, beta=BETA, v0_floor=1e-4))
    before = p.copy()
    hertzdamp.on_onset(p, BASE, 2.5)
    assert p[BASE + 4] == 2.5 and p[BASE + 5] == p[BASE + 2] / 2.5
    hertzdamp.on_onset(p, BASE, -1.0)  # a grazing onset: the floor
    assert p[BASE + 4] == 1e-4 and p[BASE + 5] == p[BASE + 2] / 1e-4
    assert np.array_equal(p[BASE:BASE + 4], before[BASE:BASE + 4])
    assert np.isnan(p[:BASE]).all()


# ------------------------------------------------ line resultants: mpmath

def _reference_law(name: str, p: np.ndarray):
    """The law's force per unit length f(d, r) in mpmath, and its breakpoints in s."""
    import mpmath

    values = [mpmath.mpf(float(v)) for v in p[BASE:]]
    if name.startswith("kelvin-voigt"):
        k, c, no_pull = values

        def f(d, r):
            if d <= 0:
                return mpmath.mpf(0)
            g = k * d + c * r
            return max(g, mpmath.mpf(0)) if no_pull else g
        return f
    if name == "jankowski":
        beta, chi, c_s, _ = values  # (the last: the engine's phase flags of a tangent run)

        def f(d, r):
            if d <= 0:
                return mpmath.mpf(0)
            out = beta * d**chi
            return out + c_s * d ** ((chi - 1) / 2) * r if r > 0 else out
        return f
    beta, chi, xi = values[0], values[1], values[5]

    def f(d, r):
        return beta * d**chi + xi * d**chi * r if d > 0 else mpmath.mpf(0)
    return f


def reference_line(name, p, d_lo, d_hi, r_lo, r_hi, dps=30):
    """``(I0, I1, S0, S1)``: int f ds, int f (s - 1/2) ds and the same of |f| |s - 1/2|^k."""
    import mpmath

    f = _reference_law(name, p)
    with mpmath.workdps(dps):
        lo, hi, rl, rh = (mpmath.mpf(v) for v in (d_lo, d_hi, r_lo, r_hi))

        def at(s):
            return f(lo + (hi - lo) * s, rl + (rh - rl) * s)
        points = {mpmath.mpf(0), mpmath.mpf(1)}
        for a, b in ((lo, hi), (rl, rh)):
            if a != b and 0 < a / (a - b) < 1:
                points.add(a / (a - b))
        if name.startswith("kelvin-voigt"):
            k, c = mpmath.mpf(float(p[BASE])), mpmath.mpf(float(p[BASE + 1]))
            a, b = k * lo + c * rl, k * hi + c * rh
            if a != b and 0 < a / (a - b) < 1:
                points.add(a / (a - b))
        points = sorted(points)
        half = mpmath.mpf(1) / 2
        i0 = mpmath.quad(at, points)
        i1 = mpmath.quad(lambda s: at(s) * (s - half), points)
        s0 = mpmath.quad(lambda s: abs(at(s)), points)
        s1 = mpmath.quad(lambda s: abs(at(s) * (s - half)), points)
        return float(i0), float(i1), float(s0), float(s1)


def _line_case(name, d_lo, d_hi, r_lo, r_hi, e=0.55):
    module, p = law_p(name, e, v0=0.9)
    args = line_args(d_lo, d_hi, r_lo, r_hi)
    force, moment, lo, hi = module.line_force(p, BASE, *args)
    r_lo2 = args[2] - args[3] * HALF
    r_hi2 = args[2] + args[3] * HALF
    return module, p, args, force, moment, (lo, hi, r_lo2, r_hi2)


@pytest.mark.parametrize("name", list(DAMPED) + ["linear"])
@pytest.mark.parametrize("regime", ["partial", "parallel", "skewed"])
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_line_resultants_match_mpmath(name, regime, data):
    """Force and moment to 1e-12 of int |f| (and int |f| |s - 1/2|) over the line."""
    d_lo, d_hi = data.draw(ends(regime))
    r_lo, r_hi = data.draw(_rate), data.draw(_rate)
    if name == "linear":
        p = pack(linear_law.block(k=K_LIN))
        force, moment, lo, hi = linear_law.line_force(p, BASE, *line_args(d_lo, d_hi, 0.0, 0.0))
        import mpmath

        with mpmath.workdps(30):
            ref = [float(mpmath.quad(lambda s, k=k: max(lo + (hi - lo) * s, 0) * (s - 0.5) ** k,
                                     [0, 1] if lo * hi > 0 else [0, lo / (lo - hi), 1]))
                   * K_LIN for k in (0, 1)]
        assert abs(force - ref[0]) <= 1e-12 * abs(ref[0])
        assert abs(moment / (2 * HALF) - ref[1]) <= 1e-12 * force
        return
    _, p, _, force, moment, (lo, hi, rl, rh) = _line_case(name, d_lo, d_hi, r_lo, r_hi)
    i0, i1, s0, s1 = reference_line(name, p, lo, hi, rl, rh)
    assert abs(force - i0) <= 1e-12 * s0 + 1e-300
    assert abs(moment / (2.0 * HALF) - i1) <= 1e-12 * s1 + 1e-300


@pytest.mark.parametrize("name", list(DAMPED))
@pytest.mark.parametrize("regime", ["partial", "parallel", "skewed"])
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_line_resultants_mirror_symmetric(name, regime, data):
    """Swapping the ends (negating both slopes) keeps the force and negates the moment:
    bitwise for the laws on the moments alone, to 1e-12 of the scale for the split lines
    (their split point is computed from the end values, which the swap exchanges; seen:
    1.3e-13 where a clipped force nearly cancels). The scale counts the undamped
    force of the same penetration too: where the damping cancels it to 5e-15 (ends
    +-0.01, rates -+1) the split point's rounding is relative to the parts, not to
    their tiny sum (9e-24, found by hypothesis)."""
    d_lo, d_hi = data.draw(ends(regime))
    r_lo, r_hi = data.draw(_rate), data.draw(_rate)
    module, p = law_p(name, 0.5)
    d_c, slope, rate_c, rate_slope, half = line_args(d_lo, d_hi, r_lo, r_hi)
    f1, m1, lo1, hi1 = module.line_force(p, BASE, d_c, slope, rate_c, rate_slope, half)
    f2, m2, lo2, hi2 = module.line_force(p, BASE, d_c, -slope, rate_c, -rate_slope, half)
    assert lo1 == hi2 and hi1 == lo2
    if name in ("jankowski", "kelvin-voigt no-pull"):
        f0, m0, _, _ = module.line_force(p, BASE, d_c, slope, 0.0, 0.0, half)
        scale = abs(f1) + abs(m1) / half + abs(f0) + abs(m0) / half + 1e-300
        assert abs(f1 - f2) <= 1e-12 * scale and abs(m1 + m2) <= 1e-12 * scale * half
    else:
        assert f1 == f2 and m1 == -m2


@pytest.mark.parametrize("j", [-0.75, 0.0, 0.25, 0.5, 1.5, 2.5])
@pytest.mark.parametrize("regime", ["partial", "parallel", "skewed"])
@settings(max_examples=15, deadline=None)
@given(data=st.data())
def test_moment3_matches_mpmath(j, regime, data):
    """The third moment (the Jacobians' rate terms) to 1e-12 of int d+^j |s - 1/2|^3."""
    import mpmath

    d_lo, d_hi = data.draw(ends(regime))
    got = moment3(j, d_lo, d_hi)
    assert moment3(j, d_hi, d_lo) == -got
    with mpmath.workdps(50):  # 30 digits miss the d^-0.75 edge singularity by ~1e-8
        lo, hi = mpmath.mpf(d_lo), mpmath.mpf(d_hi)

        def pen(s):
            d = lo + (hi - lo) * s
            return d**j if d > 0 else mpmath.mpf(0)
        pts = [0, 1] if lo > 0 and hi > 0 else [0, lo / (lo - hi), 1]
        ref = mpmath.quad(lambda s: pen(s) * (s - 0.5) ** 3, pts)
        scale = mpmath.quad(lambda s: pen(s) * abs(s - 0.5) ** 3, pts)
        if not (lo > 0 and hi > 0):
            # one end in contact: the quadrature of the d^j edge singularity errs by
            # ~1e-12 for j < 0 (seen at j = -0.75); the exact value is a sum of Beta
            # functions: M3 = sign f p^j int_0^1 (1 - w)^j (1/2 - f w)^3 dw
            p, sign = (hi, 1) if hi > 0 else (lo, -1)
            f = p / abs(hi - lo)
            beta = [mpmath.beta(j + 1, n + 1) for n in range(4)]
            ref = sign * f * p**j * (beta[0] / 8 - 3 * f * beta[1] / 4
                                     + 3 * f**2 * beta[2] / 2 - f**3 * beta[3])
    assert abs(got - float(ref)) <= 1e-12 * float(scale)


# ------------------------------------------------------------- Jacobians

def _fd_line(module, p, args, which, h):
    plus = list(args)
    minus = list(args)
    plus[which] += h
    minus[which] -= h
    fp, mp_, _, _ = module.line_force(p, BASE, *plus)
    fm, mm, _, _ = module.line_force(p, BASE, *minus)
    return (fp - fm) / (2 * h), (mp_ - mm) / (2 * h)


@pytest.mark.parametrize("name", list(DAMPED))
def test_line_gradient_matches_finite_differences(name):
    """The 8 derivatives of (force, moment) against central differences; points whose
    differences at h and h/2 disagree (a kink of the law inside the stencil) are skipped,
    and at most a fifth may be."""
    rng = np.random.default_rng(15)
    checked = 0
    cases = 60
    for i in range(cases):
        regime = ("partial", "parallel", "skewed")[i % 3]
        mean = 10.0 ** rng.uniform(-4, 0)
        if regime == "partial":
            d_lo, d_hi = mean, -mean * 10.0 ** rng.uniform(-2, 1)
        elif regime == "parallel":
            d_lo, d_hi = mean * (1 - 0.1 * rng.uniform(-1, 1)), mean
        else:
            d_lo, d_hi = mean * rng.uniform(0.05, 0.6), mean
        if rng.random() < 0.5:
            d_lo, d_hi = d_hi, d_lo
        r_lo, r_hi = rng.choice([-1, 1], 2) * 10.0 ** rng.uniform(-2, 1, 2)
        module, p = law_p(name, 0.5, v0=0.9)
        args = line_args(d_lo, d_hi, r_lo, r_hi)
        force, moment, lo, hi = module.line_force(p, BASE, *args)
        grad = module.line_gradient(p, BASE, lo, hi, args[2] - args[3] * HALF,
                                    args[2] + args[3] * HALF, HALF)
        d_scale = max(abs(lo), abs(hi))
        r_scale = max(abs(r_lo), abs(r_hi))
        steps = (1e-6 * d_scale, 1e-6 * d_scale / HALF, 1e-6 * r_scale, 1e-6 * r_scale / HALF)
        scale = abs(force) + abs(moment) / HALF
        if scale == 0.0:  # no force anywhere on the line (clipped): nor any derivative
            assert not any(grad)
            checked += 1
            continue
        ok = True
        errors = []
        for which, h in enumerate(steps):
            fd = _fd_line(module, p, args, which, h)
            fd2 = _fd_line(module, p, args, which, h / 2)
            got = (grad[[0, 1, 4, 5][which]], grad[[2, 3, 6, 7][which]])
            for g, a, b, w in zip(got, fd, fd2, (1.0, 1.0 / HALF), strict=True):
                if abs(a - b) * h * w > 1e-8 * scale:
                    ok = False  # a kink inside the stencil
                errors.append(abs(g - b) * h * w / scale)
        if ok:
            checked += 1
            assert max(errors) < 1e-7, (name, regime, d_lo, d_hi, r_lo, r_hi, errors)
    assert checked >= 0.8 * cases


@pytest.mark.parametrize("name", list(DAMPED))
def test_point_stiffness_and_rate_match_finite_differences(name):
    """``(dF/dd, dF/dd')`` and ``dF/dt = F_d d' + F_r d''`` against differences."""
    rng = np.random.default_rng(7)
    module, p = law_p(name, 0.5, v0=0.9)
    for _ in range(50):
        d = 10.0 ** rng.uniform(-5, 0)
        r = rng.choice([-1, 1]) * 10.0 ** rng.uniform(-2, 1)
        a = rng.normal() * 10.0
        f = module.point_force(p, BASE, d, r)
        if name == "kelvin-voigt no-pull" and abs(f) < 1e-3 * (K_LIN * d):
            continue  # at the clip
        kd, kr = module.point_stiffness(p, BASE, d, r)
        hd, hr = 1e-6 * d, 1e-6 * abs(r)
        force = module.point_force
        fd_d = (force(p, BASE, d + hd, r) - force(p, BASE, d - hd, r)) / (2 * hd)
        fd_r = (force(p, BASE, d, r + hr) - force(p, BASE, d, r - hr)) / (2 * hr)
        scale = abs(f) + 1e-300
        assert abs(kd - fd_d) * hd <= 1e-8 * scale + 1e-14 * abs(kd * hd)
        assert abs(kr - fd_r) * hr <= 1e-8 * scale + 1e-14 * abs(kr * hr)
        rate = module.point_force_rate(p, BASE, d, r, a)
        assert math.isclose(rate, kd * r + kr * a, rel_tol=1e-12, abs_tol=1e-12 * abs(kd * r))
        # the models' call without the acceleration: accel = 0
        assert module.point_force_rate(p, BASE, d, r) == module.point_force_rate(p, BASE, d, r, 0.0)


# ---------------------------------------------------------- free impacts

def free_impact(module, p: np.ndarray, m_eff: float, v0: float, method: str = "DOP853",
                rtol: float = 1e-12, atol: float = 1e-14) -> tuple[float, float, float]:
    """One impact of two free bodies: ``m_eff d'' = -F(d, d')`` from ``d = 0``, ``d' = v0``.

    The law's point force is called from Python (its numba dispatcher); scipy's
    ``solve_ivp`` integrates until d returns to 0 (a terminal event), its error
    control shrinking the steps that straddle a jump of the force (Kelvin-Voigt)
    until they are accurate.

    Returns
    -------
    (e, duration, peak_force, least_force) : tuple of float
        The measured coefficient of restitution ``-d'_end / v0``, the contact
        duration (units of 1 / omega_Ax), and the largest and the least (most
        tensile) force at the accepted steps (units of A_g K_Ax).
    """
    module.on_onset(p, BASE, v0)
    force = module.point_force

    def rhs(t, y):
        return [y[1], -force(p, BASE, y[0], y[1]) / m_eff]

    def released(t, y):
        return y[0]
    released.terminal = True
    released.direction = -1
    # a contact lasts ~ (m_eff^2 / (beta^2 v0))^(1/5) (Hertz), pi sqrt(m_eff / k) (linear)
    sol = solve_ivp(rhs, (0.0, 1e4), [1e-300, v0], method=method, rtol=rtol, atol=atol,
                    events=released)
    if sol.status != 1:
        raise RuntimeError(f"no release: {sol.message}")
    forces = [force(p, BASE, d, v) for d, v in sol.y.T[1:-1]]
    forces.append(force(p, BASE, 1e-300, sol.y_events[0][0][1]))  # the limit at release
    return -sol.y_events[0][0][1] / v0, float(sol.t_events[0][0]), max(forces), min(forces)


#: measured e must lie within these bands around the target (docs/contact_laws.md):
#: (lower bound of e_measured - e, upper bound), for e in 0.3 .. 0.95
KNOWN_DEVIATION = {
    "kelvin-voigt": (-1e-8, 1e-8),          # exact by construction
    "kelvin-voigt no-pull": (0.0, 0.1),     # ends early: loses less than plain
    "hertzdamp": (0.0, 0.4),                # Lankarani-Nikravesh: good only near e = 1
    "hertzdamp ye": (-0.05, 0.0),           # Ye et al.: slightly too dissipative
    "hunt-crossley": (0.0, 0.3),            # Hunt-Crossley: too little dissipation at low e
    "jankowski": (-0.01, 0.0),              # Jankowski: within 0.01 below
}


@pytest.mark.parametrize("name", list(DAMPED))
@pytest.mark.parametrize("e", [0.3, 0.5, 0.65, 0.8, 0.95])
def test_free_impact_restitution(name, e):
    """The measured e is in the law's known band, the same at approach speeds over
    three decades (every law here is self-similar in v0), and tends to the target as
    e -> 1."""
    module, make = DAMPED[name]
    measured = []
    for v0 in (0.01, 0.3, 10.0):
        p = pack(make(e))
        measured.append(free_impact(module, p, M_EFF, v0)[0])
    lo, hi = KNOWN_DEVIATION[name]
    assert lo <= measured[1] - e <= hi, (name, e, measured)
    assert max(measured) - min(measured) < 1e-9, measured
    if e == 0.95:
        assert abs(measured[1] - e) < 5e-3


def test_kelvin_voigt_restitution_exact():
    """Plain Kelvin-Voigt: the half-cycle of a damped oscillator ends with e v0 exactly."""
    for e in (0.3, 0.5, 0.7, 0.9, 0.99):
        for v0 in (1e-2, 1.0, 1e1):
            p = pack(kelvin_voigt.block(e, k=K_LIN, m_eff=M_EFF))
            measured, duration, _, _ = free_impact(kelvin_voigt, p, M_EFF, v0)
            assert abs(measured - e) < 1e-8
            xi = kelvin_voigt.damping_ratio(e)
            expected = math.pi / (math.sqrt(K_LIN / M_EFF) * math.sqrt(1.0 - xi * xi))
            assert abs(duration - expected) < 1e-8 * expected


def test_free_impact_independent_of_integrator():
    """DOP853 and Radau agree on the measured e (the measurement is the law's, not the
    method's)."""
    for name in ("hertzdamp", "jankowski", "kelvin-voigt no-pull"):
        module, make = DAMPED[name]
        a = free_impact(module, pack(make(0.6)), M_EFF, 1.0)[0]
        b = free_impact(module, pack(make(0.6)), M_EFF, 1.0, method="Radau")[0]
        assert abs(a - b) < 1e-8, (name, a, b)


# ------------------------------------------------------------ energy balance

def wall_run(name: str, e: float, impacts: int, k_s: float = 1.0, mass: float = 1.0,
             rtol: float = 1e-12):
    """A mass on a spring pounding a wall at its rest position (no damping, no ground).

    ``m x'' = -k_s x - F(x, x')``; the state carries ``W``, the work of the
    contact's damping part ``F - F_elastic`` (``W' = (F - F_el) x'``). Each
    episode is integrated on its own (terminal events at d = 0 in the expected
    direction), the onset writing the law's memory, by scipy's DOP853 at ``rtol``
    (``atol = 1e-3 rtol``).

    Returns
    -------
    (balance, energies) : (float, list of float)
        ``max |E + W - E0| / E0`` over the episode ends, and E at each onset.
    """
    module, make = DAMPED[name]
    p = pack(make(e))
    parent = linear_law if name.startswith("kelvin-voigt") else hertz
    force, elastic = module.point_force, parent.point_force

    def energy(y):
        kinetic = 0.5 * mass * y[1] ** 2
        return kinetic + 0.5 * k_s * y[0] ** 2 + module.point_potential(p, BASE, y[0])

    def rhs(t, y):
        f = force(p, BASE, y[0], y[1])
        return [y[1], (-k_s * y[0] - f) / mass, (f - elastic(p, BASE, y[0], y[1])) * y[1]]

    def crossing(t, y):
        return y[0]
    crossing.terminal = True
    y = np.array([0.0, 1.0, 0.0])
    e0 = energy(y)
    worst = 0.0
    energies = []
    t = 0.0
    for _ in range(impacts):
        module.on_onset(p, BASE, y[1])
        energies.append(energy(y))
        y[0] = 1e-300
        for direction in (-1, 1):  # in contact until d falls to 0, then free until it rises
            crossing.direction = direction
            sol = solve_ivp(rhs, (t, t + 1e3), y, method="DOP853", rtol=rtol,
                            atol=1e-3 * rtol, events=crossing)
            t = float(sol.t_events[0][0])
            y = np.array(sol.y_events[0][0])
            y[0] = -1e-300 if direction == -1 else 0.0
            worst = max(worst, abs(energy(y) + y[2] - e0) / e0)
    return worst, energies


@pytest.mark.parametrize("name", list(DAMPED))
def test_energy_balance(name):
    """Kinetic + spring + contact potential lost = work of the damping force, to 1e-8."""
    worst, energies = wall_run(name, 0.8, 12)
    assert worst < 1e-8
    assert energies[-1] < 0.5 * energies[0]  # it did dissipate


@pytest.mark.slow
@pytest.mark.parametrize("name", list(DAMPED))
def test_energy_balance_100_impacts(name):
    """The same over 100 impacts (issue 15), e = 0.95. The reference runs at rtol 1e-13:
    the no-pull variant's force has a kink inside each episode (where it would pull, it
    is clamped to 0) that scipy steps across without an event, and its error adds up
    over the episodes (1.2e-8 after 100 at rtol 1e-12, 9e-10 at 1e-13, 3e-11 at 3e-14:
    the reference's error, not the law's)."""
    worst, energies = wall_run(name, 0.95, 100, rtol=1e-13)
    assert worst < 1e-8
    assert energies[-1] < 0.1 * energies[0]


def bar_run(name: str, e: float, impacts: int):
    """A rigid bar on a translational and a torsional spring pounding a wall along its
    face (a line contact that rotates: corner and face impacts, the line's ends
    penetrating in turn), no damping, no ground.

    ``d(y) = X - th y`` on ``y`` in [-HALF, HALF]; ``m X'' = -k_x X - F``,
    ``I th'' = -k_t th + M`` with (F, M) the law's line resultants; ``W' = (F -
    F_el) X' - (M - M_el) th'`` is the work of the damping part. The memory is
    written at each onset with the closing velocity of the end that touches
    first (docs/contact_laws.md section 2).

    Returns ``max |E + W - E0| / E0`` over the episode ends and E at each onset.
    """
    module, make = DAMPED[name]
    p = pack(make(e))
    parent = linear_law if name.startswith("kelvin-voigt") else hertz
    mass, inertia, k_x, k_t = 1.0, 400.0, 1.0, 1200.0

    def ends(y):
        return y[0] + y[2] * HALF, y[0] - y[2] * HALF  # d_lo (y = -HALF), d_hi

    def energy(y):
        d_lo, d_hi = ends(y)
        return (0.5 * mass * y[1] ** 2 + 0.5 * inertia * y[3] ** 2 + 0.5 * k_x * y[0] ** 2
                + 0.5 * k_t * y[2] ** 2 + module.line_potential(p, BASE, d_lo, d_hi))

    def rhs(t, y):
        f, m, _, _ = module.line_force(p, BASE, y[0], -y[2], y[1], -y[3], HALF)
        f_el, m_el, _, _ = parent.line_force(p, BASE, y[0], -y[2], y[1], -y[3], HALF)
        return [y[1], (-k_x * y[0] - f) / mass, y[3], (-k_t * y[2] + m) / inertia,
                (f - f_el) * y[1] - (m - m_el) * y[3]]

    def touching(t, y):
        return max(ends(y))
    touching.terminal = True
    y = np.array([-0.3, 0.0, 0.01, 0.0, 0.0])  # starts free, tilted: corner impacts
    e0 = energy(y)
    worst = 0.0
    energies = []
    t = 0.0
    for _ in range(impacts):
        touching.direction = 1
        sol = solve_ivp(rhs, (t, t + 1e3), y, method="DOP853", rtol=1e-12, atol=1e-15,
                        events=touching)
        t = float(sol.t_events[0][0])
        y = np.array(sol.y_events[0][0])
        d_lo, d_hi = ends(y)
        rate = y[1] + y[3] * HALF if d_lo >= d_hi else y[1] - y[3] * HALF
        module.on_onset(p, BASE, rate)
        energies.append(energy(y))
        y[0] += 1e-15 * HALF * abs(y[2]) + 1e-300  # just inside, so the event is ahead
        touching.direction = -1
        sol = solve_ivp(rhs, (t, t + 1e3), y, method="DOP853", rtol=1e-12, atol=1e-15,
                        events=touching)
        t = float(sol.t_events[0][0])
        y = np.array(sol.y_events[0][0])
        worst = max(worst, abs(energy(y) + y[4] - e0) / e0)
        y[0] -= 1e-15 * HALF * abs(y[2]) + 1e-300
    return worst, energies


@pytest.mark.parametrize("name", list(DAMPED))
def test_energy_balance_line_contact(name):
    """The line resultants in motion: energy lost = work of the damping part, to 1e-8,
    over impacts of a rotating face (corner onsets)."""
    worst, energies = bar_run(name, 0.8, 8)
    assert worst < 1e-8
    assert energies[-1] < 0.9 * energies[0]


@pytest.mark.parametrize("name", list(DAMPED))
def test_uniform_line_is_the_point_law(name):
    """Parallel faces moving together (no slope, no rate slope): the line resultant is
    the point force, the moment 0, and the line Jacobian the point stiffness (1e-14)."""
    rng = np.random.default_rng(3)
    module, p = law_p(name, 0.45, v0=0.7)
    for _ in range(40):
        d = 10.0 ** rng.uniform(-6, 0)
        r = rng.choice([-1, 1]) * 10.0 ** rng.uniform(-3, 1)
        force, moment, d_lo, d_hi = module.line_force(p, BASE, d, 0.0, r, 0.0, HALF)
        point = module.point_force(p, BASE, d, r)
        scale = K_LIN * d + BETA * d**1.5 + abs(r)
        assert abs(force - point) <= 1e-14 * scale and moment == 0.0
        grad = module.line_gradient(p, BASE, d_lo, d_hi, r, r, HALF)
        kd, kr = module.point_stiffness(p, BASE, d, r)
        assert math.isclose(grad[0], kd, rel_tol=1e-14, abs_tol=1e-14 * abs(kd) + 1e-300)
        assert math.isclose(grad[4], kr, rel_tol=1e-14, abs_tol=1e-300)


# ---------------------------------------------------------- peak force in the engine

@pytest.mark.parametrize(("law", "e"), [("hertzdamp", 0.5), ("hunt-crossley", 0.65)])
def test_the_engine_reports_the_peak_of_a_dissipative_force(law, e):
    """A dissipative force peaks while the faces still approach, inside a step and
    before the penetration's maximum: the engine's peak force is the episode's
    maximum (the wall model, one impact, no ground motion), against scipy's DOP853
    at 1e-12 with the maximum located on its dense output. Before the fix only the
    step ends were candidates for a point contact: 6e-4 low (hertzdamp, e = 0.5) and
    6e-5 low (hunt-crossley) at rtol 1e-8."""
    from scipy.optimize import minimize_scalar

    from chaospound.scene import load_preset
    from chaospound.simulate import simulate

    beta, gap, zeta_x = 40.0, 1.0, 0.03
    scene = load_preset("wall").with_params(
        ground="none", contact_law=law, restitution=e, beta=beta, gap=gap, zeta_x=zeta_x,
        rtol=1e-8, atol=1e-10)
    y0 = (gap - 0.2, 3.0)
    run = simulate(scene, transient=0, record=1, initial_state=np.array(y0))
    assert len(run.impacts) == 1
    # X'' = -2 zeta X' - X - F (docs/model.md section 9, no ground), F = beta d^1.5 (1 + c d')
    ratio = 3.0 * (1.0 - e * e) / 4.0 if law == "hertzdamp" else 3.0 * (1.0 - e) / 2.0

    def approach(t, y):
        return [y[1], -2.0 * zeta_x * y[1] - y[0]]

    def onset(t, y):
        return y[0] - gap
    onset.terminal = True
    onset.direction = 1
    free = solve_ivp(approach, (0.0, 10.0), y0, method="DOP853", rtol=1e-12, atol=1e-14,
                     events=onset)
    v0 = free.y_events[0][0][1]

    def force(y):
        d = y[0] - gap
        return beta * d**1.5 * (1.0 + ratio * y[1] / v0) if d > 0.0 else 0.0

    def contact(t, y):
        return [y[1], -2.0 * zeta_x * y[1] - y[0] - force(y)]

    def release(t, y):
        return y[0] - gap
    release.terminal = True
    release.direction = -1
    hit = solve_ivp(contact, (free.t_events[0][0], 20.0), [gap, v0], method="DOP853",
                    rtol=1e-12, atol=1e-14, events=release, dense_output=True)
    grid = np.linspace(hit.t[0], hit.t[-1], 401)
    k = int(np.argmax([force(hit.sol(s)) for s in grid]))
    best = minimize_scalar(lambda s: -force(hit.sol(s)), bounds=(grid[k - 1], grid[k + 1]),
                           method="bounded", options={"xatol": 1e-13})
    assert run.impacts.velocity[0] == pytest.approx(v0, rel=1e-8)
    assert run.impacts.peak_force[0] == pytest.approx(-best.fun, rel=1e-7)
