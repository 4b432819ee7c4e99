"""The one engine entry, :func:`chaospound.dynamics.system.evolve`.

Every analysis runs the engine through ``evolve``; these tests check it
against independent routes to the same numbers: the System and the Scene it
came from (bitwise: a scene is converted once, to the same packed vector),
the drivers built on it (simulate, the sections, the Lyapunov spectrum, the
monodromy), and scipy's DOP853 at tight tolerance for a user's system with a
gap function (Davis's tower against a wall, tests/test_custom.py), integrated
piecewise between its contact events.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_custom import wall_gap, wall_jac, wall_rhs

from chaospound import custom_system, load_preset
from chaospound.dynamics.impact_map import impact_map
from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
from chaospound.dynamics.poincare import stroboscopic_section
from chaospound.dynamics.system import Evolution, System, evolve, monodromy
from chaospound.engine import tables as kin
from chaospound.simulate import simulate

FIG3A = load_preset("fig3a")


def _arrays(run: Evolution) -> dict:
    return {"state": run.state, "clock": run.clock, "stats": run.stats,
            "sections": run.sections, "times": run.section_times, "impacts": run.impacts,
            "impact_states": run.impact_states, "samples": run.samples}


def test_a_scene_and_its_system_evolve_bitwise_alike():
    """A Scene is converted at the edge: the same packed run, the same bits."""
    by_scene = evolve(FIG3A, transient=3, cycles=3, impacts=True, samples_per_cycle=8)
    by_system = evolve(System.from_scene(FIG3A), transient=3, cycles=3, impacts=True,
                       samples_per_cycle=8)
    assert len(by_scene.impacts) > 0 and by_scene.samples.shape == (25, 13)
    for key, value in _arrays(by_scene).items():
        np.testing.assert_array_equal(value, _arrays(by_system)[key], err_msg=key)


def test_simulate_is_evolve_with_impacts():
    sim = simulate(FIG3A, transient=3, cycles=4)
    run = evolve(FIG3A, transient=3, cycles=4, impacts=True)
    np.testing.assert_array_equal(sim.strobe.state, run.sections)
    np.testing.assert_array_equal(sim.strobe.time, run.section_times)
    np.testing.assert_array_equal(sim.impacts.time, run.impacts[:, kin.IMP_TIME])
    np.testing.assert_array_equal(sim.impacts.state, run.impact_states)
    np.testing.assert_array_equal(sim.final_state, run.state)
    # record is the former name of cycles
    np.testing.assert_array_equal(simulate(FIG3A, transient=3, record=4).strobe.state,
                                  sim.strobe.state)
    with pytest.raises(ValueError, match="give one of them"):
        simulate(FIG3A, transient=3, record=4, cycles=5)


def test_runs_continue_from_a_section():
    """transient + cycles in one run, or split in two at a section: the same states to
    the integration's accuracy (a new run picks its first step afresh)."""
    system = System.from_scene(FIG3A.with_params(rtol=1e-11, atol=1e-13))
    whole = evolve(system, transient=0, cycles=6)
    first = evolve(system, cycles=2)
    rest = evolve(system, first.state, cycles=4)
    np.testing.assert_array_equal(whole.sections[:3], evolve(system, cycles=2).sections)
    np.testing.assert_allclose(rest.sections, whole.sections[2:], rtol=0, atol=1e-8)
    np.testing.assert_array_equal(rest.cycles, np.arange(0, 5))
    np.testing.assert_allclose(rest.section_times, system.period * np.arange(0, 5),
                               rtol=1e-15)


def test_tangent_runs_feed_the_spectrum_and_the_monodromy():
    system = System.from_scene(FIG3A)
    start = evolve(system, cycles=5).state
    run = evolve(system, start, transient=2, cycles=10, tangent="qr", vectors=3)
    assert run.tangent_log.shape == (10, 3) and run.vectors.shape == (3, 12)
    np.testing.assert_allclose(run.vectors @ run.vectors.T, np.eye(3), atol=1e-13)
    spectrum = lyapunov_spectrum(system, k=3, transient=0, tangent_transient=2, cycles=10,
                                 n_blocks=2, initial_state=start)
    np.testing.assert_array_equal(np.sort(run.tangent_log.sum(axis=0))[::-1]
                                  / (10 * system.period), spectrum.exponents)
    # unit vectors added by evolve, or given after the state: the same run
    augmented = np.concatenate([start, np.eye(12)[:3].ravel()])
    given = evolve(system, augmented, transient=2, cycles=10, tangent="qr")
    np.testing.assert_array_equal(given.tangent_log, run.tangent_log)
    prop = evolve(system, start, cycles=1, tangent="propagator")
    state, matrix = monodromy(system, start, 1)
    np.testing.assert_array_equal(prop.tangent_log[0].reshape(12, 12).T, matrix)
    np.testing.assert_array_equal(prop.state, state)


