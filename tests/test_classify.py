"""Regime classification: synthetic sequences, the 0-1 test, and the paper's responses.

Synthetic data test each rule of docs/classification.md in isolation (periods
and impacts that repeat or do not, quasi-periodic and chaotic sections); the
scenes test the physics: the paper's group-periodic 3-1 at T/T_Ax = 0.70 with
impacts at two corners of one tower around one of the other, the chaotic
torsional response at 0.9, and the translational model, which needs no torsion
to be periodic.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from chaospound.cli import main
from chaospound.dynamics.classify import (
    DEFAULT_TOL,
    REGIMES,
    TAIL_MIN,
    Regime,
    _aperiodic_regime,
    _converged_period,
    _mismatch,
    _scale,
    birkhoff_digits,
    classify,
    classify_sequence,
    mean_square_displacement,
    zero_one_test,
)
from chaospound.dynamics.system import System, duffing
from chaospound.scene import load_preset

GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
JSON_KEYS = {
    "regime", "label", "impacts_per_period", "period_cycles", "corner_sequence",
    "strobe_mismatch", "max_exponent", "max_exponent_error", "zero_one", "confidence",
    "transient_used", "scene", "model",
}  # fmt: skip


# ========================================================== synthetic data
def periodic_record(period, group, cycles=64, noise=1e-7, seed=0):
    """Sections of period ``period`` and impacts ``group`` = [(cycle offset, phase, V, corner)].

    Every period repeats the group; the sections and the impact phases and
    velocities carry Gaussian noise of relative size ``noise`` (below tol).
    """
    rng = np.random.default_rng(seed)
    base = rng.uniform(-1.0, 1.0, size=(period, 4))
    states = base[np.arange(cycles + 1) % period] + noise * rng.normal(size=(cycles + 1, 4))
    rows = [
        (start + offset, phase, velocity, corner)
        for start in range(0, cycles, period)
        for offset, phase, velocity, corner in group
        if start + offset < cycles
    ]
    k, phase, velocity, corner = (list(column) for column in zip(*rows, strict=True))
    phase = np.array(phase) + noise * rng.normal(size=len(phase))
    velocity = np.array(velocity) * (1.0 + noise * rng.normal(size=len(velocity)))
    return states, np.array(k), phase, velocity, corner


def logistic(n, r=4.0, x0=0.3141):
    x = np.empty(n)
    x[0] = x0
    for i in range(n - 1):
        x[i + 1] = r * x[i] * (1.0 - x[i])
    return x


def one_impact_per_cycle(velocities):
    """One A+ impact per cycle with the given velocities and phases following them."""
    n = len(velocities)
    return np.arange(n), 0.2 + 0.1 * np.tanh(velocities), np.asarray(velocities), ["A+"] * n


@pytest.mark.parametrize(
    ("period", "group", "label"),
    [
        (1, [(0, 0.3, 2.0, "face")], "periodic 1-1"),
        (2, [(1, 0.6, 1.5, "face")], "periodic 1-2"),
        (4, [(2, 0.1, 0.9, "A+")], "periodic 1-4"),
        (1, [(0, 0.63, 3.6, "A+"), (0, 0.72, 5.9, "B-"), (0, 0.81, 2.9, "A+")],
         "group-periodic 3-1"),
        (2, [(0, 0.1, 1.0, "A+"), (0, 0.5, 2.0, "B-"), (0, 0.9, 1.2, "A-"),
             (1, 0.3, 0.7, "B+"), (1, 0.6, 1.1, "A+")], "group-periodic 5-2"),
    ],
)  # fmt: skip
def test_synthetic_periodic_sequences(period, group, label):
    regime = classify_sequence(*periodic_record(period, group))
    assert regime.label == label
    assert regime.period_cycles == period
    assert regime.impacts_per_period == len(group)
    assert regime.corner_sequence == [corner for *_, corner in group]
    assert regime.strobe_mismatch < DEFAULT_TOL
    assert regime.confidence > 0.5
    assert regime.max_exponent is None and regime.zero_one is None  # not needed with a period


def test_noise_above_tol_is_not_a_period():
    """The same period-1 record with section noise 10 tol: no period, rules 6-7 decide."""
    states, *impacts = periodic_record(1, [(0, 0.3, 2.0, "face")], noise=1e-4)
    regime = classify_sequence(states, *impacts)
    assert regime.period_cycles is None
    assert regime.strobe_mismatch > DEFAULT_TOL
    assert regime.regime == "unresolved"  # 65 sections: too few for the 0-1 test


def test_impacts_must_repeat_as_well_as_the_section():
    """Sections of period 1 but impact corners alternating A+, B-: the period is 2 (2-2)."""
    states, k, phase, velocity, _ = periodic_record(1, [(0, 0.3, 2.0, "A+")])
    corners = ["A+" if c % 2 == 0 else "B-" for c in k]
    regime = classify_sequence(states, k, phase, velocity, corners)
    assert regime.label == "periodic 2-2"
    assert regime.corner_sequence == ["A+", "B-"]
    # impact phases that drift by 1e-3 per cycle never repeat
    drifting = phase + 1e-3 * k
    assert classify_sequence(states, k, drifting, velocity, ["A+"] * len(k)).regime == "unresolved"


def test_impacts_that_stop_do_not_repeat():
    """Impacts in the first half of the window only: no period, whatever the sections say."""
    states, k, phase, velocity, corners = periodic_record(1, [(0, 0.3, 2.0, "face")])
    half = k < 32
    regime = classify_sequence(states, k[half], phase[half], velocity[half],
                               [c for c, h in zip(corners, half, strict=True) if h])
    assert regime.period_cycles is None


def test_quasi_periodic_rotation():
    """x_k = (cos 2 pi k w, sin 2 pi k w), w the golden mean: no period, K ~ 0."""
    k = np.arange(1001)
    states = np.column_stack([np.cos(2 * np.pi * GOLDEN * k), np.sin(2 * np.pi * GOLDEN * k)])
    regime = classify_sequence(states, *one_impact_per_cycle(states[:-1, 0]))
    assert regime.regime == "quasi-periodic"
    assert regime.zero_one < 0.2
    assert regime.period_cycles is None and regime.corner_sequence == []


def test_chaotic_logistic_map():
    x = logistic(1001)
    regime = classify_sequence(x, *one_impact_per_cycle(x[:-1]))
    assert regime.regime == "chaotic"
    assert regime.zero_one > 0.8
    assert regime.confidence > 0.5


def test_no_impacts_is_none_with_the_period_of_the_motion():
    states, *_ = periodic_record(2, [(0, 0.3, 1.0, "face")])
    regime = classify_sequence(states, [], [], [], [])
    assert regime.label == "none"
    assert regime.impacts_per_period == 0
    assert regime.period_cycles == 2


@pytest.mark.parametrize(
    ("exponent", "error", "expected"),
    [(0.09, 0.01, "chaotic"), (0.01, 0.01, "unresolved"), (-0.05, 0.005, "unresolved")],
)
def test_exponent_rule_without_the_01_test(exponent, error, expected):
    """docs/model.md 12: chaotic beyond 3 standard errors; without a 0-1 test an exponent
    merely consistent with 0 cannot tell weak chaos from quasi-periodicity (unresolved);
    < 0 without a period is unresolved."""
    x = logistic(101)
    regime = classify_sequence(x, *one_impact_per_cycle(x[:-1]), exponent=exponent,
                               exponent_error=error, test01=False)
    assert regime.regime == expected
    assert regime.max_exponent == exponent and regime.zero_one is None


def test_the_01_test_vetoes_an_exponent_it_contradicts():
    """A 'positive' exponent on quasi-periodic data (K ~ 0) is not called chaotic."""
    k = np.arange(1001)
    x = np.cos(2 * np.pi * GOLDEN * k)
    regime = classify_sequence(x, *one_impact_per_cycle(x[:-1]), exponent=0.05,
                               exponent_error=0.001)
    assert regime.regime == "unresolved"


def test_bad_sequences_are_rejected_with_one_line():
    states = np.zeros((10, 2))
    with pytest.raises(ValueError, match="entries"):
        classify_sequence(states, [0, 1], [0.1], [1.0], ["A+"])
    with pytest.raises(ValueError, match="corner 'C'"):
        classify_sequence(states, [0], [0.1], [1.0], ["C"])
    with pytest.raises(ValueError, match="tol"):
        classify_sequence(states, [], [], [], [], tol=-1.0)
    with pytest.raises(ValueError, match="finite"):
        classify_sequence(states, [0], [math.nan], [1.0], ["A+"])


# ================================================================ 0-1 test
def test_zero_one_separates_chaos_from_regular_signals():
    k = np.arange(1000)
    assert zero_one_test(logistic(1000)) > 0.8
    assert zero_one_test(np.tile([0.1, 0.7, 0.4], 334)[:1000]) < 0.2  # period 3
    assert zero_one_test(np.cos(2 * np.pi * GOLDEN * k)) < 0.2  # quasi-periodic
    # the modified mean-square displacement removes the mean's oscillation
    assert zero_one_test(5.0 + np.cos(2 * np.pi * GOLDEN * k)) < 0.2


def test_zero_one_is_reproducible_and_accepts_explicit_c():
    x = logistic(500)
    assert zero_one_test(x, seed=3) == zero_one_test(x, seed=3)
    assert zero_one_test(x, c_values=[1.0, 1.7, 2.3]) > 0.8
    with pytest.raises(ValueError, match="at least 20"):
        zero_one_test(x[:10])


def test_zero_one_is_the_same_whatever_ran_before():
    """The tables of exp(i c j) kept between tests (by record length and c) give the
    value of a first call, after calls on other lengths and c that fill and clear them,
    and equal the direct sums of the test's definition."""
    x = logistic(1000)
    first = zero_one_test(x)
    for n in (300, 700, 999, 1000, 1001, 40):
        zero_one_test(logistic(n), seed=n)
        zero_one_test(logistic(n), c_values=[1.1, 2.0])
    assert zero_one_test(x) == first
    c = np.random.default_rng(0).uniform(np.pi / 5, 4 * np.pi / 5, size=100)
    assert zero_one_test(x, c_values=c) == first
    j = np.arange(1, 1001)
    lags = np.arange(1, 101)
    ks = []
    for ci in c:  # the definition, sum by sum
        z = np.cumsum(x * np.exp(1j * ci * j))
        m = np.array([np.mean(np.abs(z[n:] - z[:-n]) ** 2) for n in lags])
        d = m - x.mean() ** 2 * (1 - np.cos(lags * ci)) / (1 - np.cos(ci))
        ks.append(np.corrcoef(lags, d)[0, 1])
    assert first == pytest.approx(np.median(ks), abs=1e-9)


