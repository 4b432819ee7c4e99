"""Users' own jitted systems: the analyses run on them exactly as on the built-ins.

Two user systems, written here from their equations with no chaospound code:

* Ueda's forced Duffing oscillator, which the built-in reference model also
  implements: the user's version must give the built-in's trajectory and
  Lyapunov spectrum bit for bit (one integrator, two model layers), and the
  published exponent (Sprott 2003: 0.0999 per unit time).
* Davis's (1992) tower pounding a ground-borne wall, with a gap function: its
  impacts, sections and regime must match the built-in "wall" scene.
"""

import math

import numpy as np
import pytest
from numba import njit

from chaospound import custom_system, load_preset
from chaospound.dynamics.classify import classify
from chaospound.dynamics.impact_map import impact_map
from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
from chaospound.dynamics.poincare import impact_section, stroboscopic_section
from chaospound.dynamics.system import duffing
from chaospound.simulate import simulate

# ------------------------------------------------------------ Ueda's Duffing


@njit
def duffing_rhs(t, y, q, out):
    x = y[0]
    out[0] = y[1]
    out[1] = -q[0] * y[1] - q[1] * x - q[2] * x * x * x + q[3] * math.cos(q[4] * t)


@njit
def duffing_jac(t, y, q, jac):
    jac[0, 0] = 0.0
    jac[0, 1] = 1.0
    jac[1, 0] = -q[1] - 3.0 * q[2] * y[0] * y[0]
    jac[1, 1] = -q[0]


UEDA = (0.05, 0.0, 1.0, 7.5, 1.0)  #: d, a, b, g, w


@pytest.fixture(scope="module")
def user_duffing():
    return custom_system(duffing_rhs, duffing_jac, params=UEDA, period=2 * math.pi,
                         initial_state=(1.0, 0.0), state_names=("x", "dx"), name="ueda",
                         transient=100, rtol=1e-9, atol=1e-11)


def test_user_duffing_is_the_builtin_bit_for_bit(user_duffing):
    mine = simulate(user_duffing, transient=0, record=30)
    builtin = simulate(duffing(), transient=0, record=30)
    assert mine.model == "custom" and builtin.model == "duffing"
    np.testing.assert_array_equal(mine.strobe.state, builtin.strobe.state)
    assert mine.stats.steps == builtin.stats.steps


def test_user_duffing_spectrum_is_the_builtin_and_the_published_one(user_duffing):
    mine = lyapunov_spectrum(user_duffing, cycles=1500, transient=100)
    builtin = lyapunov_spectrum(duffing(), cycles=1500, transient=100)
    np.testing.assert_array_equal(mine.exponents, builtin.exponents)
    np.testing.assert_array_equal(mine.errors, builtin.errors)
    assert math.isnan(mine.trace)  # not known for a user's system
    # Sprott (2003): 0.0999; the sum is -d for any orbit
    assert abs(mine.exponents[0] - 0.0999) <= 4 * mine.errors[0] + 2e-3
    assert mine.exponents.sum() == pytest.approx(-UEDA[0], abs=2e-3)


def test_user_duffing_two_trajectory_estimate_agrees(user_duffing):
    spectrum = lyapunov_spectrum(user_duffing, k=1, cycles=1500, transient=100)
    two = largest_exponent_two_trajectory(user_duffing, cycles=1500, transient=100,
                                          separation=1e-7)
    gap = abs(two.exponent - spectrum.exponents[0])
    assert gap <= 4 * math.hypot(two.error, spectrum.errors[0]), (two, spectrum.exponents)


def test_a_system_without_gap_has_no_impacts_and_cannot_be_classified(user_duffing):
    assert len(simulate(user_duffing, transient=0, record=5).impacts) == 0
    with pytest.raises(ValueError, match="no impacts"):
        classify(user_duffing)


# ------------------------------------------------------ a tower against a wall


@njit
def _ground(t, r):
    return math.sin(t / r), math.cos(t / r) / r


@njit
def wall_rhs(t, y, q, out):
    c, gap, beta, chi, r = q[0], q[1], q[2], q[3], q[4]
    ug, vg = _ground(t, r)
    d = y[0] - ug - gap
    force = beta * d**chi if d > 0.0 else 0.0
    out[0] = y[1]
    out[1] = -c * (y[1] - vg) - (y[0] - ug) - force


@njit
def wall_jac(t, y, q, jac):
    c, gap, beta, chi, r = q[0], q[1], q[2], q[3], q[4]
    ug, _ = _ground(t, r)
    d = y[0] - ug - gap
    stiffness = beta * chi * d ** (chi - 1.0) if d > 0.0 else 0.0
    jac[0, 0] = 0.0
    jac[0, 1] = 1.0
    jac[1, 0] = -1.0 - stiffness
    jac[1, 1] = -c


@njit
def wall_gap(t, y, q):
    ug, vg = _ground(t, q[4])
    return q[1] - (y[0] - ug), -(y[1] - vg)