def test_the_two_trajectory_estimate_takes_an_initial_state():
    """The drivers share ``initial_state``: a section state after the transient, given,
    continues the run exactly as the transient inside the driver."""
    system = System.from_scene(FIG3A)
    inside = largest_exponent_two_trajectory(system, transient=4, cycles=6, n_blocks=2)
    given = largest_exponent_two_trajectory(system, transient=0, cycles=6, n_blocks=2,
                                            initial_state=evolve(system, cycles=4).state)
    np.testing.assert_array_equal(given.history, inside.history)


@pytest.mark.parametrize("kwargs, match", [
    ({"cycles": -1}, "cycles = -1"),
    ({"transient": -2}, "transient = -2"),
    ({"tangent": "lu"}, "tangent = 'lu'"),
    ({"initial_state": np.zeros(5)}, "initial_state has 5 values"),
    ({"initial_state": np.zeros(30), "tangent": "qr"}, "a tangent run needs"),
    ({"tangent": "qr", "vectors": 13}, "vectors = 13"),
])
def test_bad_evolve_arguments_name_the_problem(kwargs, match):
    with pytest.raises(ValueError, match=match):
        evolve(FIG3A, **kwargs)


# ------------------------------------------- a user's system with a gap, vs scipy
Q = (0.1, 0.1, 100.0, 1.5, 0.8)  #: c, gap, beta, chi, period ratio r (forcing sin(t / r))
PERIOD = 2 * np.pi * Q[4]


@pytest.fixture(scope="module")
def wall():
    return custom_system(wall_rhs, wall_jac, wall_gap, params=Q, period=PERIOD,
                         initial_state=(0.0, 0.0), state_names=("x", "dx"), name="wall",
                         rtol=1e-11, atol=1e-13)


def _scipy_wall(cycles: int) -> tuple[np.ndarray, np.ndarray]:
    """DOP853 at rtol 1e-13, restarted at every sign change of the gap (the force's kink).

    Returns the states at t = k T, k = 0 .. cycles, and the onset times of contact
    (the gap closing through 0).
    """
    q = np.array(Q)

    def f(t, y):
        out = np.empty(2)
        wall_rhs.py_func(t, y, q, out)
        return out

    def gap(t, y):
        return wall_gap.py_func(t, y, q)[0]

    gap.terminal = True
    gap.direction = -1.0  # apart at t = 0: the next event is the gap closing
    t_end = cycles * PERIOD
    grid = PERIOD * np.arange(cycles + 1)
    states = np.full((cycles + 1, 2), np.nan)
    states[0] = 0.0
    t, y, onsets = 0.0, np.zeros(2), []
    while t < t_end:
        sol = solve_ivp(f, (t, t_end), y, method="DOP853", rtol=1e-13, atol=1e-15,
                        events=gap, dense_output=True)
        t_next = sol.t[-1]
        inside = (grid > t) & (grid <= t_next)
        for k in np.nonzero(inside)[0]:
            states[k] = sol.sol(grid[k])
        if sol.status == 1:
            if gap.direction < 0.0:
                onsets.append(t_next)
            gap.direction = -gap.direction  # the next event is the other crossing
        t, y = t_next, sol.y[:, -1].copy()
    return states, np.array(onsets)


def test_sections_and_impacts_of_a_user_system_with_a_gap_match_scipy(wall):
    cycles = 6
    run = evolve(wall, transient=0, cycles=cycles, impacts=True)
    reference, onsets = _scipy_wall(cycles)
    np.testing.assert_allclose(run.sections, reference, rtol=0, atol=1e-8)
    times = run.impacts[:, kin.IMP_TIME]
    assert len(times) == len(onsets) > 0
    np.testing.assert_allclose(times, onsets, rtol=0, atol=1e-8)
    # the section and the impact map of the library take the system itself
    section = stroboscopic_section(wall, transient=0, cycles=cycles)
    np.testing.assert_array_equal(section.states, run.sections)
    assert section.model == "custom"
    imap = impact_map(wall, transient=0, cycles=cycles)
    np.testing.assert_array_equal(imap.time, times)
    np.testing.assert_array_equal(imap.velocity, run.impacts[:, kin.IMP_VELOCITY])
    assert set(imap.labels) == {"face"} and imap.phase_pairs.shape == (len(times) - 1, 2)


def test_impact_map_needs_impacts_or_a_run(wall):
    smooth = custom_system(wall_rhs, wall_jac, params=Q, period=PERIOD,
                           initial_state=(0.0, 0.0))
    with pytest.raises(ValueError, match="no gap function"):
        impact_map(smooth)
    with pytest.raises(ValueError, match="pass a System or a Scene"):
        impact_map(simulate(wall, transient=0, cycles=2), cycles=3)