def banded_logistic(n, r=3.575):
    """The logistic map past the period-doubling cascade: chaos in four bands visited in
    turn (largest exponent about +0.09 per step), 2000 steps of transient dropped."""
    return logistic(2000 + n, r=r)[2000:]


def test_zero_one_sees_chaos_in_bands():
    """Banded chaos: the plain test's K is low (the band pattern's bounded oscillation
    swamps the chaotic growth over 1000 values); less its band means, K is near 1."""
    x = banded_logistic(1000)
    steps = np.log(np.abs(3.575 * (1.0 - 2.0 * banded_logistic(20000))))
    assert 0.05 < steps.mean() < 0.15  # chaotic: a positive exponent
    assert zero_one_test(x) < 0.2
    assert zero_one_test(x, bands=4) > 0.8
    assert zero_one_test(x, bands=8) > 0.8


def test_removing_bands_keeps_regular_signals_regular():
    k = np.arange(1000)
    torus = np.cos(2 * np.pi * GOLDEN * k)
    for bands in (2, 3, 4, 8):
        assert zero_one_test(np.where(k % 2 == 0, 1.0, -1.0) + 0.3 * torus, bands=bands) < 0.2
        assert zero_one_test(np.tile([0.1, 0.7, 0.4], 334)[:1000], bands=bands) < 0.2
        assert zero_one_test(torus, bands=bands) < 0.2
    with pytest.raises(ValueError, match="bands = 0"):
        zero_one_test(torus, bands=0)
    with pytest.raises(ValueError, match="bands = 101"):
        zero_one_test(torus, bands=101)


