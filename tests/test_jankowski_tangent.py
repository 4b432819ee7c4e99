"""Jankowski on a point contact: the approach phase's shifted tangent vectors.

docs/contact_laws.md section 7. Jankowski's point force ``beta d^chi + c(d) d'``
(approaching; ``c(d) = c_s d^(1/4)``) is continuous, but its Jacobian has the
term ``dF/dd ~ c'(d) d' ~ d^(-3/4)`` after every onset, which no Runge-Kutta
stage can sample. The engine integrates ``w = v - c(d) e_F (grad(d) . v)`` while
approaching (bounded equations), lands on the switch d' = 0 and converts there
and at every section. Checked by independent means on stable period-1 orbits
(T/T_Ax = 0.7 for the wall, 1.2 for the pair, e = 0.65, one and two impacts a
period, found by Newton on a finite-difference monodromy, so that nothing here
rests on the variational one), with the section also inside an approach, and
on a chaotic pair scene:

* the propagator monodromy equals the 5-point finite-difference monodromy of
  the stroboscopic map (measured 2.4e-9 to 9.4e-8 of its largest entry);
* the QR largest exponent equals ``log |mu_1| / T`` of the finite-difference
  monodromy, and the two-trajectory estimate on the chaotic scene.

The law's own Jacobian (the refusal lifted, nothing else) stops every run at
the first onset ("step size fell below round-off", at any rtol from 1e-6 to
1e-12). Without the shift (the switch landed, but ``point_shift`` returning 0:
the approach's damping dropped from the Jacobian) the monodromies miss by 1.1
to 8.3 times their largest entry and the QR exponents are +0.351 (wall) and
+0.144 (pair), on the chaotic pair 0.142 (15 combined standard errors off);
without the conversions at the sections the orbits sectioned inside an
approach miss by 79 % (wall) and 63 % (pair) of the largest entry.
"""

from __future__ import annotations

import numpy as np
import pytest
from pointorbits import (
    assert_cli_lyapunov_runs_on_the_wall,
    assert_monodromy_is_the_finite_difference,
    assert_qr_agrees_with_two_trajectories,
    assert_qr_exponent_is_log_of_the_largest_multiplier,
    fd_orbits,
)

from chaospound import load_preset

#: (preset, period ratio, section phase): stable impacting period-1 orbits, sectioned
#: between impacts and inside an approach phase (wall: onset at 0.306 T, the section
#: 0.006 T later; pair: onset at 0.107 T, the section 0.004 T later)
ORBITS = [("wall", 0.7, 0.0), ("wall", 0.7, 0.312),
          ("fig4-translational", 1.2, 0.0), ("fig4-translational", 1.2, 0.111)]
IDS = ["wall", "wall-approach-section", "pair", "pair-approach-section"]


def _scene(preset: str, ratio: float, phase: float = 0.0, e: float = 0.65):
    return load_preset(preset).with_params(contact_law="jankowski", restitution=e,
                                           period_ratio=ratio, phase=phase)


@pytest.fixture(scope="module")
def orbits():
    """``case -> (map, orbit)`` (:func:`pointorbits.fd_orbits`)."""
    return fd_orbits({case: _scene(*case) for case in ORBITS})


def test_the_approach_sections_fall_inside_an_approach(orbits):
    """The orbits' sections at phase > 0 lie in contact with d' > 0 (the vectors are
    shifted there), those at phase 0 out of contact."""
    for case in ORBITS:
        smap, orbit = orbits[case]
        system = smap.system
        ends = np.zeros(4)
        system.engine().module.model_ends(case[2] * system.period, orbit.state,
                                          system.params, ends)
        approaching = ends[0] > 0.0 and ends[2] > 0.0
        assert approaching == (case[2] > 0.0), (case, ends)


@pytest.mark.parametrize("case", ORBITS, ids=IDS)
def test_monodromy_through_the_singular_onsets_is_the_finite_difference(orbits, case):
    """The propagator monodromy of one period (the approach phases shifted, the switch
    d' = 0 landed) equals the 5-point finite difference to 1e-6 of its largest entry at
    rtol 1e-12 (measured 2.4e-9 to 9.4e-8)."""
    assert_monodromy_is_the_finite_difference(*orbits[case])


@pytest.mark.parametrize("case", ORBITS, ids=IDS)
def test_qr_exponent_is_log_of_the_largest_multiplier(orbits, case):
    """From the orbit's state, the QR largest exponent equals ``log |mu_1| / T`` of
    the finite-difference monodromy within three of its error bars."""
    assert_qr_exponent_is_log_of_the_largest_multiplier(*orbits[case], _scene(*case))


def test_qr_and_two_trajectory_agree_on_a_chaotic_pair():
    """fig4-translational at T/T_Ax = 1.25, e = 0.65 is chaotic with Jankowski: the QR
    largest exponent (300 cycles) and the two-trajectory estimate agree within three
    combined standard errors, and are clearly positive."""
    assert_qr_agrees_with_two_trajectories(_scene("fig4-translational", 1.25), 300)


def test_cli_lyapunov_on_the_wall_with_jankowski(capsys):
    """The QR spectrum of the wall with Jankowski, which the CLI used to refuse."""
    assert_cli_lyapunov_runs_on_the_wall(capsys, "jankowski")
