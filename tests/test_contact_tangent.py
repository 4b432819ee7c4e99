"""Tangent dynamics of the laws with memory and jumps, checked by independent means.

docs/contact_laws.md section 7. Hertzdamp and Hunt-Crossley keep the onset
velocity v0 of each episode (a function of the state and time of the onset);
Kelvin-Voigt's pointwise force jumps at the contact edge. On the line-contact
models (towers, tower-wall) the engine carries the memory's sensitivity in the
variational equations (Kelvin-Voigt's saltation on the point models:
tests/test_saltation.py); here:

* the propagator monodromy of one period equals a central finite difference of
  the engine's own stroboscopic map (the memory in the packed vector restored
  before every run, as the propagator keeps it fixed at the section);
* the QR largest Lyapunov exponent agrees with the two-trajectory method on a
  chaotic scene and with ``log |mu| / T`` of the finite-difference monodromy
  on a periodic one;
* the energy of a mass pounding a wall through each dissipative law, with no
  other damping, falls by exactly the work of the law's damping part,
  integrated alongside by the engine (a user system reusing the law's kernels).
"""

from __future__ import annotations

import json
import math

import numba
import numpy as np
import pytest

from chaospound import load_preset
from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
from chaospound.dynamics.system import System, advance, custom_system, monodromy
from chaospound.engine.tables import ST_EVENTS
from chaospound.physics.contact import hertz, hertzdamp, jankowski, kelvin_voigt
from chaospound.physics.contact import linear as linear_law
from chaospound.simulate import simulate


def _system(preset: str, law: str, e: float = 0.6, rtol: float = 1e-12, **values) -> System:
    scene = load_preset(preset).with_params(contact_law=law, restitution=e, method="dop853",
                                            rtol=rtol, atol=rtol * 1e-2, **values)
    return System.from_scene(scene)


def _strobe_derivative(system: System, state: np.ndarray, memory: np.ndarray) -> np.ndarray:
    """4th-order central difference of the one-period map, each run from ``memory``."""
    n = state.size
    out = np.empty((n, n))
    for j in range(n):
        step = 1e-4 * max(1.0, abs(state[j]))
        values = []
        for m in (-2, -1, 1, 2):
            shifted = state.copy()
            shifted[j] += m * step
            system.params[:] = memory
            values.append(advance(system, shifted, 1)[0])
        out[:, j] = (values[0] - 8 * values[1] + 8 * values[2] - values[3]) / (12 * step)
    system.params[:] = memory
    return out


def _check_monodromy(system: System, cycles: int = 30) -> None:
    state, _, _ = advance(system, system.initial_state, cycles, from_time_zero=True)
    memory = system.params.copy()
    _, _, stats = advance(system, state, 1)
    assert stats[ST_EVENTS] > 0  # the period holds contact events (onsets)
    system.params[:] = memory
    _, matrix = monodromy(system, state, 1)
    reference = _strobe_derivative(system, state, memory)
    assert np.max(np.abs(matrix - reference)) < 1e-6 * np.max(np.abs(reference))


@pytest.mark.parametrize("preset,law", [("tower-wall", "hertzdamp"),
                                        ("tower-wall", "kelvin-voigt"),
                                        ("wall", "hertzdamp"),
                                        # compiles two engines of its own: the full
                                        # matrix of laws and models runs with -m slow
                                        pytest.param("fig4-translational", "hunt-crossley",
                                                     marks=pytest.mark.slow)])
def test_monodromy_across_memory_and_jumps_is_the_strobe_maps_derivative(preset, law):
    """hertzdamp's v0 sensitivity (through the onset state and time) on a line and a
    point contact, and Kelvin-Voigt's line contact (a continuous resultant whose
    Jacobian jumps at the crossings) are exact in the tangent."""
    _check_monodromy(_system(preset, law))


@pytest.mark.slow
@pytest.mark.parametrize("preset,law,rtol", [
    ("tower-wall", "hunt-crossley", 1e-12),
    ("fig3a", "hertzdamp", 1e-12),
    ("fig3a", "hunt-crossley", 1e-12),
    # at rtol 1e-12 the step controller cannot cross the Jacobian's jump at the
    # corner onsets of this orbit (docs/contact_laws.md section 7)
    ("fig3a", "kelvin-voigt", 1e-10),
])
def test_monodromy_on_the_towers(preset, law, rtol):
    _check_monodromy(_system(preset, law, rtol=rtol))


def test_memory_sensitivity_is_reset_for_each_run():
    """A tangent run starts at the packed memory: stale sensitivities left in the
    packed vector by an earlier run do not leak into the next monodromy."""
    system = _system("tower-wall", "hertzdamp")
    state, _, _ = advance(system, system.initial_state, 30, from_time_zero=True)
    memory = system.params.copy()
    _, first = monodromy(system, state, 1)
    system.params[:] = memory
    slots = slice(system.params.size - len(hertzdamp.MEMORY) + 2, system.params.size)
    system.params[slots] = 1e3  # garbage in the sensitivity slots
    _, second = monodromy(system, state, 1)
    assert np.array_equal(first, second)