def test_banded_chaos_with_a_positive_exponent_is_chaotic():
    """Rule 6 picks the bands (the period <= 8 of least mismatch) itself: the plain 0-1
    test no longer vetoes the exponent of banded chaos, and a banded torus stays
    quasi-periodic."""
    x = banded_logistic(1001)
    regime = classify_sequence(x, *one_impact_per_cycle(x[:-1]), exponent=0.09,
                               exponent_error=0.005)
    assert regime.regime == "chaotic"
    assert regime.evidence["zero_one_bands"] in (4, 8)
    assert regime.zero_one < 0.2 < 0.8 < regime.evidence["zero_one_banded"]
    k = np.arange(1001)
    torus = np.where(k % 2 == 0, 1.0, -1.0) + 0.3 * np.cos(2 * np.pi * GOLDEN * k)
    regime = classify_sequence(torus, *one_impact_per_cycle(torus[:-1]), exponent=0.0001,
                               exponent_error=0.001)
    assert regime.regime == "quasi-periodic"
    assert regime.evidence["zero_one_bands"] > 1
    assert max(regime.zero_one, regime.evidence["zero_one_banded"]) < 0.2


def test_rule_3_at_once_is_rule_3_period_by_period():
    """The convergence test of every period at once (one table of section distances)
    picks the period the definition does, P by P: the smallest P whose last
    max(2P, TAIL_MIN) pairs P apart are within tol, none where a P does not fit."""

    def by_definition(states, max_period, tol):
        scale, last = _scale(states), states.shape[0] - 1
        for p in range(1, max_period + 1):
            comparisons = max(2 * p, TAIL_MIN)
            if last < comparisons + p - 1:
                return None
            if _mismatch(states[last - comparisons - p + 1:], p, scale) < tol:
                return p
        return None

    rng = np.random.default_rng(8)
    found = 0
    for _ in range(3000):
        n, dim, period = rng.integers(3, 70), rng.integers(1, 13), rng.integers(1, 12)
        orbit = rng.normal(size=(period, dim))
        decay = np.exp(-rng.uniform(0.0, 0.3) * np.arange(n))[:, None]
        states = (orbit[np.arange(n) % period]
                  + 10.0 ** rng.uniform(-9, 0) * rng.normal(size=(n, dim)) * decay)
        max_period, tol = int(rng.integers(1, 20)), 10.0 ** rng.uniform(-6, -1)
        expected = by_definition(states, max_period, tol)
        assert _converged_period(states, max_period, tol) == expected
        found += expected is not None
    assert 300 < found < 2700  # both outcomes are exercised


