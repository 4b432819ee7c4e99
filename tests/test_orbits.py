"""Periodic orbits, Floquet multipliers, continuation and bifurcation points (issue 16).

Every test checks physics against an independent account: the closed-form
steady response of the damped linear oscillators, long forward integration,
the QR Lyapunov exponents, the trace identity of the Jacobian, and brute-force
up/down sweeps run by the sweep machinery (or by forward integration for the
Duffing oscillator).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from chaospound.cli import main
from chaospound.dynamics.classify import classify
from chaospound.dynamics.lyapunov import _constant_trace, lyapunov_spectrum
from chaospound.dynamics.system import advance, duffing
from chaospound.orbits import (
    OrbitNotFound,
    StroboscopicMap,
    find_orbit,
    finite_difference_monodromy,
    orbit_trajectory,
)
from chaospound.orbits.continuation import continue_branch, switch_period_doubling
from chaospound.orbits.floquet import response_floquet, spectrum_floquet
from chaospound.orbits.grazing import clearance_minima, free_flight_clearance
from chaospound.orbits.shooting import ORBIT_TOL, newton_fixed_point, orbit_at
from chaospound.orbits.store import open_branches, write_branches
from chaospound.scene import load_preset
from chaospound.simulate import simulate
from chaospound.store import open_sweep

FIG3A = load_preset("fig3a")
WALL_GAP5 = load_preset("wall").with_params(gap=5)


# ------------------------------------------------------------------ helpers
def linear_response(omega: float, zeta: float, w: float) -> tuple[float, float]:
    """Steady (X, X') at t = 0 of X'' + 2 zeta Om (X' - u') + Om^2 (X - u) = 0, u = sin(w t).

    The forcing 2 zeta Om u' + Om^2 u = Re[(2 zeta Om w - i Om^2) e^{iwt}], so
    X = Re[C e^{iwt}] with C = (2 zeta Om w - i Om^2) / (Om^2 - w^2 + 2 i zeta Om w).
    """
    c = (2 * zeta * omega * w - 1j * omega**2) / (omega**2 - w**2 + 2j * zeta * omega * w)
    return c.real, (1j * w * c).real


def linear_multipliers(omega: float, zeta: float, period: float) -> np.ndarray:
    """exp((-zeta Om +- i Om sqrt(1 - zeta^2)) T): the oscillator's one-period propagator."""
    lam = -zeta * omega + 1j * omega * math.sqrt(1 - zeta**2)
    return np.array([np.exp(lam * period), np.exp(np.conj(lam) * period)])


def sort_complex(z: np.ndarray) -> np.ndarray:
    return np.array(sorted(np.asarray(z, complex), key=lambda c: (round(abs(c), 9), c.imag)))


def orbits_on_stable_runs(smap: StroboscopicMap, branch, value: float):
    """Solve the orbit at ``value`` from every stable, monotone run of the branch covering it.

    The start is the linear interpolation of the run's states; Newton's method (at
    the map's tolerances) converges to the branch's own orbit there.
    """
    lam, states, stable = branch.values, branch.states, branch.stable
    out = []
    i = 0
    while i < len(lam) - 1:
        if not (stable[i] and stable[i + 1]):
            i += 1
            continue
        j = i
        sign = np.sign(lam[i + 1] - lam[i])
        while j < len(lam) - 1 and stable[j + 1] and np.sign(lam[j + 1] - lam[j]) == sign:
            j += 1
        seg = slice(i, j + 1)
        lo, hi = min(lam[i], lam[j]), max(lam[i], lam[j])
        if lo <= value <= hi:
            order = np.argsort(lam[seg])
            x0 = np.array([np.interp(value, lam[seg][order], states[seg][order][:, c])
                           for c in range(states.shape[1])])
            out.append(find_orbit(smap.with_parameter(value=value), initial_state=x0,
                                  period=branch.period))
        i = j
    return out


# ---------------------------------------------------- linear limit (no contact)
@pytest.mark.parametrize("preset", ["wall", "fig4-translational"])
def test_without_contact_the_orbit_is_the_linear_steady_response(preset):
    """Gap 1e4: never a contact. The map is affine, so the finite-difference
    monodromy is exact for any step up to round-off: a step of 0.1 (relative)
    keeps round-off near 1e-13; Newton converges in one step."""
    scene = load_preset(preset).with_params(gap=1e4, period_ratio=0.8)
    smap = StroboscopicMap.of(scene, fd_step=0.1)
    orbit = find_orbit(smap)
    w, period = 1 / 0.8, scene.period
    zeta = 0.03
    expected = list(linear_response(1.0, zeta, w))
    mu = list(linear_multipliers(1.0, zeta, period))
    if preset != "wall":  # the pair model: tower B, Om = 1.5
        expected += list(linear_response(1.5, zeta, w))
        mu += list(linear_multipliers(1.5, zeta, period))
    assert orbit.iterations <= 2 and orbit.impacts_per_period == 0
    np.testing.assert_allclose(orbit.state, expected, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sort_complex(orbit.multipliers), sort_complex(mu), rtol=0,
                               atol=1e-10)
    assert orbit.stable
    np.testing.assert_allclose(sorted(orbit.exponents), sorted([-zeta] * 2 + (
        [] if preset == "wall" else [-1.5 * zeta] * 2)), atol=1e-10)


# ------------------------------------------------------------ fig3a, 3-1 orbit
@pytest.fixture(scope="module")
def fig3a_orbit():
    smap = StroboscopicMap.of(FIG3A)
    return smap, find_orbit(smap, transient=40)


def test_fig3a_orbit_equals_long_forward_integration(fig3a_orbit):
    """The 3-1 orbit from 40 transient cycles equals where 400 cycles of forward
    integration (transient decaying like 0.876^N) arrive, state and impacts."""
    smap, orbit = fig3a_orbit
    assert orbit.residual <= 1e-10 and orbit.label == "3-1"
    assert orbit.corners == ("A+", "B-", "A+")
    far, _, _ = advance(smap.system, smap.system.initial_state, 400, from_time_zero=True)
    np.testing.assert_allclose(orbit.state, far, rtol=0, atol=1e-8)
    run = simulate(smap.system, transient=400, record=2)
    np.testing.assert_allclose(run.impacts.velocity, np.tile(orbit.impact_velocity, 2),
                               rtol=0, atol=1e-8)
    np.testing.assert_allclose(run.impacts.phase, np.tile(orbit.impact_phase, 2), atol=1e-8)


def test_orbit_trajectory_closes_on_itself(fig3a_orbit):
    smap, orbit = fig3a_orbit
    run = orbit_trajectory(smap, orbit, samples_per_cycle=50)
    states = run.trajectory.state
    assert states.shape == (51, 12)
    np.testing.assert_allclose(states[-1], states[0], atol=1e-9)
    np.testing.assert_allclose(run.impacts.velocity, orbit.impact_velocity, atol=1e-12)


def test_fig3a_floquet_exponent_equals_qr_lyapunov_exponent(fig3a_orbit):
    """The largest Floquet exponent (log|mu| / T of the complex pair |mu| = 0.8757)
    against the QR estimate with a long tangent transient: within 3 standard errors
    (the second pair, |mu| = 0.861, aligns away only like (0.861/0.876)^N)."""
    _, orbit = fig3a_orbit
    spectrum = lyapunov_spectrum(FIG3A.with_params(rtol=1e-9), k=1, tangent_transient=600,
                                 cycles=2000)
    assert abs(spectrum.exponents[0] - orbit.exponents[0]) <= 3 * spectrum.errors[0]
    assert spectrum.errors[0] < 1e-5


def test_fd_monodromy_obeys_the_trace_identity(fig3a_orbit):
    """det M = exp(trace(J) k T): the Jacobian's trace is constant (contact forces
    depend on positions only), so Liouville's formula holds exactly along any orbit."""
    smap, orbit = fig3a_orbit
    trace = _constant_trace(smap.system)
    assert np.linalg.det(orbit.monodromy) == pytest.approx(math.exp(trace * smap.period),
                                                           rel=1e-7)
    assert np.prod(orbit.multipliers).real == pytest.approx(math.exp(trace * smap.period),
                                                            rel=1e-7)
    assert np.sum(orbit.exponents) == pytest.approx(trace, rel=1e-7)
    # the variational monodromy (the default): the 1e-10 (measured 2e-12), and
    # its multipliers are a finite-difference monodromy's eigenvalues to 1e-6 (3e-9)
    assert abs(np.sum(orbit.exponents) - trace) < 1e-10
    _, fd = finite_difference_monodromy(smap, orbit.state, 1)
    fd_mu = np.linalg.eigvals(fd)
    assert max(np.min(np.abs(fd_mu - mu)) for mu in orbit.multipliers) < 1e-6
    # two periods, an impacting wall orbit, and the Duffing oscillator (trace -d)
    _, m2 = smap.monodromy(orbit.state, 2)
    assert np.linalg.det(m2) == pytest.approx(math.exp(2 * trace * smap.period), rel=1e-7)
    wall = StroboscopicMap.of(WALL_GAP5.with_params(period_ratio=0.8))
    impacting = find_orbit(wall, initial_state=[-3.0, -5.0])
    assert impacting.impacts_per_period == 1
    assert np.linalg.det(impacting.monodromy) == pytest.approx(
        math.exp(_constant_trace(wall.system) * wall.period), rel=1e-7)
    duff = StroboscopicMap.of(duffing(damping=0.1, linear=1.0, cubic=0.2, amplitude=0.5,
                                      frequency=1.2))
    x, m = duff.monodromy(np.array([0.3, 1.0]), 1)
    assert np.linalg.det(m) == pytest.approx(math.exp(-0.1 * duff.period), rel=1e-7)


def test_the_monodromy_provider_is_pluggable(fig3a_orbit):
    """Newton only calls smap.monodromy: a provider with a wrong matrix still converges
    to the same orbit (slower) and reports that matrix's eigenvalues."""
    smap, orbit = fig3a_orbit
    calls = []

    def chord(m, x, k):  # a quasi-Newton provider: the true M frozen at the orbit
        calls.append(k)
        return m.advance(x, k), orbit.monodromy

    from dataclasses import replace

    frozen = replace(smap, monodromy_provider=chord)
    x, m, res, _ = newton_fixed_point(frozen, orbit.state + 1e-4, 1)
    assert calls and res <= 1e-10 and m is orbit.monodromy
    np.testing.assert_allclose(x, orbit.state, atol=1e-9)


def test_the_approximate_final_monodromy_has_the_exact_multipliers_to_its_rtol(fig3a_orbit):
    """exact_monodromy=False (what a classifier asking only for stability uses) returns
    the same fixed point, and a matrix whose multipliers are the exact ones to about
    the map's jacobian_rtol (1e-6), not the map's own rtol."""
    smap, orbit = fig3a_orbit
    start = orbit.state + 1e-4
    x, m, res, it = newton_fixed_point(smap, start, 1)
    xa, ma, resa, ita = newton_fixed_point(smap, start, 1, exact_monodromy=False)
    assert (res, it) == (resa, ita) and np.array_equal(x, xa)
    exact, approximate = (np.sort(np.abs(np.linalg.eigvals(a))) for a in (m, ma))
    assert np.max(np.abs(approximate - exact)) < 1e-4 * np.max(exact)
    assert not np.array_equal(m, ma)  # it is the looser matrix indeed


class _CountingMap:
    """A map that counts the forcing periods its caller has it integrate."""

    def __init__(self, smap):
        self.smap, self.periods = smap, 0

    def advance(self, x, k=1):
        self.periods += k
        return self.smap.advance(x, k)

    def monodromy(self, x, k=1):
        self.periods += k
        return self.smap.monodromy(x, k)

    def approximate_monodromy(self, x, k=1):
        self.periods += k
        return self.smap.approximate_monodromy(x, k)


def test_give_up_early_finds_the_same_orbit(fig3a_orbit):
    """The classifier's early-giving-up Newton converges to the orbit plain Newton
    finds, with the same stability, from a start off the orbit."""
    smap, orbit = fig3a_orbit
    start = orbit.state + 1e-3
    x, m, res, _ = newton_fixed_point(smap, start, 1)
    xg, mg, resg, _ = newton_fixed_point(smap, start, 1, give_up_early=True)
    assert res <= ORBIT_TOL and resg <= ORBIT_TOL
    np.testing.assert_allclose(xg, x, atol=1e-8 * max(1.0, np.max(np.abs(x))))
    np.testing.assert_allclose(np.abs(np.linalg.eigvals(mg)), np.abs(np.linalg.eigvals(m)),
                               rtol=1e-6)


def test_give_up_early_stops_sooner_on_a_chaotic_set():
    """On fig4's chaotic attractor (T/T_Ax 0.9) no period-3 orbit is near the section
    state: plain Newton spends its 15 iterations, the early-giving-up one stops at the
    first step along which the residual does not fall, having run fewer periods."""
    smap = StroboscopicMap.of(load_preset("fig4").with_params(period_ratio=0.9))
    x = smap.advance(smap.system.initial_state, 200)
    plain, early = _CountingMap(smap), _CountingMap(smap)
    with pytest.raises(OrbitNotFound, match="no convergence in 15"):
        newton_fixed_point(plain, x, 3, tol=1e-7, max_iter=15)
    with pytest.raises(OrbitNotFound, match="no descent along Newton's step"):
        newton_fixed_point(early, x, 3, tol=1e-7, max_iter=15, give_up_early=True)
    assert early.periods < 0.5 * plain.periods


def test_newton_failure_is_one_clear_error():
    chaotic = StroboscopicMap.of(load_preset("fig4").with_params(period_ratio=0.9))
    with pytest.raises(OrbitNotFound, match="period-1 orbit: no convergence in 2 Newton"):
        find_orbit(chaotic, max_iter=2)
    with pytest.raises(ValueError, match="period = 0"):
        find_orbit(chaotic, period=0)


# ---------------------------------------------------- wall: folds, hysteresis
@pytest.fixture(scope="module")
def wall_branch():
    smap = StroboscopicMap.of(WALL_GAP5, parameter="period_ratio")
    return smap, continue_branch(smap, "period_ratio", 0.45, 1.0)


@pytest.fixture(scope="module")
def wall_sweep(tmp_path_factory):
    """The README's hysteresis sweep, brute force both ways, grid step 0.01."""
    path = tmp_path_factory.mktemp("wall") / "hysteresis.h5"
    assert main(["sweep", "--preset", "wall", "--set", "gap=5", "--param",
                 "period_ratio=0.45:1.0:0.01", "--continuation", "both", "-o", str(path),
                 "--quiet"]) == 0
    return open_sweep(path)


def test_wall_folds_bound_the_brute_force_hysteresis(wall_branch, wall_sweep):
    smap, branch = wall_branch
    folds = sorted(sp.value for sp in branch.of_kind("fold"))
    assert len(folds) == 2, [sp.kind for sp in branch.special]
    assert all(sp.bracket < 1e-8 for sp in branch.special)
    # a real multiplier at +1 (to 1e-4 at the upper fold: 6e-6 past a grazing the
    # multiplier runs from 0.84 to 8 within 1e-5 of the parameter; measured 1.4e-5)
    for sp in branch.of_kind("fold"):
        assert np.min(np.abs(sp.orbit.multipliers - 1.0)) < 1e-4
    grid = wall_sweep.grid["period_ratio"]
    forward = wall_sweep.array("impact_count", "forward") > 0
    backward = wall_sweep.array("impact_count", "backward") > 0
    differ = grid[forward != backward]  # the coexistence the sweep shows
    assert differ.size > 10
    step = 0.01
    assert differ.min() - step < folds[0] <= differ.min()
    assert differ.max() <= folds[1] < differ.max() + step
    # the upper fold follows the grazing of the free flight by 6e-6 (Hertz contact)
    [graze] = branch.of_kind("grazing")
    assert 0 < folds[1] - graze.value < 1e-4 and graze.orbit.impact_velocity[0] < 0.01


def test_wall_stable_branch_coincides_with_brute_force_velocities(wall_branch, wall_sweep):
    """At every grid point of both sweeps the brute-force response is a stable part of
    the continued branch: the orbit solved from the branch there has the sweep's impact
    velocity (to the sweep's own convergence, 40 + 8 cycles at rtol 1e-5)."""
    smap, branch = wall_branch
    grid = wall_sweep.grid["period_ratio"]
    worst = 0.0
    for name in ("forward", "backward"):
        velocities = wall_sweep.impact_velocities(name)
        for i, value in enumerate(grid):
            candidates = orbits_on_stable_runs(smap, branch, float(value))
            observed = velocities[i]
            match = [o for o in candidates if o.impacts_per_period == (observed.size > 0)]
            assert match, (name, value)
            if observed.size:
                err = min(abs(o.impact_velocity[0] - observed.mean()) / observed.mean()
                          for o in match)
                worst = max(worst, err)
    assert worst < 2e-3


def test_grazing_point_separates_impacting_from_free_orbits(wall_branch):
    """Located on the free flight's minimum gap (regula falsi, bracket < 1e-9): 1e-9
    before it the orbit has no impact and its closest approach is a small positive
    gap; 1e-9 past it (before the fold) it has one: forward simulation over one
    period of each orbit."""
    smap, branch = wall_branch
    [graze] = branch.of_kind("grazing")
    assert "clearance" in graze.note and graze.bracket < 1e-9
    assert abs(graze.test) < 1e-7  # the clearance's minimum at the located point
    for offset, expected in ((-1e-9, 0), (1e-9, 1)):
        at = smap.with_parameter(value=graze.value + offset)
        orbit = find_orbit(at, initial_state=graze.orbit.state)
        run = simulate(at.system, transient=0, record=1, initial_state=orbit.state,
                       start_at_section=True)
        assert len(run.impacts) == expected == orbit.impacts_per_period
        gap = free_flight_clearance(at, orbit.state)
        if expected == 0:
            assert 0 < gap < 1e-6
    before = smap.with_parameter(value=graze.value - 1e-6)
    orbit = find_orbit(before, initial_state=graze.orbit.state)
    assert 1e-5 < free_flight_clearance(before, orbit.state) < 1e-4  # ~43 per unit T/T_Ax


def test_clearance_of_the_linear_response_is_the_closed_form():
    """Without contact (gap 8, T/T_Ax 0.6) the wall model's relative displacement
    X - u_g is the sinusoid Re[(C + i) e^{iwt}]: the one minimum of the clearance
    per cycle is gap - |C + i|, which the dense samples' Hermite interpolation finds
    to 1e-9."""
    scene = load_preset("wall").with_params(gap=8.0, period_ratio=0.6)
    smap = StroboscopicMap.of(scene)
    orbit = find_orbit(smap, transient=0, initial_state=[0.0, 0.0])
    assert orbit.impacts_per_period == 0
    c = complex(*linear_response(1.0, 0.03, 1 / 0.6))  # (X, X') at t = 0: X = Re[C]
    c = complex(c.real, -c.imag * 0.6)  # C = X(0) - i X'(0) / w
    minima = clearance_minima(smap, orbit.state, 1)
    assert minima.shape[0] == 1
    assert minima[0, 1] == pytest.approx(8.0 - abs(c + 1j), abs=1e-9)


def test_branch_file_round_trip_and_cli(wall_branch, wall_sweep, tmp_path, capsys):
    smap, branch = wall_branch
    path = tmp_path / "branch.h5"
    write_branches(path, [branch], scene_toml=WALL_GAP5.to_toml(), model="wall",
                   system="wall", state_names=smap.system.state_names)
    back = open_branches(path)
    [read] = back.branches
    np.testing.assert_array_equal(read.values, branch.values)
    np.testing.assert_array_equal(read.multipliers, branch.multipliers)
    np.testing.assert_array_equal(read.stable, branch.stable)
    assert [(s.kind, s.value) for s in read.special] == \
        [(s.kind, s.value) for s in branch.special]
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left
    figure = tmp_path / "branch.png"
    assert main(["plot", str(path), "--over", str(wall_sweep.path), "-o", str(figure)]) == 0
    assert figure.stat().st_size > 10_000
    capsys.readouterr()
    # the command line: exit 2 on bad input, the branch's numbers in --json
    assert main(["continue", "--preset", "wall", "--param", "period_ratio=0.5",
                 "-o", str(tmp_path / "x.h5")]) == 2
    assert main(["continue", "--preset", "wall", "--param", "nonsense=0.5:0.6",
                 "-o", str(tmp_path / "x.h5")]) == 2
    assert "unknown parameter" in capsys.readouterr().err
    out = tmp_path / "cli.h5"
    assert main(["continue", "--preset", "wall", "--set", "gap=5", "--param",
                 "period_ratio=0.45:1.0", "-o", str(out), "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    folds = [s["value"] for s in summary["branches"][0]["special"] if s["kind"] == "fold"]
    np.testing.assert_allclose(sorted(folds), sorted(sp.value for sp in
                                                     branch.of_kind("fold")), atol=1e-9)
    assert main(["orbit", "--preset", "fig4", "--set", "period_ratio=0.9", "--quiet"]) == 1
    assert "no convergence" in capsys.readouterr().err


def test_cli_orbit_json_reports_the_3_1_orbit(capsys, fig3a_orbit):
    _, orbit = fig3a_orbit
    assert main(["orbit", "--preset", "fig3a", "--json", "--quiet"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["label"] == "3-1" and document["corners"] == ["A+", "B-", "A+"]
    assert document["stable"] is True
    np.testing.assert_allclose(document["impact_velocities"], orbit.impact_velocity,
                               atol=1e-9)


# ------------------------------------------------------------------- Duffing
DUFFING = {"damping": 0.1, "linear": 1.0, "cubic": 0.2, "amplitude": 0.5}


def duffing_at(w: float):
    return duffing(frequency=w, **DUFFING)


def test_duffing_frequency_response_folds_against_brute_force():
    """Hardening Duffing x'' + 0.1 x' + x + 0.2 x^3 = 0.5 cos(w t): the period-1
    branch in w has two folds bounding the hysteresis of up/down forward sweeps
    (each point 300 periods from the previous one's state), and its stable parts are
    where those sweeps end."""
    smap = StroboscopicMap.of(duffing_at(0.8), parameter="frequency", factory=duffing_at,
                              value=0.8)
    branch = continue_branch(smap, "frequency", 0.8, 2.2)
    folds = sorted(sp.value for sp in branch.of_kind("fold"))
    assert len(folds) == 2 and branch.stop_reasons == ["reached frequency = 0.8",
                                                       "reached frequency = 2.2"]
    for sp in branch.of_kind("fold"):
        assert sp.bracket < 1e-8 and np.min(np.abs(sp.orbit.multipliers - 1.0)) < 1e-8
    # a step budget that ends the branch early says where, and how to go on
    short = continue_branch(smap, "frequency", 0.8, 2.2, max_steps=4)
    assert short.stop_reasons[1].startswith("max_steps = 4 reached at frequency = ")
    assert float(short.stop_reasons[1].split("= ")[2].split()[0]) == pytest.approx(
        short.values.max(), rel=1e-9)
    step = 0.02
    grid = np.round(np.arange(0.8, 2.2 + step / 2, step), 12)

    def sweep(values):
        x, out = np.zeros(2), []
        for w in values:
            x, _, _ = advance(duffing_at(w).with_solver(rtol=1e-10, atol=1e-12), x, 300)
            out.append(x.copy())
        return np.array(out)

    up = sweep(grid)
    down = sweep(grid[::-1])[::-1]
    differ = grid[np.max(np.abs(up - down), axis=1) > 1e-6]
    assert differ.size >= 3
    assert differ.min() - step < folds[0] <= differ.min()
    assert differ.max() <= folds[1] < differ.max() + step
    for i, w in enumerate(grid):
        orbits = orbits_on_stable_runs(smap, branch, float(w))
        for state in (up[i], down[i]):
            assert min(np.max(np.abs(o.state - state)) for o in orbits) < 1e-8, w


# ----------------------------------------------------------- period doubling
def test_period_doubling_matches_brute_force_and_switches_to_its_period_2(tmp_path):
    """fig4-translational (pair model): the sweep's period 1 -> 2 change between
    T/T_Ax = 0.70 and 0.71 (200 transient cycles) contains the located period doubling,
    and the branch switched to there is the sweep's period-2 response at 0.71."""
    path = tmp_path / "pd.h5"
    assert main(["sweep", "--preset", "fig4-translational", "--param",
                 "period_ratio=0.65:0.75:0.01", "--continuation", "forward", "--transient",
                 "200", "-o", str(path), "--quiet"]) == 0
    sweep = open_sweep(path)
    grid = sweep.grid["period_ratio"]
    period = sweep.array("period_cycles", "forward")
    change = [i for i in range(len(grid) - 1) if period[i] == 1 and period[i + 1] == 2]
    assert len(change) == 1
    lo, hi = grid[change[0]], grid[change[0] + 1]
    scene = load_preset("fig4-translational").with_params(transient=200)
    smap = StroboscopicMap.of(scene, parameter="period_ratio")
    branch = continue_branch(smap, "period_ratio", 0.65, 0.75)
    [pd] = branch.of_kind("period-doubling")
    assert lo < pd.value < hi and pd.bracket < 1e-8
    mu = pd.orbit.multipliers
    assert np.min(np.abs(mu + 1.0)) < 1e-6
    doubled = switch_period_doubling(smap, pd, 0.65, float(hi) + 0.005, max_steps=150)
    assert doubled.period == 2
    [orbit] = [o for o in orbits_on_stable_runs(smap, doubled, float(hi))
               if o.impacts_per_period == 2]
    observed = np.unique(np.round(sweep.impacts(change[0] + 1, "forward")["velocity"], 3))
    np.testing.assert_allclose(np.sort(orbit.impact_velocity), observed, atol=2e-3)
    # and it is not the period-1 orbit: two different impacts per period
    assert abs(orbit.impact_velocity[0] - orbit.impact_velocity[1]) > 0.3
    # continued back from 0.715, the period-2 branch turns where it meets its parent:
    # reported as the period doubling's vertex (a pitchfork of P^2, not a fold)
    back = continue_branch(smap.with_parameter(value=0.715), "period_ratio", 0.715, 0.70,
                           period=2, both=False, transient=300)
    assert back.orbits[0].label == "2-2"
    [vertex] = back.special
    assert vertex.kind == "period-doubling" and "vertex" in vertex.note
    assert abs(vertex.value - pd.value) < 1e-6


def test_orbit_record_and_parameter_maps():
    """with_parameter rebuilds scenes through Scene.with_params and custom systems
    through their factory; orbit_at reports the map's parameter value."""
    smap = StroboscopicMap.of(WALL_GAP5, parameter="gap")
    assert smap.value == 5.0
    other = smap.with_parameter(value=6.0)
    assert other.system.scene.gap == 6.0 and other.system.rtol == 1e-12
    duff = StroboscopicMap.of(duffing_at(1.0), parameter="frequency", factory=duffing_at,
                              value=1.0)
    assert duff.with_parameter(value=1.5).period == pytest.approx(2 * math.pi / 1.5)
    with pytest.raises(ValueError, match="factory"):
        StroboscopicMap.of(duffing_at(1.0), parameter="frequency")
    x, m, res, it = newton_fixed_point(other, np.zeros(2), 1)
    orbit = orbit_at(other, x, 1, m, res, it)
    assert orbit.value == 6.0 and orbit.parameter == "gap"


# ------------------------------------------------------------- Neimark-Sacker
def test_fig3a_orbit_loses_stability_at_a_neimark_sacker_point(tmp_path):
    """The 3-1 orbit (A+ B- A+) of the 12-state towers model, continued up in T/T_Ax,
    loses stability when a complex pair of multipliers leaves the unit circle; the
    brute-force sweep (200 transient cycles, full classification) shows 3-1 up to
    0.740 and a period-5 response (14 impacts, frequency locking on the torus born
    there) at 0.745."""
    path = tmp_path / "ns.h5"
    assert main(["sweep", "--preset", "fig3a", "--param", "period_ratio=0.73:0.75:0.005",
                 "--continuation", "forward", "--transient", "200", "--classify", "full",
                 "-o", str(path), "--quiet"]) == 0
    sweep = open_sweep(path)
    grid = sweep.grid["period_ratio"]
    three_one = [int(sweep.array("impacts_per_period", "forward")[i]) == 3
                 and int(sweep.array("period_cycles", "forward")[i]) == 1
                 for i in range(len(grid))]
    last = max(i for i, ok in enumerate(three_one) if ok)
    assert all(three_one[:last + 1]) and last + 1 < len(grid)
    assert sweep.array("period_cycles", "forward")[last + 1] != 1
    smap = StroboscopicMap.of(FIG3A, parameter="period_ratio")
    branch = continue_branch(smap, "period_ratio", 0.735, 0.745, both=False, max_steps=60)
    ns = branch.of_kind("neimark-sacker")[0]
    assert grid[last] < ns.value < grid[last + 1] and ns.bracket < 1e-8
    pair = ns.orbit.multipliers[:2]
    np.testing.assert_allclose(np.abs(pair), 1.0, atol=1e-6)
    assert abs(pair[0].imag) > 0.5 and pair[0] == np.conj(pair[1])
    assert ns.orbit.label == "3-1" and ns.orbit.corners == ("A+", "B-", "A+")
    before = branch.orbits[:ns.index]  # the points before it along the curve
    assert len(before) > 3 and all(o.stable for o in before)
    for offset, stable in ((-1e-5, True), (1e-5, False)):  # the same orbit on both sides
        near = find_orbit(smap.with_parameter(value=ns.value + offset),
                          initial_state=ns.orbit.state)
        assert near.stable == stable and near.label == "3-1"
        assert abs(near.multipliers[0].imag) > 0.5
    # the torus rotates by arg(mu) / 2 pi = 0.217 per cycle, near the 1:5 locking seen
    assert abs(np.angle(pair[0]) / (2 * np.pi) - 1 / 5) < 0.03


# ------------------------------------------- exact exponents of periodic responses
FIG4_070 = load_preset("fig4").with_params(period_ratio=0.70)


def test_classify_gives_the_exact_floquet_exponents_of_a_periodic_response():
    """fig4 at T/T_Ax = 0.70 (issue 16): classify solves the 3-1 orbit and reports its
    Floquet exponents, equal to the orbit solver's from a 200-cycle start and to those
    of a finite-difference monodromy (5-point stencil) to 1e-6; the Lyapunov spectrum's
    companion report finds the same orbit from the end of the QR run."""
    regime = classify(FIG4_070)
    assert regime.label == "group-periodic 3-1"
    floquet = regime.evidence["floquet"]
    assert floquet["method"] == "variational" and floquet["residual"] <= 1e-10
    assert regime.floquet_exact and floquet["confirmed"] and regime.confidence == 1.0
    smap = StroboscopicMap.of(FIG4_070)
    orbit = find_orbit(smap, transient=200)
    np.testing.assert_allclose(regime.floquet_exponents, orbit.exponents, rtol=0, atol=1e-9)
    np.testing.assert_allclose(regime.floquet_multipliers, orbit.multipliers, atol=1e-9)
    fd = find_orbit(replace(smap, monodromy_provider=finite_difference_monodromy),
                    initial_state=orbit.state)
    np.testing.assert_allclose(regime.floquet_exponents, fd.exponents, rtol=0, atol=1e-6)
    assert json.loads(json.dumps(regime.to_json_dict()))["floquet_exact"] is True
    spectrum = lyapunov_spectrum(FIG4_070)
    report = spectrum_floquet(FIG4_070, spectrum)
    assert report.exact and report.period == 1 and report.method == "variational"
    np.testing.assert_allclose(report.exponents, orbit.exponents, rtol=0, atol=1e-9)
    chaotic = load_preset("fig4").with_params(period_ratio=0.9)
    assert spectrum_floquet(chaotic, lyapunov_spectrum(chaotic, k=1)) is None


def test_floquet_multipliers_do_not_depend_on_the_section_phase():
    """The multipliers belong to the orbit, not to the section that cuts it: with the
    section inside a contact episode (phase 0.645; the group's first impact starts at
    0.633 and lasts 0.05 of a cycle) they equal those of the section at phase 0, and so
    do the impacts, in rotated order. (The map must return the state at the section,
    not where the engine stopped following the episode.)"""
    base = find_orbit(StroboscopicMap.of(FIG4_070), transient=200)
    inside = find_orbit(StroboscopicMap.of(FIG4_070.with_params(phase=0.645)), transient=200)
    run = simulate(StroboscopicMap.of(FIG4_070.with_params(phase=0.645)).system, transient=0,
                   record=1, initial_state=inside.state, start_at_section=True)
    end = run.impacts.time + run.impacts.duration
    assert np.any((run.impacts.time < run.strobe.time[-1]) & (run.strobe.time[-1] < end))
    np.testing.assert_allclose(sort_complex(inside.multipliers), sort_complex(base.multipliers),
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.sort(inside.impact_velocity), np.sort(base.impact_velocity),
                               rtol=0, atol=1e-9)
    assert inside.corners == base.corners[1:] + base.corners[:1]


@pytest.mark.parametrize("law", [
    "hertzdamp",
    # two engines of its own (the jump's exact tangent is also checked on the
    # tower-wall model by test_contact_tangent): -m slow
    pytest.param("kelvin_voigt", marks=pytest.mark.slow),
])
def test_laws_with_memory_or_jumps_have_exact_floquet_exponents(law):
    """A law with per-episode memory (hertzdamp) or a force jump at onset (Kelvin-Voigt)
    on the line contact: the variational monodromy (memory sensitivity, one-sided
    Jacobians) gives classify's exact exponents; they equal those of an independent
    finite-difference monodromy, and a perturbation of 1e-6 grows over 10 cycles as
    M^10 predicts (to its own O(1e-6) nonlinearity)."""
    scene = FIG4_070.with_params(contact_law=law)
    regime = classify(scene)
    assert regime.label == "group-periodic 3-1" and regime.floquet_exact
    smap = StroboscopicMap.of(scene, monodromy_provider=finite_difference_monodromy)
    report = response_floquet(scene, smap.start_state(200), 1)
    np.testing.assert_allclose(report.exponents, regime.floquet_exponents, rtol=0, atol=1e-6)
    x, m = report.orbit.state, report.orbit.monodromy
    delta = np.random.default_rng(1).normal(size=x.size)
    delta *= 1e-6 / np.linalg.norm(delta)
    predicted = np.linalg.matrix_power(m, 10) @ delta
    forward = smap.advance(x + delta, 10) - x
    assert np.linalg.norm(forward - predicted) < 1e-4 * np.linalg.norm(predicted)


def test_minimal_period_tells_a_doubled_solve_from_a_doubled_orbit():
    """Newton on P^2(x) = x from a period-1 orbit converges to it (the wall at gap 5,
    T/T_Ax 1.0: periodic 1-1): its sections repeat after 1 cycle, which
    minimal_period finds and response_floquet reports (the orbit does not confirm a
    period-2 response). fig4 at T/T_Ax 0.95 responds on a stable period-2 orbit, whose
    sections 1 cycle apart differ."""
    from chaospound.orbits.shooting import minimal_period

    smap = StroboscopicMap.of(WALL_GAP5.with_params(period_ratio=1.0))
    one = find_orbit(smap, period=1, transient=300)
    x, m, _, _ = newton_fixed_point(smap, one.state, 2)
    assert minimal_period(smap, x, 2) == 1 and minimal_period(smap, x, 4) == 1
    report = response_floquet(WALL_GAP5.with_params(period_ratio=1.0), x, 2)
    assert report.found and report.stable and report.minimal_period == 1
    assert not report.confirmed and "repeats after 1 cycles, not 2" in report.note
    scene = load_preset("fig4").with_params(period_ratio=0.95)
    two_map = StroboscopicMap.of(scene)
    two = find_orbit(two_map, period=2, transient=300)
    assert minimal_period(two_map, two.state, 2) == 2
    assert response_floquet(scene, two.state, 2).minimal_period == 2


def test_cli_orbit_says_when_a_period_k_solve_found_a_shorter_orbit(capsys):
    """`chaospound orbit --period 2` on the wall's period-1 orbit: the report says
    it repeats after 1 cycle, and the JSON gives minimal_period; a period-1 solve
    has no such note."""
    wall = ["--preset", "wall", "--set", "gap=5", "--set", "period_ratio=1.0", "--quiet"]
    assert main(["orbit", *wall, "--period", "2"]) == 0
    assert "note: the orbit repeats after 1 cycle:" in capsys.readouterr().out
    assert main(["orbit", *wall, "--period", "2", "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["period_cycles"] == 2 and document["minimal_period"] == 1
    assert main(["orbit", *wall]) == 0
    assert "note:" not in capsys.readouterr().out


def test_cli_lyapunov_and_classify_say_which_exponents_are_exact(capsys):
    """`chaospound lyapunov` prints the exact Floquet exponents of a periodic response
    beside the QR estimates (and says which are exact); `classify` reports the exact
    largest exponent instead of '-'; a chaotic response has none."""
    orbit = find_orbit(StroboscopicMap.of(FIG4_070), transient=200)
    assert main(["lyapunov", "--preset", "fig4", "--set", "period_ratio=0.70", "--json",
                 "--quiet"]) == 0
    document = json.loads(capsys.readouterr().out)
    floquet = document["floquet"]
    assert floquet["periodic"] and floquet["exact"] and floquet["period_cycles"] == 1
    np.testing.assert_allclose(floquet["exponents"], orbit.exponents, rtol=0, atol=1e-9)
    assert main(["lyapunov", "--preset", "fig4", "--set", "period_ratio=0.70", "--k", "2",
                 "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "Floquet (per unit t, exact)" in text and "-0.0301746" in text
    assert "exact: the response's Lyapunov exponents" in text
    assert main(["classify", "--preset", "fig4", "--set", "period_ratio=0.70",
                 "--quiet"]) == 0
    assert "-0.0301746 per unit t" in capsys.readouterr().out
    assert main(["lyapunov", "--preset", "fig4", "--set", "period_ratio=0.9", "--k", "1",
                 "--cycles", "50", "--json", "--quiet"]) == 0
    assert json.loads(capsys.readouterr().out)["floquet"]["periodic"] is False


def test_the_wall_branch_costs_the_same_from_either_end(wall_branch):
    """Started at T/T_Ax = 1.0, where the orbit's state is 5 times larger than at 0.45,
    the branch passes the same folds and grazing with about as many points: the step
    cap follows each point's state scale, not the starting orbit's (it took 400 points
    and stopped short of the lower fold's far side when it was relative to the start)."""
    smap, forward = wall_branch
    backward = continue_branch(smap, "period_ratio", 1.0, 0.45)
    assert len(backward.orbits) <= 1.2 * len(forward.orbits)
    for kind in ("fold", "grazing"):
        ours = sorted(sp.value for sp in backward.of_kind(kind))
        theirs = sorted(sp.value for sp in forward.of_kind(kind))
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-8)
    values = [o.value for o in backward.orbits]
    assert min(values) == 0.45 and max(values) == 1.0


def test_a_given_ds_max_is_a_fixed_cap(wall_branch):
    """--ds-max caps every pseudo-arclength step, whatever the state's scale (a corrected
    point lies on the hyperplane through the predicted one, so its distance from the
    previous point exceeds the step by the correction only)."""
    smap, _ = wall_branch
    cap = 0.05
    branch = continue_branch(smap, "period_ratio", 1.0, 0.55, ds_max=cap, both=False,
                             max_steps=40)
    y = np.array([np.append(o.state, o.value) for o in branch.orbits])
    steps = np.linalg.norm(np.diff(y, axis=0), axis=1)
    assert steps.size > 10 and steps.max() <= 1.01 * cap
    assert max(abs(o.state).max() for o in branch.orbits) > 5  # where the old cap grew
