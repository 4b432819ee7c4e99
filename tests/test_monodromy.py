"""The monodromy matrix from the variational equations ("propagator" engines).

Checked against three independent facts: a central finite difference of the
flow map, Liouville's formula ``det M = exp(trace(J) k T)`` (the trace is
constant for every built-in model), and the closed form of the damped linear
oscillator when the towers never touch.
"""

import numpy as np
import pytest

from chaospound.dynamics.system import System, advance, duffing, monodromy
from chaospound.kernels.params import T_CX, T_OM2, TOWER_A
from chaospound.scene import load_preset


def _tight(system: System) -> System:
    return system.with_solver(method="dop853", rtol=1e-12, atol=1e-14)


def _section_state(system: System, cycles: int = 30) -> np.ndarray:
    state, _, _ = advance(system, system.initial_state, cycles, from_time_zero=True)
    return state


def _finite_difference(system: System, state: np.ndarray, periods: int) -> np.ndarray:
    n = state.size
    jac = np.empty((n, n))
    for j in range(n):  # the 5-point stencil: truncation O(h^4), round-off O(tol / h)
        step = 1e-4 * max(1.0, abs(state[j]))
        values = []
        for m in (-2, -1, 1, 2):
            shifted = state.copy()
            shifted[j] += m * step
            values.append(advance(system, shifted, periods)[0])
        jac[:, j] = (values[0] - 8.0 * values[1] + 8.0 * values[2] - values[3]) / (12.0 * step)
    return jac


@pytest.mark.parametrize("preset", ["fig3a", "fig4-translational", "wall"])
def test_monodromy_equals_a_finite_difference_of_the_flow(preset):
    system = _tight(System.from_scene(load_preset(preset)))
    state = _section_state(system)
    end, matrix = monodromy(system, state, 1)
    direct, _, _ = advance(system, state, 1)
    # the same trajectory, to the tolerance (the tangent vectors share the step control)
    np.testing.assert_allclose(end, direct, rtol=0.0, atol=1e-9)
    reference = _finite_difference(system, state, 1)
    scale = np.max(np.abs(reference))
    assert np.max(np.abs(matrix - reference)) < 1e-6 * scale


@pytest.mark.parametrize("preset, periods", [("fig3a", 1), ("fig3a", 3), ("tower-wall", 2)])
def test_liouville_formula(preset, periods):
    system = _tight(System.from_scene(load_preset(preset)))
    state = _section_state(system)
    _, matrix = monodromy(system, state, periods)
    trace = system.engine().module.model_trace(system.params)
    log_det = np.log(abs(np.linalg.det(matrix)))
    assert log_det == pytest.approx(trace * periods * system.period, rel=1e-10, abs=1e-10)


def test_without_contact_the_multipliers_are_the_damped_oscillators():
    scene = load_preset("wall").with_params(gap=1e6)
    system = _tight(System.from_scene(scene))
    state = _section_state(system, cycles=2)
    _, matrix = monodromy(system, state, 1)
    c = system.params[TOWER_A + T_CX]
    om2 = system.params[TOWER_A + T_OM2]
    root = np.sqrt(complex(om2 - 0.25 * c * c))
    expected = np.exp(np.array([-0.5 * c + 1j * root, -0.5 * c - 1j * root]) * system.period)
    got = np.linalg.eigvals(matrix)
    got = got[np.argsort(got.imag)]
    expected = expected[np.argsort(expected.imag)]
    assert np.max(np.abs(got - expected)) < 1e-10


def test_reference_oscillator_monodromy_and_its_trace():
    system = _tight(duffing())
    state = _section_state(system, cycles=5)
    _, matrix = monodromy(system, state, 1)
    reference = _finite_difference(system, state, 1)
    assert np.max(np.abs(matrix - reference)) < 1e-5 * np.max(np.abs(reference))
    assert np.linalg.det(matrix) == pytest.approx(np.exp(-0.05 * system.period), rel=1e-10)