@pytest.mark.parametrize("signal", ["chaotic", "offset noise", "quasi-periodic"])
def test_mean_square_displacement_by_fft_is_the_direct_sum(signal):
    """The 0-1 test's M_c(n) by prefix sums and an FFT autocorrelation equals the
    definition, mean_j |z(j + n) - z(j)|^2 summed directly, to 1e-12 of its size:
    also where |z| grows like sqrt(N) (chaos) or a mean makes it oscillate."""
    rng = np.random.default_rng(4)
    k = np.arange(1000)
    phi = {"chaotic": logistic(1000), "offset noise": 5.0 + rng.normal(size=1000),
           "quasi-periodic": np.cos(2 * np.pi * GOLDEN * k)}[signal]
    c = rng.uniform(math.pi / 5, 4 * math.pi / 5, size=30)
    z = np.cumsum(phi[None, :] * np.exp(1j * np.outer(c, k + 1)), axis=1)
    direct = np.array([[np.mean(np.abs(row[n:] - row[:-n]) ** 2) for n in range(1, 101)]
                       for row in z])
    fast = mean_square_displacement(z, 100)
    assert fast.shape == (30, 100)
    scale = np.max(np.abs(direct), axis=1, keepdims=True)
    assert np.max(np.abs(fast - direct) / scale) < 1e-12


