"""Lyapunov engine: published spectra, the trace identity, linear limits, cross-checks."""

import numpy as np
import pytest
from kernels_by_name import jacobian

from chaospound.dynamics.lyapunov import (
    kaplan_yorke,
    largest_exponent_two_trajectory,
    lyapunov_spectrum,
)
from chaospound.dynamics.system import System, duffing, lorenz
from chaospound.scene import load_preset

CHAOTIC_FIG4 = load_preset("fig4").with_params(period_ratio=0.9, rtol=1e-8)
PERIODIC_FIG4 = load_preset("fig4").with_params(period_ratio=1.5, rtol=1e-8)


def test_lorenz_spectrum_matches_published_values():
    """Lorenz (10, 28, 8/3): about (0.906, 0, -14.57) (e.g. Sprott 2003)."""
    spec = lyapunov_spectrum(lorenz(), cycles=1000, tangent_transient=20)
    reference = np.array([0.9056, 0.0, -14.5723])
    assert np.all(np.abs(spec.exponents - reference) <= 3 * spec.errors + 0.02)
    assert spec.exponents.sum() == pytest.approx(-(10 + 1 + 8 / 3), rel=1e-6)
    assert kaplan_yorke(spec.exponents) == pytest.approx(2.062, abs=0.01)


def test_ueda_duffing_spectrum_matches_published_values():
    """x'' + 0.05 x' + x^3 = 7.5 cos t (Ueda 1979): about (0.0999, -0.1499)."""
    spec = lyapunov_spectrum(duffing(), cycles=4000, transient=100)
    assert abs(spec.exponents[0] - 0.0999) <= 3 * spec.errors[0] + 0.005
    assert spec.exponents.sum() == pytest.approx(-0.05, rel=1e-6)


def test_two_trajectory_method_on_ueda():
    ueda = duffing(rtol=1e-11, atol=1e-13)
    two = largest_exponent_two_trajectory(ueda, cycles=2000, separation=1e-6)
    assert abs(two.exponent - 0.0999) <= 3 * two.error + 0.005


@pytest.mark.parametrize("scene", [PERIODIC_FIG4, CHAOTIC_FIG4], ids=["periodic", "chaotic"])
def test_sum_of_exponents_equals_mean_trace_towers(scene):
    """docs/model.md 12: sum of all 12 exponents = -2(zx_A + zy_A + zt_A Om_tA) - ... ."""
    spec = lyapunov_spectrum(scene, cycles=60, tangent_transient=5)
    assert spec.exponents.shape == (12,)
    d = scene.to_dict()
    expected = (-2 * (0.03 + 0.03 + 0.03 * d["Om_tA"]) - 2 * 1.5 * (0.03 + 0.03)
                - 2 * 0.03 * d["Om_tB"])
    assert spec.trace == pytest.approx(expected, rel=1e-12)
    assert spec.exponents.sum() == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("period_ratio", [0.7, 1.1])
def test_sum_of_exponents_equals_mean_trace_pair(period_ratio):
    scene = load_preset("fig4-translational").with_params(period_ratio=period_ratio, rtol=1e-8)
    spec = lyapunov_spectrum(scene, cycles=100, tangent_transient=5)
    assert spec.exponents.shape == (4,)
    expected = -2 * 0.03 - 2 * 1.5 * 0.03
    assert spec.exponents.sum() == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("preset", ["fig3a", "fig4-translational", "tower-wall", "wall"])
def test_without_contact_exponents_are_the_linear_damping_rates(preset):
    """Large gap: the exponents are the real parts of the structural eigenvalues."""
    scene = load_preset(preset).with_params(gap=1e4, rtol=1e-10, atol=1e-12)
    system = System.from_scene(scene)
    spec = lyapunov_spectrum(system, cycles=40, tangent_transient=10, transient=5)
    jac = np.zeros((system.dim, system.dim))
    jacobian(system.model_id, 0.0, np.zeros(system.dim), system.params, jac)
    rates = np.sort(np.linalg.eigvals(jac).real)[::-1]
    np.testing.assert_allclose(spec.exponents, rates, atol=2e-3)
    # the damped translational oscillators of the pair: -zeta Om, twice each
    if preset == "fig4-translational":
        np.testing.assert_allclose(spec.exponents, [-0.03, -0.03, -0.045, -0.045], atol=2e-3)


def test_periodic_scene_has_clearly_negative_largest_exponent():
    spec = lyapunov_spectrum(PERIODIC_FIG4, k=1, cycles=100, tangent_transient=10)
    assert spec.max_exponent + 5 * spec.max_error < -0.01


def test_chaotic_scene_positive_and_methods_agree():
    """fig4 at T/T_Ax = 0.9: positive largest exponent, two methods within error bars."""
    spec = lyapunov_spectrum(CHAOTIC_FIG4, k=1, cycles=300, tangent_transient=10)
    assert spec.max_exponent > 3 * spec.max_error
    two = largest_exponent_two_trajectory(CHAOTIC_FIG4.with_params(rtol=1e-11, atol=1e-13),
                                          cycles=300, separation=1e-6)
    combined = np.hypot(spec.max_error, two.error)
    assert abs(spec.max_exponent - two.exponent) <= 3 * combined


def test_kaplan_yorke_dimension():
    assert kaplan_yorke(np.array([-0.1, -0.2])) == 0.0
    assert kaplan_yorke(np.array([0.5, 0.0, -1.0])) == pytest.approx(2.5)
    assert kaplan_yorke(np.array([0.1, 0.0])) == 2.0


def test_bad_arguments_are_rejected():
    with pytest.raises(ValueError, match="k = 13"):
        lyapunov_spectrum(CHAOTIC_FIG4, k=13)
    with pytest.raises(ValueError, match="n_blocks"):
        lyapunov_spectrum(CHAOTIC_FIG4, n_blocks=1)