def test_qr_exponent_is_log_of_the_floquet_multiplier_on_a_periodic_orbit():
    """A period-1 orbit of tower-wall with hertzdamp (T/T_Ax = 1, four contact events
    a period): the QR largest exponent equals ``log |mu_1| / T`` of the
    finite-difference monodromy matrix."""
    system = _system("tower-wall", "hertzdamp", rtol=1e-11, period_ratio=1.0)
    state, _, _ = advance(system, system.initial_state, 200, from_time_zero=True)
    memory = system.params.copy()
    following, _, stats = advance(system, state, 1)
    assert np.max(np.abs(following - state)) < 1e-8  # period 1
    assert stats[ST_EVENTS] > 0
    system.params[:] = memory
    multipliers = np.linalg.eigvals(_strobe_derivative(system, state, memory))
    expected = math.log(np.max(np.abs(multipliers))) / system.period
    spectrum = lyapunov_spectrum(system, k=1, transient=0, tangent_transient=40, cycles=60,
                                 n_blocks=6, initial_state=state)
    assert abs(spectrum.exponents[0] - expected) < 1e-3 * abs(expected)


#: Kelvin-Voigt's line case compiles two engines of its own for a check that the pair's
#: (tests/test_saltation.py) and the line monodromy above already make: a long study
@pytest.mark.parametrize("law", ["hertzdamp",
                                 pytest.param("kelvin-voigt", marks=pytest.mark.slow)])
def test_qr_and_two_trajectory_agree_on_a_chaotic_scene(law):
    """fig4 at T/T_Ax = 0.9 stays chaotic with e = 0.65: the two estimates of the
    largest exponent agree within their error bars (and are clearly positive)."""
    scene = load_preset("fig4").with_params(contact_law=law, restitution=0.65,
                                            period_ratio=0.9, method="dop853", rtol=1e-10,
                                            atol=1e-12)
    qr = lyapunov_spectrum(scene, k=1, cycles=300, transient=100)
    two = largest_exponent_two_trajectory(scene, cycles=300, transient=100)
    assert two.exponent > 3 * two.error
    assert abs(qr.exponents[0] - two.exponent) < 3 * math.hypot(qr.errors[0], two.error)


# --------------------------------------------------------------- energy balance

BASE = 3  #: the law's block after (k_s, gap, law code) in the user's parameters
HERTZDAMP, KELVIN_VOIGT, JANKOWSKI = 0.0, 1.0, 2.0  #: the law codes (q[2])


@numba.njit(cache=True)
def _forces(q, d, rate):
    """``(F, F_elastic)`` of the law coded ``q[2]`` whose block is ``q[BASE:]``."""
    if q[2] == KELVIN_VOIGT:
        return kelvin_voigt.point_force(q, BASE, d, rate), linear_law.point_force(q, BASE, d, rate)
    if q[2] == JANKOWSKI:
        return jankowski.point_force(q, BASE, d, rate), hertz.point_force(q, BASE, d, rate)
    return hertzdamp.point_force(q, BASE, d, rate), hertz.point_force(q, BASE, d, rate)


@numba.njit(cache=True)
def pounding_rhs(t, y, q, out):
    """A unit mass on a spring ``q[0]`` pounding a wall at ``x = q[1]``; ``y[2]`` is the
    work of the contact's damping part, ``W' = (F - F_el) x'``."""
    f, f_el = _forces(q, y[0] - q[1], y[1])
    out[0] = y[1]
    out[1] = -q[0] * y[0] - f
    out[2] = (f - f_el) * y[1]


@numba.njit(cache=True)
def pounding_jacobian(t, y, q, jac):
    """Central differences (the Jacobian is not under test here)."""
    h = 1e-7
    plus = np.empty(3)
    minus = np.empty(3)
    shifted = y.copy()
    for j in range(3):
        shifted[j] = y[j] + h
        pounding_rhs(t, shifted, q, plus)
        shifted[j] = y[j] - h
        pounding_rhs(t, shifted, q, minus)
        shifted[j] = y[j]
        for i in range(3):
            jac[i, j] = (plus[i] - minus[i]) / (2 * h)


@numba.njit(cache=True)
def pounding_gap(t, y, q):
    return q[1] - y[0], -y[1]


def _energy(y: np.ndarray, q: np.ndarray, module) -> float:
    """Kinetic + spring + the law's elastic contact potential (the independent side)."""
    return (0.5 * y[1] ** 2 + 0.5 * q[0] * y[0] ** 2
            + module.point_potential(q, BASE, y[0] - q[1]))