# ================================================== weighted Birkhoff average
def test_birkhoff_average_converges_super_fast_on_a_torus_only():
    """On a circle rotation (a smooth observable of an irrational rotation, whose
    exact average is known) the two halves' weighted averages agree to near
    machine precision, and each equals the exact mean; on the logistic map's chaos
    and on noise they agree only to about the N^(-1/2) of a plain average."""
    n = np.arange(1000)
    angle = 2 * np.pi * GOLDEN * n
    torus = 0.4 + np.cos(angle) + 0.3 * np.sin(2 * angle + 1.0) + np.cos(angle) ** 3
    assert birkhoff_digits(torus) > 11
    half = np.arange(1, 501) / 501
    w = np.exp(-1.0 / (half * (1.0 - half)))
    assert abs(w @ torus[:500] / w.sum() - 0.4) < 1e-11  # cos^3 averages to 0 too
    plain = -math.log10(abs(torus[:500].mean() - torus[500:].mean()) / np.ptp(torus))
    assert plain < 6  # the plain average converges as 1/N on a torus, not faster
    assert birkhoff_digits(logistic(1000)) < 3.5
    noise = np.random.default_rng(2).normal(size=1000)
    assert birkhoff_digits(noise) < 3.5
    assert birkhoff_digits(np.full(50, 2.0)) == math.inf
    with pytest.raises(ValueError, match="at least 20"):
        birkhoff_digits(torus[:10])


@pytest.mark.parametrize("k, digits, expected", [
    (0.1, None, "quasi-periodic"),  # the 0-1 test alone
    (0.5, 7.0, "quasi-periodic"),  # the Birkhoff average alone
    (0.5, 3.0, "unresolved"),  # neither
    (0.9, 2.0, "unresolved"),  # a chaotic K with lambda consistent with zero
])
def test_quasi_periodicity_needs_a_zero_exponent_and_one_regular_test(k, digits, expected):
    """Rule 6: |lambda| <= 3 sigma and the record regular by the 0-1 test (K < 0.2) or by
    the weighted Birkhoff average (>= 5 digits); a positive exponent stays chaotic."""
    evidence = {} if digits is None else {"birkhoff_digits": digits}
    regime, confidence = _aperiodic_regime(0.001, 0.002, k, evidence)
    assert regime == expected
    assert (confidence > 0) == (expected != "unresolved")
    chaotic, _ = _aperiodic_regime(0.02, 0.002, 0.5, {"birkhoff_digits": 7.0})
    assert chaotic == "chaotic"


# ============================================================ scenes: physics
def test_fig3a_is_group_periodic_3_1_at_corners_c_f_c():
    """Paper Fig. 3(a), T/T_Ax = 0.70: three impacts per cycle, corners C, F, C."""
    regime = classify(load_preset("fig3a"))
    assert regime.regime == "group-periodic"
    assert (regime.impacts_per_period, regime.period_cycles) == (3, 1)
    first, second, third = regime.corner_sequence
    assert first == third != "face"
    assert second[0] != first[0]  # the middle impact is at the other tower's corner
    assert regime.strobe_mismatch < 1e-2 * regime.evidence["tol"]
    assert regime.evidence["rtol"] <= 1e-8  # the classification tightened rtol 1e-6
    assert 40 <= regime.transient_used < 2000