@pytest.fixture(scope="module")
def wall_pair():
    """(user system, built-in scene) of the "wall" preset, both at rtol 1e-10."""
    scene = load_preset("wall").with_params(rtol=1e-10, atol=1e-12)
    flat = scene.to_dict()
    q = (2 * flat["zeta_x_A"], flat["gap"], flat["beta"], flat["chi"], flat["period_ratio"])
    user = custom_system(wall_rhs, wall_jac, wall_gap, params=q, period=scene.period,
                         initial_state=(0.0, 0.0), state_names=("X_A", "dX_A"),
                         name="wall (user)", rtol=1e-10, atol=1e-12)
    return user, scene


def test_user_wall_impacts_equal_the_builtin_wall_model(wall_pair):
    user, scene = wall_pair
    mine = simulate(user, transient=40, record=8)
    builtin = simulate(scene)
    assert builtin.model == "wall" and len(mine.impacts) == len(builtin.impacts) > 0
    np.testing.assert_allclose(mine.impacts.time, builtin.impacts.time, rtol=0, atol=1e-8)
    np.testing.assert_allclose(mine.impacts.velocity, builtin.impacts.velocity, rtol=1e-7)
    np.testing.assert_allclose(mine.strobe.state, builtin.strobe.state, rtol=0, atol=1e-8)
    assert set(mine.impacts.labels) == {"face"}
    assert np.all(mine.impacts.velocity > 0)  # the closing speed -dg/dt


def test_user_wall_sections_and_impact_map(wall_pair):
    user, scene = wall_pair
    mine = stroboscopic_section(user, phase=0.25, transient=40, cycles=10)
    builtin = stroboscopic_section(scene, phase=0.25, transient=40, cycles=10)
    np.testing.assert_allclose(mine.states, builtin.states, rtol=0, atol=1e-8)
    run = simulate(user, transient=40, record=8)
    section = impact_section(run)
    assert len(section) == len(run.impacts)
    pairs = impact_map(run)
    np.testing.assert_allclose(pairs.velocity, run.impacts.velocity)


def test_user_wall_is_classified_like_the_wall_scene(wall_pair):
    user, scene = wall_pair
    mine = classify(user)
    builtin = classify(scene)
    assert (mine.regime, mine.period_cycles, mine.impacts_per_period) == (
        builtin.regime, builtin.period_cycles, builtin.impacts_per_period)
    assert mine.evidence["model"] == "custom"


def test_user_wall_spectrum_matches_the_builtin(wall_pair):
    user, scene = wall_pair
    mine = lyapunov_spectrum(user, cycles=60, transient=40)
    builtin = lyapunov_spectrum(scene.with_params(rtol=1e-10, atol=1e-12), cycles=60,
                                transient=40)
    np.testing.assert_allclose(mine.exponents, builtin.exponents, rtol=1e-5, atol=1e-6)
    assert mine.exponents[0] < -0.005  # a periodic orbit: contracting


# ------------------------------------------------------------- bad input


def test_functions_must_be_jitted():
    with pytest.raises(ValueError, match="rhs must be a numba.njit function"):
        custom_system(duffing_rhs.py_func, duffing_jac, params=UEDA, period=1.0,
                      initial_state=(1.0, 0.0))


def test_bad_arguments_get_one_clear_line():
    cases = [
        (dict(period=0.0), "period = 0.0"),
        (dict(period=math.nan), "period = nan"),
        (dict(initial_state=()), "initial_state"),
        (dict(initial_state=(1.0, math.inf)), "initial_state"),
        (dict(params=(1.0, math.nan)), "params"),
        (dict(method="euler"), "method = 'euler'"),
        (dict(state_names=("x",)), "state_names has 1 names for 2 states"),
    ]
    for change, words in cases:
        kwargs = dict(params=UEDA, period=1.0, initial_state=(1.0, 0.0))
        kwargs.update(change)
        with pytest.raises(ValueError, match=words.replace("(", r"\(")):
            custom_system(duffing_rhs, duffing_jac, **kwargs)


@njit
def _scalar_gap(t, y, q):
    return 1.0 - y[0]


def test_a_gap_must_return_value_and_rate():
    with pytest.raises(ValueError, match=r"gap\(t, y, q\)"):
        custom_system(duffing_rhs, duffing_jac, _scalar_gap, params=UEDA, period=1.0,
                      initial_state=(1.0, 0.0))


def test_one_engine_serves_a_system_whatever_its_number_of_parameters(user_duffing):
    # a sixth entry that the functions never read: the same engine module, the same bits
    longer = custom_system(duffing_rhs, duffing_jac, params=UEDA + (123.0,),
                           period=2 * math.pi, initial_state=(1.0, 0.0), transient=100,
                           rtol=1e-9, atol=1e-11)
    assert longer.engine().module is user_duffing.engine().module
    mine = simulate(user_duffing, transient=0, record=10)
    other = simulate(longer, transient=0, record=10)
    np.testing.assert_array_equal(mine.strobe.state, other.strobe.state)
    spectrum = lyapunov_spectrum(longer, transient=20, cycles=40)
    reference = lyapunov_spectrum(user_duffing, transient=20, cycles=40)
    np.testing.assert_array_equal(spectrum.exponents, reference.exponents)
