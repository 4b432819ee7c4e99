"""The converged classification (chaospound.dynamics.converged), the sweep default.

Checked against known answers (the paper's fig3a group-periodic 3-1, chaos of
fig4 at T/T_Ax = 0.9, the wall model's two periodic branches, a period-doubling
cascade, the torus of a forced self-excited oscillator), against the
careful adaptive classifier (an independent procedure: long transients, no
Newton), against Newton's orbit itself (the stored record repeats to within
the classification's tol), and for the warm starts of continuation: a scan
run forward, backward and from fresh starts names every point alike where the
attractor is unique.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp

from chaospound import custom_system
from chaospound.dynamics.classify import (
    DEFAULT_TOL,
    _classification_system,
    classify,
    length_weights,
)
from chaospound.dynamics.converged import (
    BATCH_FROM,
    CHAOS_WATCH,
    EXPONENT_RTOL,
    MIN_WINDOW,
    WATCH_CHUNK,
    ZERO_ONE_CYCLES,
    _exponent_system,
    _mean_and_error,
    classify_converged,
)
from chaospound.dynamics.system import advance, as_system
from chaospound.scene import load_preset
from chaospound.simulate import simulate
from chaospound.store import open_sweep
from chaospound.sweep import SweepSpec, parse_axis, run_sweep

FIG4 = load_preset("fig4")
WALL = load_preset("wall").with_params(gap=5.0)


def labels(sweep, branch):
    return list(zip(sweep.regimes(branch), sweep.array("period_cycles", branch).tolist(),
                    sweep.array("impacts_per_period", branch).tolist(), strict=True))


def test_fig3a_is_group_periodic_3_1_confirmed_by_newton():
    scene = load_preset("fig3a")
    result = classify_converged(scene)
    regime = result.regime
    assert regime.label == "group-periodic 3-1"
    assert regime.evidence["confirmed_by"] == "newton"
    assert regime.evidence["orbit_residual"] < 1e-7
    assert regime.evidence["max_multiplier"] < 1.0  # the orbit is an attractor
    assert regime.confidence > 0.9
    # the record read is the orbit: a period-1 section repeats to well within tol
    states = result.record.strobe.state * length_weights(scene, result.record.state_names)
    scale = np.max(np.linalg.norm(states, axis=1))
    assert np.max(np.linalg.norm(np.diff(states, axis=0), axis=1)) / scale < DEFAULT_TOL / 10
    # the careful classifier, from rest with its own long transient, agrees
    careful = classify(scene)
    assert careful.label == regime.label
    assert regime.corner_sequence == careful.corner_sequence


def test_fig4_at_0_9_is_chaotic_by_more_than_three_sigma():
    regime = classify_converged(FIG4.with_params(period_ratio=0.9)).regime
    assert regime.regime == "chaotic"
    assert regime.max_exponent > 3 * regime.max_exponent_error > 0
    assert regime.period_cycles is None
    assert regime.evidence["decided_by"] == "exponent"
    # a chaotic reading must last CHAOS_WATCH cycles (far below the careful classifier's
    # 2000): the watch's last run ends there
    assert CHAOS_WATCH <= regime.transient_used < CHAOS_WATCH + WATCH_CHUNK


@pytest.mark.parametrize(("period_ratio", "label"), [(1.207007007007007, "group-periodic 7-2"),
                                                     (1.1695695695695696, "group-periodic 32-10")])
def test_a_chaotic_transient_is_the_orbit_it_settles_on(period_ratio, label):
    """fig4 at these T/T_Ax reads chaotic for a few hundred cycles (its exponent clears
    4 sigma within 300), then settles on a stable group-periodic orbit (after 440 and
    560 cycles from rest: the careful classifier's transients). Watching the sections
    until CHAOS_WATCH cycles finds the orbit, which Newton confirms with its multipliers;
    without the watch the point was labelled chaotic."""
    scene = FIG4.with_params(period_ratio=period_ratio)
    regime = classify_converged(scene).regime
    assert regime.label == label
    assert regime.evidence["confirmed_by"] == "newton"
    assert regime.evidence["max_multiplier"] < 1.0
    assert regime.evidence["exponent_stages"][0]["decision"].startswith("chaotic transient")
    assert regime.transient_used < CHAOS_WATCH
    assert classify(scene).label == label  # the careful classifier, its own 6000 cycles


def exponent_blocks(system, state, cycles: int, block: int = 10) -> np.ndarray:
    """Largest-exponent estimates over consecutive blocks of ``block`` cycles."""
    n = system.dim
    augmented = np.zeros(2 * n)
    augmented[:n], augmented[n] = state, 1.0
    augmented, _, _ = advance(system, augmented, 10, tangent="qr",
                              tangent_log=np.zeros((0, 1)), record_from=10)  # alignment
    log = np.zeros((cycles, 1))
    advance(system, augmented, cycles, tangent="qr", tangent_log=log, record_from=0)
    return log[:, 0].reshape(-1, block).sum(axis=1) / (block * system.period)


@pytest.mark.parametrize("period_ratio", [0.9, 1.0])
def test_the_exponent_at_exponent_rtol_is_the_exponent_at_the_classification_rtol(
        period_ratio):
    """The exponent stage runs at EXPONENT_RTOL (1e-6), not the classification's 1e-8:
    on fig4's chaotic attractor the two estimates, from the same section, differ by
    less than three standard errors of their difference, and both are positive by more
    than three of their own."""
    tight, rtol, _ = _classification_system(as_system(FIG4.with_params(
        period_ratio=period_ratio)))
    loose = _exponent_system(tight, rtol)
    assert (rtol, loose.rtol, loose.atol) == (1e-8, EXPONENT_RTOL, 1e-2 * EXPONENT_RTOL)
    state = simulate(tight, transient=200, record=1).strobe.state[-1]
    estimates = []
    for system in (tight, loose):
        blocks = exponent_blocks(system, state, 400)
        estimates.append((blocks.mean(), blocks.std(ddof=1) / math.sqrt(blocks.size)))
    (lam_t, err_t), (lam_l, err_l) = estimates
    assert lam_t > 3 * err_t and lam_l > 3 * err_l
    assert abs(lam_t - lam_l) < 3 * math.hypot(err_t, err_l)


@pytest.mark.parametrize("period_ratio", [1.0487, 1.0913])
def test_a_transient_ending_during_the_exponent_is_confirmed_there(period_ratio):
    """fig4 near the resonance: the sections wander for hundreds of cycles (the
    exponent's blocks start), then settle on a stable orbit. The blocks' sections are
    watched, so Newton confirms the orbit there, well before the exponent's cap and a
    0-1 record; the careful classifier, waiting for the sections to converge, finds the
    same orbit after a longer transient."""
    point = FIG4.with_params(period_ratio=period_ratio)
    regime = classify_converged(point).regime
    decisions = [stage.get("decision") for stage in regime.evidence["exponent_stages"]]
    assert decisions[-1] == "a period came in sight and was confirmed"
    assert regime.evidence["confirmed_by"] == "newton"
    assert regime.regime == "group-periodic"
    careful = classify(point)
    assert regime.label == careful.label
    assert regime.transient_used < careful.transient_used


@pytest.mark.parametrize("rho", [0.0, 0.8])
def test_the_exponent_error_widens_for_correlated_blocks(rho):
    """The standard error of the block exponents' mean against its true spread over
    3000 AR(1) series of 30 blocks: independent blocks keep the plain std / sqrt(N)
    (within 10 %); blocks with lag-1 correlation 0.8 (a torus's drift) get an error at
    least twice the plain one's, closer to the truth it understates threefold."""
    rng = np.random.default_rng(3)
    noise = rng.normal(size=(3000, 130))
    series = np.zeros_like(noise)
    for i in range(1, series.shape[1]):
        series[:, i] = rho * series[:, i - 1] + noise[:, i]
    series = series[:, 100:]
    truth = series.mean(axis=1).std()
    widened = np.median([_mean_and_error(list(row))[1] for row in series]) / truth
    plain = np.median(series.std(axis=1, ddof=1)) / math.sqrt(series.shape[1]) / truth
    if rho == 0.0:
        assert 0.9 < widened < 1.1 and 0.9 < plain < 1.1
    else:
        assert plain < 0.4 and widened > 2.0 * plain and widened < 1.0


@pytest.mark.parametrize(("kind", "low", "high"), [
    ("independent", 0.9, 1.15), ("telescoping", 1.0, 2.5), ("drifting", 0.7, 1.0)])
def test_the_exponent_error_of_many_blocks_is_that_of_their_batch_means(kind, low, high):
    """From BATCH_FROM blocks the error comes from batch means. Over 2000 series of 120
    blocks, against the true spread of their mean: independent blocks keep it (the
    plain std / sqrt(N) too); telescoping blocks, e_j - e_(j-1) plus a little noise
    (an impact's stretching, then the contraction after it, in neighbouring blocks),
    get an error within 2.5 times the truth where the plain one is 6 times it; AR(1)
    blocks with rho = 0.8 (a drift) keep most of the widening the plain error lacks
    (it is 0.32 of the truth)."""
    assert BATCH_FROM <= 120
    rng = np.random.default_rng(5)
    if kind == "independent":
        series = rng.normal(size=(2000, 120))
    elif kind == "telescoping":
        e = rng.normal(size=(2000, 121))
        series = e[:, 1:] - e[:, :-1] + 0.2 * rng.normal(size=(2000, 120))
    else:
        noise = rng.normal(size=(2000, 220))
        series = np.zeros_like(noise)
        for i in range(1, series.shape[1]):
            series[:, i] = 0.8 * series[:, i - 1] + noise[:, i]
        series = series[:, 100:]
    truth = series.mean(axis=1).std()
    error = np.median([_mean_and_error(list(row))[1] for row in series]) / truth
    plain = np.median(series.std(axis=1, ddof=1)) / math.sqrt(series.shape[1]) / truth
    assert low < error < high
    if kind == "telescoping":
        assert plain > 5.0
    if kind == "drifting":
        assert plain < 0.4


def test_weak_chaos_at_the_edge_of_the_budget_is_named_chaotic():
    """fig4 at T/T_Ax 0.4600 (a point of the 1000-point scan): an exponent of about
    0.006 over 1200 cycles of 10-cycle blocks, whose plain standard error (0.0035, 1.7
    sigma) left the point unresolved; the batch means' error crosses 3 sigma and the
    point is chaotic, as the agreement benchmark's careful classify names it after a
    6000-cycle transient and 1600 cycles of exponent (0.0057 +- 0.0019, its 0-1 test
    K 0.97)."""
    point = FIG4.with_params(period_ratio=0.45995995995996)
    regime = classify_converged(point).regime
    assert regime.regime == "chaotic"
    assert regime.max_exponent > 3 * regime.max_exponent_error
    careful = classify(point, max_transient=6000, lyapunov_cycles=400)  # the agreement's
    assert careful.regime == "chaotic"
    spread = math.hypot(careful.max_exponent_error, regime.max_exponent_error)
    assert abs(careful.max_exponent - regime.max_exponent) < 3 * spread


def test_a_torus_whose_block_exponents_drift_together_is_not_chaotic():
    """fig4 at T/T_Ax 1.0539: a torus whose 10-cycle block exponents swing slowly
    (positive for dozens of blocks, then negative); the plain standard error of their
    mean put lambda = 0.002 at 4.4 sigma after 5 blocks and the point was named
    chaotic. With the correlation's widening it is quasi-periodic, as classify finds
    after its 2000-cycle transient."""
    point = FIG4.with_params(period_ratio=1.0539)
    regime = classify_converged(point).regime
    assert regime.regime == "quasi-periodic"
    assert abs(regime.max_exponent) < 3 * regime.max_exponent_error
    assert classify(point).regime == "quasi-periodic"


@pytest.mark.parametrize("period_ratio", [0.9398398398398398, 1.1508508508508508])
def test_weak_chaos_whose_exponent_leans_positive_is_not_a_torus(period_ratio):
    """Points of the 1000-point fig4 scan with a largest exponent of about 0.008,
    1 to 3 standard errors above zero after the 300-cycle cap, and a plain 0-1 test
    under 0.2 (its 1000 sections are a few dozen Lyapunov times): rule 6 read them
    quasi-periodic. The exponent now goes on (as classify's rerun near the 3-sigma
    line) and crosses 3 sigma: chaotic, as classify names them after a 6000-cycle
    transient and 1600 cycles of exponent. The two exponents, measured on different
    stretches of the attractor, agree within 3 standard errors of their difference
    (0.0069 +- 0.0017 and 0.0110 +- 0.0033 at 0.9398)."""
    point = FIG4.with_params(period_ratio=period_ratio)
    regime = classify_converged(point).regime
    stages = regime.evidence["exponent_stages"]
    assert stages[0]["cycles"] == 300 and 1.0 < stages[0]["exponent_over_error"] < 3.0
    assert "over 1 sigma" in stages[-1]["decision"]
    assert regime.regime == "chaotic"
    assert regime.max_exponent > 3 * regime.max_exponent_error
    careful = classify(point, max_transient=6000)
    assert careful.regime == "chaotic"
    spread = math.hypot(careful.max_exponent_error, regime.max_exponent_error)
    assert abs(careful.max_exponent - regime.max_exponent) < 3 * spread


def test_a_positive_exponent_is_not_vetoed_by_too_short_a_zero_one_record():
    """fig4 at gap 1.4573, T/T_Ax 0.7357 (a point of the 200 x 200 map): weak chaos,
    an exponent of about 0.006 per unit t (0.028 a cycle) several standard errors
    above zero, but K = 0.10 to 0.18 over 1000 sections, whose veto left the point
    unresolved in both classifications (the converged one first read it
    quasi-periodic). The 0-1 test needs more Lyapunov times: over 4000 sections K
    is 0.36 (0.83 over 16000), and both name it chaotic."""
    point = FIG4.with_params(gap=1.457286432160804, period_ratio=0.735678391959799)
    fast = classify_converged(point)
    careful = classify(point, max_transient=6000)
    for regime in (fast.regime, careful):
        assert regime.evidence["zero_one_vetoed"] < 0.2
        assert regime.evidence["sections"] == 4 * ZERO_ONE_CYCLES + 1
        assert regime.zero_one >= 0.2
        assert regime.regime == "chaotic"
        assert regime.max_exponent > 3 * regime.max_exponent_error
    # the stored record is the one read: its 4001 sections, the last cycles' impacts
    assert fast.record.strobe.state.shape[0] == 4 * ZERO_ONE_CYCLES + 1
    assert np.all(np.diff(fast.record.strobe.cycle) == 1)
    assert np.all(fast.record.impacts.cycle >= 4 * ZERO_ONE_CYCLES - MIN_WINDOW)
    assert np.array_equal(fast.final_state, fast.record.strobe.state[-1])


def test_the_zero_one_record_keeps_its_sections_and_the_last_impacts():
    """A label read by the 0-1 test (the torus at T/T_Ax 1.0539) stores the record's
    1001 sections and the impacts of its last ``record`` cycles only, on the record's
    own clock: each impact lies in the cycle it is counted in, between that cycle's
    sections, at the phase the impact's time gives."""
    result = classify_converged(FIG4.with_params(period_ratio=1.0539))
    record, regime = result.record, result.regime
    assert regime.evidence["decided_by"] == "exponent and 0-1 test"
    assert record.strobe.state.shape[0] == ZERO_ONE_CYCLES + 1 == record.record + 1
    np.testing.assert_array_equal(record.strobe.cycle, np.arange(ZERO_ONE_CYCLES + 1))
    np.testing.assert_array_equal(result.final_state, record.strobe.state[-1])
    imp = record.impacts
    window = MIN_WINDOW
    assert len(imp) > 0 and imp.cycle.min() >= ZERO_ONE_CYCLES - window
    start = record.strobe.time[imp.cycle]
    assert np.all((start <= imp.time) & (imp.time < start + record.period))


def test_a_zero_one_record_that_repeats_keeps_all_its_impacts():
    """Where the sections repeat within tol (rule 4 then reads the impacts of the
    whole window), the 0-1 record is recorded with every impact: on fig3a's 3-1 orbit,
    three a cycle over all 1000 cycles."""
    from chaospound.dynamics.converged import _Classifier

    point = load_preset("fig3a")
    orbit = classify_converged(point)
    classifier = _Classifier(point, 16, 2000, None, True)
    record = classifier._zero_one_record(orbit.final_state)
    assert len(record.impacts) == 3 * ZERO_ONE_CYCLES
    assert record.impacts.cycle.min() == 0 and record.impacts.cycle.max() == ZERO_ONE_CYCLES - 1


def test_wall_branches_none_and_periodic_1_1_coexist():
    """wall, gap 5: between T/T_Ax 0.575 and 0.875 the rest state's branch has no
    impact while the impacting 1-1 orbit (reached from a state on it) is stable too."""
    point = WALL.with_params(period_ratio=0.7)
    rest = classify_converged(point).regime
    assert rest.label == "none" and rest.period_cycles == 1
    impacting = classify_converged(WALL.with_params(period_ratio=0.95))
    assert impacting.regime.label == "periodic 1-1"
    # continue the impacting orbit down to 0.7 in steps: it stays periodic 1-1
    state = impacting.final_state
    for ratio in (0.9, 0.85, 0.8, 0.75, 0.7):
        result = classify_converged(WALL.with_params(period_ratio=ratio), start_state=state)
        assert result.regime.label == "periodic 1-1", ratio
        assert result.regime.evidence["max_multiplier"] < 1.0
        state = result.final_state
    assert len(result.record.impacts) == result.record.record  # one impact a cycle


@pytest.mark.parametrize("preset, grid, regime", [
    ("fig4-translational", "period_ratio=0.45:0.65#5", "periodic"),
    # 0.745, just below the chaotic band, is not such a point: its label there depends
    # on the path (group-periodic 5-14 or chaotic), and the last bit of any sum decides
    ("fig4", "period_ratio=0.705:0.735#4", "group-periodic"),
])
def test_warm_starts_change_nothing_where_the_attractor_is_unique(tmp_path, preset, grid,
                                                                  regime):
    """A short scan forward, backward (each point warm-started from the one before) and
    from fresh starts (the default) names every point alike, and ends on the same
    orbit."""
    scene = load_preset(preset)
    axis = parse_axis(grid, scene)
    run_sweep(scene, SweepSpec(axes=(axis,), continuation="both"), tmp_path / "both.h5",
              progress=False)
    run_sweep(scene, SweepSpec(axes=(axis,)), tmp_path / "fresh.h5", progress=False)
    both, fresh = open_sweep(tmp_path / "both.h5"), open_sweep(tmp_path / "fresh.h5")
    assert labels(both, "forward") == labels(both, "backward") == labels(fresh, "fresh")
    assert set(fresh.regimes()) == {regime}
    for branch in ("forward", "backward"):
        np.testing.assert_allclose(both.array("final_state", branch),
                                   fresh.array("final_state"), rtol=0, atol=1e-4)


@pytest.mark.parametrize(("period_ratio", "period"), [(1.597, 1), (1.608, 2), (1.6161, 4),
                                                     (1.6170, 8)])
def test_a_period_doubling_cascade_is_named_period_by_period(period_ratio, period):
    """The wall model at gap 0.5 doubles its two-impact period-1 orbit at T/T_Ax ~1.601,
    again at ~1.615 and ~1.6165, and is chaotic from ~1.6172 (a 0.0002-step scan): in
    each window both classifications name the period, with twice as many impacts as the
    window before, and Newton's orbit confirms it, every multiplier inside the unit
    circle."""
    scene = load_preset("wall").with_params(gap=0.5, period_ratio=period_ratio)
    fast = classify_converged(scene).regime
    careful = classify(scene)
    for regime in (fast, careful):
        assert regime.regime == "group-periodic"
        assert (regime.period_cycles, regime.impacts_per_period) == (period, 2 * period)
    assert fast.evidence["confirmed_by"] == "newton"
    assert fast.evidence["max_multiplier"] < 1.0
    assert fast.corner_sequence == careful.corner_sequence


# ---------------------------------------- a torus: van der Pol forced against a wall
WALL_VDP = 1.8  #: the wall's position; the free limit cycle reaches x ~ 2


@njit
def vdp_rhs(t, y, q, out):
    """x'' - mu (1 - x^2) x' + x + beta (x - wall)^(3/2)_+ = a cos(omega t)."""
    mu, a, omega, wall, beta = q[0], q[1], q[2], q[3], q[4]
    d = y[0] - wall
    force = beta * d * math.sqrt(d) if d > 0.0 else 0.0
    out[0] = y[1]
    out[1] = mu * (1.0 - y[0] * y[0]) * y[1] - y[0] - force + a * math.cos(omega * t)


@njit
def vdp_jacobian(t, y, q, jac):
    mu, beta, d = q[0], q[4], y[0] - q[3]
    stiffness = 1.5 * beta * math.sqrt(d) if d > 0.0 else 0.0
    jac[0, 0] = 0.0
    jac[0, 1] = 1.0
    jac[1, 0] = -2.0 * mu * y[0] * y[1] - 1.0 - stiffness
    jac[1, 1] = mu * (1.0 - y[0] * y[0])


@njit
def vdp_gap(t, y, q):
    return q[3] - y[0], -y[1]


def free_period(mu: float, beta: float) -> float:
    """Period of the unforced oscillator's limit cycle against the wall, by scipy (an
    independent integrator): the time between upward zero crossings of x."""
    out = np.zeros(2)

    def f(t, y):
        vdp_rhs(t, y, np.array([mu, 0.0, 1.0, WALL_VDP, beta]), out)
        return out.copy()

    def up(t, y):
        return y[0]

    up.direction = 1.0
    run = solve_ivp(f, (0.0, 400.0), [0.5, 0.0], events=up, rtol=1e-11, atol=1e-12)
    crossings = run.t_events[0][-10:]
    return float(np.mean(np.diff(crossings)))


def test_a_forced_self_excited_oscillator_has_a_quasi_periodic_torus():
    """A van der Pol oscillator (mu 0.5) pounding on a wall, forced weakly (a = 0.1) at
    1.6 times its own frequency: no locking, the response fills a torus. Both
    classifications call it quasi-periodic (exponent zero within its error: the phase
    of the self-oscillation is neutral), and the sections turn about the origin by the
    rotation number of the free limit cycle, T / T0 mod 1, to within the forcing's
    pull."""
    q = {"mu": 0.5, "a": 0.1, "omega": 1.6, "wall": WALL_VDP, "beta": 50.0}
    system = custom_system(vdp_rhs, vdp_jacobian, vdp_gap, params=q,
                           period=lambda v: 2 * math.pi / v["omega"], initial_state=(0.5, 0.0),
                           state_names=("x", "dx"), name="forced van der Pol")
    fast = classify_converged(system)
    careful = classify(system)
    for regime in (fast.regime, careful):
        assert regime.regime == "quasi-periodic"
        assert abs(regime.max_exponent) <= 3 * regime.max_exponent_error
        assert regime.zero_one < 0.2 or regime.evidence["birkhoff_digits"] >= 5
    assert careful.evidence["birkhoff_digits"] >= 5  # a smooth torus: super-convergence
    sections = fast.record.strobe.state
    turns = np.diff(np.unwrap(np.arctan2(sections[:, 1], sections[:, 0]))) / (2 * np.pi)
    # the phase point turns clockwise in (x, x'): by -T / T0 turns per section, which
    # np.unwrap sees as the shorter +(1 - T / T0 mod 1); measured 0.65929 against 0.65937
    rotation = (-np.mean(turns)) % 1.0
    expected = (2 * math.pi / q["omega"] / free_period(q["mu"], q["beta"])) % 1.0
    assert abs(rotation - expected) < 2e-3


def test_a_budget_too_short_says_why():
    regime = classify_converged(FIG4.with_params(period_ratio=0.9), max_transient=30).regime
    assert regime.regime == "unresolved" and regime.confidence == 0.0
    assert "within 30 cycles" in regime.evidence["why"]


def test_the_sweep_default_is_converged_and_paper_is_the_window():
    axis = (parse_axis("period_ratio=0.9,1.0"),)
    assert SweepSpec(axes=axis).classify == "converged"
    assert SweepSpec(axes=axis, classify="paper").classify == "window"
    with pytest.raises(ValueError, match="converged, paper, window, full"):
        SweepSpec(axes=axis, classify="fast")