def test_group_periodicity_does_not_depend_on_the_section_phase():
    """Same orbit seen from another section phase: same n-P, corners rotated."""
    base = classify(load_preset("fig3a"))
    shifted = classify(load_preset("fig3a").with_params(phase=0.7))
    assert shifted.label == base.label
    sequence = base.corner_sequence
    rotations = [sequence[i:] + sequence[:i] for i in range(len(sequence))]
    assert shifted.corner_sequence in rotations
    assert shifted.corner_sequence != sequence  # the impact at phase 0.72 now comes first


def test_fig4_periodic_and_impact_free_points():
    """T/T_Ax = 1.3 pounds once per cycle; at 1.5 the steady response is periodic but
    never touches (relative amplitude 0.55 < gap): docs/model.md 12 calls it 'none'."""
    pounding = classify(load_preset("fig4").with_params(period_ratio=1.3))
    assert pounding.label == "periodic 1-1"
    free = classify(load_preset("fig4").with_params(period_ratio=1.5))
    assert free.regime == "none"
    assert free.period_cycles == 1
    assert free.strobe_mismatch < free.evidence["tol"]


def test_fig4_at_0_9_is_chaotic():
    """Largest exponent about +0.09 +- 0.01 per unit time, K near 1."""
    regime = classify(load_preset("fig4").with_params(period_ratio=0.9))
    assert regime.regime == "chaotic"
    assert regime.period_cycles is None
    assert regime.max_exponent > 3 * regime.max_exponent_error
    assert abs(regime.max_exponent - 0.09) < 3 * regime.max_exponent_error + 0.01
    assert regime.zero_one > 0.8
    assert regime.evidence["birkhoff_digits"] < 5  # chaos: the averages converge as N^(-1/2)
    assert regime.strobe_mismatch > 1e3 * regime.evidence["tol"]
    assert regime.transient_used == 2000  # never converged
    from chaospound.cli.classify import _classify_report

    [row] = [line for line in _classify_report(load_preset("fig4"), regime, None).splitlines()
             if "Birkhoff average" in line]
    assert f"{regime.evidence['birkhoff_digits']:.1f} digits (regular at >= 5)" in row


@pytest.mark.parametrize(("period_ratio", "label"), [(0.7, "periodic 1-1"), (1.3, "periodic 1-2")])
def test_translational_pounding_is_not_group_periodic(period_ratio, label):
    """The pair model (no torsion): periodic face impacts, not groups (the paper, 3.2)."""
    regime = classify(load_preset("fig4-translational").with_params(period_ratio=period_ratio))
    assert regime.evidence["model"] == "pair"
    assert regime.regime != "group-periodic"
    assert regime.label == label
    assert set(regime.corner_sequence) == {"face"}


