"""Stable periodic orbits found without the variational equations, and the two checks
of a point contact's tangent dynamics on them (test_saltation, test_jankowski_tangent)."""

import json
import math
from dataclasses import replace

import numpy as np

from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
from chaospound.dynamics.system import System
from chaospound.orbits import StroboscopicMap, find_orbit, finite_difference_monodromy
from chaospound.orbits.maps import variational_monodromy


def fd_orbits(scenes: dict) -> dict:
    """``case -> (map, orbit)`` for ``scenes = {case: scene}``: Newton on the
    finite-difference monodromy (every iteration's, at the map's tolerance), so that
    nothing rests on the variational one; ``orbit.monodromy`` is the finite difference
    at the solution. Each orbit must impact and be stable."""
    found = {}
    for case, scene in scenes.items():
        smap = replace(StroboscopicMap.of(scene,
                                          monodromy_provider=finite_difference_monodromy),
                       jacobian_rtol=None)
        orbit = find_orbit(smap, transient=60)
        assert orbit.impacts_per_period >= 1 and orbit.stable
        found[case] = (smap, orbit)
    return found


def assert_monodromy_is_the_finite_difference(smap, orbit) -> None:
    """The propagator monodromy of one period equals the orbit's finite difference to
    1e-6 of its largest entry."""
    reference = orbit.monodromy
    _, matrix = variational_monodromy(smap, orbit.state, 1)
    assert np.max(np.abs(matrix - reference)) < 1e-6 * np.max(np.abs(reference))


def assert_qr_exponent_is_log_of_the_largest_multiplier(smap, orbit, scene) -> None:
    """From the orbit's state, the QR largest exponent of ``scene`` (dop853, rtol
    1e-11) equals ``log |mu_1| / T`` of the finite-difference monodromy within three
    of its error bars."""
    expected = math.log(abs(orbit.multipliers[0])) / smap.system.period
    system = System.from_scene(scene.with_params(method="dop853", rtol=1e-11, atol=1e-13))
    spectrum = lyapunov_spectrum(system, k=1, transient=0, tangent_transient=20, cycles=60,
                                 n_blocks=6, initial_state=orbit.state)
    assert abs(spectrum.exponents[0] - expected) < 3 * spectrum.errors[0]


def assert_qr_agrees_with_two_trajectories(scene, cycles: int) -> None:
    """On a chaotic ``scene`` (dop853, rtol 1e-10): the QR largest exponent and the
    two-trajectory estimate over ``cycles`` (after 100) are clearly positive and agree
    within three combined standard errors."""
    scene = scene.with_params(method="dop853", rtol=1e-10, atol=1e-12)
    qr = lyapunov_spectrum(scene, k=1, cycles=cycles, transient=100)
    two = largest_exponent_two_trajectory(scene, cycles=cycles, transient=100)
    assert two.exponent > 3 * two.error and qr.exponents[0] > 3 * qr.errors[0]
    assert abs(qr.exponents[0] - two.exponent) < 3 * math.hypot(qr.errors[0], two.error)


def assert_cli_lyapunov_runs_on_the_wall(capsys, law: str) -> None:
    """``chaospound lyapunov`` on the wall with ``law`` (which it used to refuse) prints
    a QR spectrum, and its json says QR is available, with two finite exponents."""
    from chaospound.cli import main

    argv = ["lyapunov", "--preset", "wall", "--set", f"contact_law={law}",
            "--set", "method=dop853",  # the engines the orbit tests compiled
            "--transient", "5", "--record", "2", "--cycles", "10"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert "not available" not in out + err and "lambda (per unit t)" in out
    assert main([*argv, "--json", "--no-floquet"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["qr"]["available"] is True and len(document["exponents"]) == 2
    assert all(math.isfinite(x) for x in document["exponents"])
