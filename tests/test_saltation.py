"""Kelvin-Voigt on a point contact: the saltation matrix at every jump of the force.

docs/contact_laws.md section 7. On the wall and pair models the Kelvin-Voigt
force ``k d + c d'`` jumps by ``c d'`` at an onset and, plain, by ``-c d'`` at a
release; the engine maps the tangent vectors by the saltation matrix there
(and, with no_pull, lands on the switch ``k d + c d' = 0``, where only the
Jacobian jumps). Checked by independent means on stable period-1 orbits (T/T_Ax
= 0.7 for the wall, 1.2 for the pair, e = 0.65, one and two impacts a period, found by
Newton on a finite-difference monodromy, so that nothing here rests on the
variational one) and on a chaotic pair scene:

* the propagator monodromy equals the 5-point finite-difference monodromy of
  the stroboscopic map (without the saltation it missed by 0.37 % (wall) and
  0.89 % (pair) of its largest entry for the plain law, by 8.0 and 7.7 times
  it with no_pull);
* the QR largest exponent equals ``log |mu_1| / T`` of the finite-difference
  monodromy, and the two-trajectory estimate on the chaotic scene.

For the plain law the saltation is a similarity (``M = P M0 P^-1``, ``P = k I +
c J_free``: section 7), so the multipliers and the exponents, unlike the
matrix, do not show it; with no_pull they do (without it the QR exponents on
the orbits were +0.36 instead of -0.12 (wall) and +0.15 instead of -0.016
(pair), on the chaotic pair 0.13 instead of 0.03): each exponent check has a
no-pull case that fails without the saltation.
"""

from __future__ import annotations

import pytest
from pointorbits import (
    assert_cli_lyapunov_runs_on_the_wall,
    assert_monodromy_is_the_finite_difference,
    assert_qr_agrees_with_two_trajectories,
    assert_qr_exponent_is_log_of_the_largest_multiplier,
    fd_orbits,
)

from chaospound import load_preset

#: (preset, period ratio, no_pull): stable impacting period-1 orbits
ORBITS = [("wall", 0.7, False), ("wall", 0.7, True),
          ("fig4-translational", 1.2, False), ("fig4-translational", 1.2, True)]
IDS = ["wall", "wall-no-pull", "pair", "pair-no-pull"]


def _scene(preset: str, ratio: float, no_pull: bool, e: float = 0.65):
    return load_preset(preset).with_params(contact_law="kelvin-voigt", restitution=e,
                                           period_ratio=ratio, no_pull=no_pull)


@pytest.fixture(scope="module")
def orbits():
    """``case -> (map, orbit)`` (:func:`pointorbits.fd_orbits`)."""
    return fd_orbits({case: _scene(*case) for case in ORBITS})


@pytest.mark.parametrize("case", ORBITS, ids=IDS)
def test_monodromy_across_the_force_jumps_is_the_finite_difference(orbits, case):
    """The propagator monodromy of one period (the saltation at the onset and the
    release, the no-pull switch landed) equals the 5-point finite difference to
    1e-6 of its largest entry at rtol 1e-12 (measured 2e-8 to 1.2e-7)."""
    assert_monodromy_is_the_finite_difference(*orbits[case])


@pytest.mark.parametrize("case", ORBITS, ids=IDS)
def test_qr_exponent_is_log_of_the_largest_multiplier(orbits, case):
    """From the orbit's state, the QR largest exponent equals ``log |mu_1| / T`` of
    the finite-difference monodromy within three of its error bars."""
    assert_qr_exponent_is_log_of_the_largest_multiplier(*orbits[case], _scene(*case))


@pytest.mark.parametrize("ratio,e,no_pull", [(1.25, 0.65, False), (1.24, 0.8, True)],
                         ids=["plain", "no-pull"])
def test_qr_and_two_trajectory_agree_on_a_chaotic_pair(ratio, e, no_pull):
    """fig4-translational near T/T_Ax = 1.25 is chaotic with Kelvin-Voigt: the QR
    largest exponent (1000 cycles) and the two-trajectory estimate agree within
    three combined standard errors, and are clearly positive."""
    assert_qr_agrees_with_two_trajectories(_scene("fig4-translational", ratio, no_pull, e), 1000)


def test_cli_lyapunov_on_the_wall_with_kelvin_voigt(capsys):
    """The QR spectrum of the wall with Kelvin-Voigt, which the CLI used to refuse."""
    assert_cli_lyapunov_runs_on_the_wall(capsys, "kelvin-voigt")