def test_a_slow_approach_to_a_stable_orbit_is_periodic_not_a_torus():
    """fig4-translational at T/T_Ax 0.7458 (a point of the 1000-point scan). After the
    2000-cycle transient the sections repeat at P = 16 only to some 5e-3, the exponent
    over 200 cycles is zero within its error and the 0-1 test is regular: rules 1-6
    read a torus (quasi-periodic with confidence 1, before rule 6b). The record closes
    in on a stable period-16 orbit, its multipliers a complex pair at |mu| = 0.94, which
    rule 6b names. Checked without Newton: a plain run at rtol 1e-11 from where a
    2000-cycle transient at rtol 1e-8 ends settles on period 16 with 19 impacts per
    period by itself (the rtol 1e-8 runs cannot show it: their noise keeps so weakly
    stable an orbit's mismatch near tol)."""
    from chaospound.simulate import simulate

    scene = load_preset("fig4-translational").with_params(period_ratio=0.7458458458458459)
    regime = classify(scene)
    assert regime.label == "group-periodic 19-16"
    assert regime.evidence["reached_by"] == "newton"
    approach = regime.evidence["approach"]
    assert approach["label"] == "quasi-periodic"  # rules 1-6
    assert approach["period"] == 16
    assert approach["distance_last_quarter"] < 0.5 * approach["distance_first_quarter"]
    assert regime.floquet_exact
    assert 0.93 < max(abs(z) for z in regime.floquet_multipliers) < 0.95
    assert regime.transient_used > 2000
    from chaospound.cli.classify import _classify_report

    assert "Newton at P = 16: the record closed in on the orbit" in _classify_report(
        scene, regime, None)
    # independent of Newton: plain integration, tight enough to converge by itself
    loose = simulate(scene.with_params(rtol=1e-8, atol=1e-10), transient=2000, record=1)
    tight = simulate(scene.with_params(rtol=1e-11, atol=1e-13), transient=2000, record=48,
                     initial_state=loose.strobe.state[-1], start_at_section=True)
    states = tight.strobe.state
    assert _mismatch(states, 16, _scale(states)) < 0.1 * DEFAULT_TOL
    assert min(_mismatch(states, p, _scale(states)) for p in range(1, 16)) > 1e3 * DEFAULT_TOL
    assert len(tight.impacts) == 3 * 19


def test_a_slow_alternating_approach_to_a_period_1_orbit_is_period_1():
    """fig4 at T/T_Ax 0.4497 (a point of the 1000-point scan), just before a period
    doubling: the period-1 orbit's multiplier is -0.9946, so the sections alternate
    about it while they close in, and after 900 cycles they repeat at P = 2 within
    tol / 10 but not at P = 1 (rule 3 reads group-periodic 4-2). Newton at P = 2 lands
    on the period-1 orbit, which rule 8b names. Checked without Newton: a plain run of
    3000 cycles at rtol 1e-11 from where the record ends repeats at P = 1."""
    from chaospound.cli.classify import _classify_report
    from chaospound.simulate import simulate

    scene = load_preset("fig4").with_params(period_ratio=0.44974974974974974)
    regime = classify(scene)
    assert regime.label == "group-periodic 2-1"
    assert regime.evidence["reached_by"] == "newton"
    approach = regime.evidence["approach"]
    assert approach["label"] == "group-periodic 4-2" and approach["orbit_period"] == 1
    assert regime.floquet_exact
    assert 0.99 < max(abs(z) for z in regime.floquet_multipliers) < 1.0
    assert "found an orbit of period 1" in _classify_report(scene, regime, None)
    # independent of Newton: the approach, run on, repeats at P = 1
    loose = simulate(scene.with_params(rtol=1e-8, atol=1e-10), transient=900, record=1)
    tight = simulate(scene.with_params(rtol=1e-11, atol=1e-13), transient=3000, record=8,
                     initial_state=loose.strobe.state[-1], start_at_section=True)
    states = tight.strobe.state
    assert _mismatch(states, 1, _scale(states)) < 0.1 * DEFAULT_TOL
    assert len(tight.impacts) == 2 * 8
    # and 900 cycles are not enough for it: P = 2 repeats there, P = 1 does not
    early = simulate(scene.with_params(rtol=1e-8, atol=1e-10), transient=880, record=20)
    s = early.strobe.state
    assert _mismatch(s, 1, _scale(s)) > 10 * DEFAULT_TOL
    assert _mismatch(s, 2, _scale(s)) < 0.2 * DEFAULT_TOL


def test_a_torus_near_a_resonance_stays_a_torus():
    """fig4 at T/T_Ax 1.0539, a torus (tests/test_converged.py): its sections come
    within 1e-2 of period 5, so rule 6b tries Newton there, and finds no orbit that
    the record approaches; the label stays quasi-periodic and the evidence says what
    was tried."""
    regime = classify(load_preset("fig4").with_params(period_ratio=1.0539))
    assert regime.regime == "quasi-periodic"
    assert "reached_by" not in regime.evidence
    approach = regime.evidence["approach"]
    assert approach["period"] == 5
    assert approach["result"] != "approached"