ENERGY_LAWS = {
    # memory fixed (v0 = 1): hertzdamp's kernels, the onset write is the engine's
    # (tests/test_contact_laws.py checks the balance with it, by scipy)
    "hertzdamp": (hertzdamp, HERTZDAMP, lambda: hertzdamp.block(0.98, beta=1000.0)),
    "jankowski": (jankowski, JANKOWSKI, lambda: jankowski.block(0.98, beta=1000.0, m_eff=1.0)),
    "kelvin-voigt": (kelvin_voigt, KELVIN_VOIGT,
                     lambda: kelvin_voigt.block(0.98, k=100.0, m_eff=1.0)),
}


@pytest.mark.parametrize("law", list(ENERGY_LAWS))
def test_energy_lost_is_the_damping_work_over_100_impacts(law):
    """No structural damping, no ground: ``E0 - E(t) = W(t)`` to 1e-8 of E0 at every
    section over >= 100 impacts, the engine integrating W alongside (the wall at
    the spring's rest position: an impact every half cycle however little energy is left)."""
    module, code, make = ENERGY_LAWS[law]
    q = np.array([1.0, 0.0, code] + list(make().values()))
    system = custom_system(pounding_rhs, pounding_jacobian, pounding_gap,
                           period=2 * math.pi, initial_state=[0.0, 1.0, 0.0], params=q,
                           method="dop853", rtol=1e-12, atol=1e-14)
    sim = simulate(system, transient=0, record=60)
    states = sim.strobe.state
    e0 = _energy(states[0], q, module)
    balance = [abs(_energy(y, q, module) + y[2] - e0) / e0 for y in states]
    assert sim.impacts.velocity.size >= 100
    assert max(balance) < 1e-8
    assert states[-1][2] > 0.5 * e0  # most of the energy went into the damping work


# ------------------------------------------------------------------ the CLI

SHORT = ["--transient", "5", "--record", "2", "--cycles", "10"]


def test_cli_lyapunov_with_jankowski_on_a_point_contact(capsys):
    """Jankowski on the point-contact wall (its Jacobian is singular after every onset;
    the engine shifts the approach phase's tangent vectors, tests/test_jankowski_tangent.py),
    which the CLI used to refuse: the QR spectrum and the two-trajectory estimate."""
    from chaospound.cli import main

    argv = ["lyapunov", "--preset", "wall", "--set", "contact_law=jankowski", *SHORT]
    code = main([*argv, "--two-trajectory", "--json", "--no-floquet"])
    out, err = capsys.readouterr()
    assert code == 0, err
    document = json.loads(out)
    assert document["qr"]["available"] is True and len(document["exponents"]) == 2
    assert all(math.isfinite(x) for x in document["exponents"])
    assert math.isfinite(document["two_trajectory"]["exponent"])


def test_cli_lyapunov_with_memory_on_a_line_contact(capsys):
    """tower-wall with hertzdamp: the QR spectrum and the two-trajectory estimate."""
    from chaospound.cli import main

    code = main(["lyapunov", "--preset", "tower-wall", "--set", "contact_law=hertzdamp",
                 "--set", "method=dop853",  # the engines the monodromy tests compiled
                 *SHORT, "--k", "2", "--two-trajectory", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    document = json.loads(out)
    assert len(document["exponents"]) == 2 and "two_trajectory" in document


def test_contact_damping_lowers_the_exponent_sum_below_the_structural_trace(capsys):
    """The sum of all exponents is the orbit's mean trace of the Jacobian. With an elastic
    law that is the constant structural trace; hertzdamp's contact damping adds
    -mu dF/dd' < 0 during every impact, so its sum lies below, and no constant trace is
    claimed (the CLI says so instead of reporting a spurious difference)."""
    from chaospound.cli import main

    elastic = System.from_scene(load_preset("tower-wall"))
    damped = System.from_scene(load_preset("tower-wall").with_params(
        contact_law="hertzdamp", restitution=0.5, method="dop853"))
    structural = float(elastic.engine("qr").module.model_trace(elastic.params))
    assert float(damped.engine("qr").module.model_trace(damped.params)) == structural
    settings = dict(transient=20, tangent_transient=5, cycles=60, n_blocks=3)
    hertz = lyapunov_spectrum(elastic, **settings)
    assert float(np.sum(hertz.exponents)) == pytest.approx(structural, rel=1e-4)
    spectrum = lyapunov_spectrum(damped, **settings)
    assert math.isnan(spectrum.trace)
    assert float(np.sum(spectrum.exponents)) < structural - 0.1
    code = main(["lyapunov", "--preset", "tower-wall", "--set", "contact_law=hertzdamp",
                 "--set", "method=dop853", *SHORT, "--k", "6"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "not constant along the orbit" in out and "difference" not in out