def test_system_and_scene_give_the_same_regime():
    scene = load_preset("fig4").with_params(period_ratio=1.3)
    assert classify(System.from_scene(scene)).label == classify(scene).label


def test_classify_rejects_bad_arguments():
    scene = load_preset("fig3a")
    with pytest.raises(ValueError, match="max_transient"):
        classify(scene, min_transient=50, max_transient=10)
    with pytest.raises(ValueError, match="window"):
        classify(scene, window=10, max_period=16)
    with pytest.raises(ValueError, match="no impacts to classify"):
        classify(duffing())


def test_regime_json_and_label():
    regime = Regime("group-periodic", impacts_per_period=3, period_cycles=1,
                    corner_sequence=["A+", "B-", "A+"], strobe_mismatch=1e-8, confidence=1.0)
    assert regime.label == "group-periodic 3-1"
    assert json.loads(json.dumps(regime.to_json_dict()))["label"] == "group-periodic 3-1"
    assert Regime("chaotic").label == "chaotic"
    assert set(REGIMES) >= {"none", "unresolved"}
    with pytest.raises(ValueError, match="regime"):
        Regime("weird")


# ====================================================================== CLI
def test_cli_classify_json(capsys):
    code = main(["classify", "--preset", "fig3a", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    document = json.loads(out)
    assert JSON_KEYS <= set(document)
    assert document["label"] == "group-periodic 3-1"
    assert document["model"] == "towers"
    assert document["scene"]["name"] == "fig3a"


def test_cli_classify_report_and_plot(capsys, tmp_path: Path):
    figure = tmp_path / "fig3a.png"
    code = main(["classify", "--preset", "fig3a", "--plot", str(figure)])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "group-periodic 3-1" in out and "A+ B- A+" in out
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "options",
    [
        ["--preset", "nosuch"],
        ["--preset", "fig3a", "--set", "gap=-1"],
        ["--preset", "fig3a", "--max-transient", "10"],
        ["--preset", "fig3a", "--window", "5"],
        ["--preset", "fig3a", "--record", "8"],
        ["--preset", "fig3a", "--max-period", "x"],
    ],
)
def test_cli_classify_bad_input_is_one_line_exit_2(capsys, options):
    code = main(["classify", *options])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert len(err.splitlines()) == 1 and err.startswith("chaospound: error: ")
    if "--window" in options:  # in the options' words, with the bound
        assert "--window 5: must be at least twice --max-period (16), >= 32" in err


@pytest.mark.parametrize(("extra", "zero_one", "expected"), [
    ({"zero_one_bands": 2, "zero_one_banded": 0.997}, 0.093,
     "0.093; 0.997 less the means of 2 bands"),
    ({"sections": 4001, "zero_one_vetoed": 0.149}, 0.363,
     "0.363 (over 4001 sections; 0.149 over the first 1001"),
])
def test_cli_report_gives_the_zero_one_tests_of_rule_6(extra, zero_one, expected):
    """The report's 0-1 row gives the band-corrected K beside the plain one, and, where
    a 0-1 test that vetoed a positive exponent over 1001 sections was rerun over 4001,
    both Ks and the record's length (rule 6)."""
    from chaospound.cli.classify import _classify_report

    evidence = {"tol": 1e-5, "best_period": 2, "rtol": 1e-8, "atol": 1e-10, "model": "towers",
                "window_cycles": 64, **extra}
    regime = Regime("chaotic", strobe_mismatch=0.13, max_exponent=0.035,
                    max_exponent_error=0.003, zero_one=zero_one, confidence=0.9,
                    evidence=evidence)
    [row] = [line for line in _classify_report(load_preset("fig4"), regime, None).splitlines()
             if "0-1 test K" in line]
    assert expected in row
