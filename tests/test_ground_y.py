"""The ground's y component in the equations of motion (issue 15: the bi-directional
harmonic input of Gong & Hao 2005, docs/model.md section 5, docs/ground_motions.md 2).

Each tower's Y equation is driven by ``u_gy``: ``Y'' = -c_y (Y' - u_gy') - Om^2 [(Y -
u_gy) - e_x th] + mu Q_Y``, and the torsion's stiffness coupling reads ``e_y (X - u_g)
- e_x (Y - u_gy)``. The tests check the physics against closed forms and an independent
integration, the bitwise identity of every x-only run, an exact mirror symmetry and
the reductions a y component forbids.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from chaospound import load_preset
from chaospound.dynamics.system import System
from chaospound.engine.compose import Composition
from chaospound.physics.ground import sine
from chaospound.scene import Scene, SceneError
from chaospound.simulate import simulate

FAR = 1e6  #: a gap no motion here closes: no contact


def _steady_base_excited(t, amplitude, phase, w, om2, c):
    """Steady state of ``Y'' = -c (Y' - u') - om2 (Y - u)`` for ``u = a sin(w t + phase)``.

    ``Y = Im(a H e^{i(w t + phase)})`` with ``H = (om2 + i c w) / (om2 - w^2 + i c w)``.
    """
    h = (om2 + 1j * c * w) / (om2 - w * w + 1j * c * w)
    z = amplitude * h * np.exp(1j * (w * np.asarray(t) + phase))
    return z.imag, (1j * w * z).imag


def test_symmetric_towers_follow_the_closed_form_base_excitation():
    """No contact, e = 0: each tower's Y is the damped linear oscillator driven by the
    base motion u_gy = y_ratio sin(t/r + y_phase); started on its steady state it stays
    there (amplitude and phase of the transfer function), to 1e-8 at rtol 1e-12."""
    ratio, phase = 0.8, 0.4
    base = Scene().with_params(gap=FAR, ground_y_ratio=ratio, ground_y_phase=phase,
                               method="dop853", rtol=1e-12, atol=1e-14)
    r = base.excitation.period_ratio
    w = 1.0 / r
    om_b = base.freq_ratio
    towers = ((1.0, 2.0 * base.tower_A.zeta_y), (om_b * om_b, 2.0 * base.tower_B.zeta_y * om_b))
    state = np.zeros(12)
    for (om2, c), at in zip(towers, (2, 8), strict=True):
        state[at], state[at + 1] = _steady_base_excited(0.0, ratio, phase, w, om2, c)
    scene = base.with_params(initial_state=state.tolist())
    assert scene.model_name == "towers"
    sim = simulate(scene, transient=0, record=5, samples_per_cycle=16)
    assert sim.impacts.time.size == 0
    t = sim.trajectory.time
    for (om2, c), at in zip(towers, (2, 8), strict=True):
        y, v = _steady_base_excited(t, ratio, phase, w, om2, c)
        assert np.max(np.abs(sim.trajectory.state[:, at] - y)) < 1e-8 * ratio
        assert np.max(np.abs(sim.trajectory.state[:, at + 1] - v)) < 1e-8 * ratio
    # and the torsion stays at rest: e = 0 decouples it
    assert np.max(np.abs(sim.trajectory.state[:, [4, 5, 10, 11]])) < 1e-12


def _independent_rhs(scene: Scene):
    """The 12-state contact-free equations of docs/model.md section 5, from the scene's
    physical fields (not the packed vector): x and y ground motions both applied."""
    r = scene.excitation.period_ratio
    ratio, phase = scene.excitation.ground_y_ratio, scene.excitation.ground_y_phase
    blocks = []
    for tower, om in ((scene.tower_A, 1.0), (scene.tower_B, scene.freq_ratio)):
        om2 = om * om
        e2 = tower.e_x ** 2 + tower.e_y ** 2
        omt2 = om2 * (tower.length ** 2 + tower.w ** 2 + 4.0 * e2) / (4.0 * tower.rho2)
        blocks.append((om2, 2.0 * tower.zeta_x * om, 2.0 * tower.zeta_y * om,
                       2.0 * tower.zeta_t * math.sqrt(omt2), tower.e_x, tower.e_y,
                       tower.rho2, omt2))

    def rhs(t, s):
        ug, vg = math.sin(t / r), math.cos(t / r) / r
        ugy = ratio * math.sin(t / r + phase)
        vgy = ratio * math.cos(t / r + phase) / r
        out = np.empty(12)
        for i, (om2, cx, cy, ct, ex, ey, rho2, omt2) in enumerate(blocks):
            x, vx, y, vy, th, vth = s[6 * i:6 * i + 6]
            out[6 * i:6 * i + 6] = (
                vx, -cx * (vx - vg) - om2 * ((x - ug) + ey * th),
                vy, -cy * (vy - vgy) - om2 * ((y - ugy) - ex * th),
                vth, -ct * vth - om2 / rho2 * (ey * (x - ug) - ex * (y - ugy)) - omt2 * th)
        return out

    return rhs


def test_eccentric_towers_agree_with_an_independent_integration():
    """No contact, both towers eccentric in x and y: the y input couples into torsion
    through e_x and back into X through e_y; the engine (dop853, rtol 1e-12) agrees
    with scipy's DOP853 at rtol 1e-12 on the equations written out here, to 1e-8."""
    scene = Scene().with_params(gap=FAR, ground_y_ratio=0.7, ground_y_phase=-1.1,
                                ecc_x_A=6.0, ecc_y_A=-4.0, ecc_x_B=-3.0, ecc_y_B=5.0,
                                method="dop853", rtol=1e-12, atol=1e-14)
    sim = simulate(scene, transient=0, record=4, samples_per_cycle=8)
    assert sim.model == "towers" and sim.impacts.time.size == 0
    t = sim.trajectory.time
    ref = solve_ivp(_independent_rhs(scene), (0.0, t[-1]), np.zeros(12), method="DOP853",
                    rtol=1e-12, atol=1e-14, t_eval=t)
    assert ref.success
    scale = np.max(np.abs(ref.y), axis=1)
    assert np.all(scale[[2, 4, 8, 10]] > 1e-2)  # Y and th are driven, not just X
    np.testing.assert_allclose(sim.trajectory.state, ref.y.T, rtol=0.0, atol=1e-8)
    # the difference the y input makes is far above that agreement
    x_only = simulate(scene.with_params(ground_y_ratio=0.0), transient=0, record=4,
                      samples_per_cycle=8)
    assert np.max(np.abs(x_only.trajectory.state - sim.trajectory.state)) > 1e-1


def _assert_same_run(a, b):
    for name in ("time", "velocity", "corner", "contact_y", "peak_force", "state"):
        assert np.array_equal(getattr(a.impacts, name), getattr(b.impacts, name)), name
    assert np.array_equal(a.strobe.state, b.strobe.state)
    assert np.array_equal(a.final_state, b.final_state)


def test_zero_y_ratio_is_bitwise_the_x_only_run():
    """fig3a: ``ground_y_ratio = 0`` (any phase) selects the x-only composition, and the
    y-carrying composition fed a zero y component gives bitwise the same impacts,
    sections and final state (x - 0.0 is x: tower_accel_xy reduces to tower_accel)."""
    scene = load_preset("fig3a")
    x_only = System.from_scene(scene)
    zero = System.from_scene(scene.with_params(ground_y_ratio=0.0, ground_y_phase=0.7))
    assert zero.composition == x_only.composition and not zero.ground_y
    reference = simulate(scene, transient=4, record=3)
    assert reference.impacts.time.size > 0
    _assert_same_run(simulate(zero, transient=4, record=3), reference)
    block = sine.block({"period_ratio": scene.excitation.period_ratio})
    carrying = replace(x_only, ground_y=True, params=np.concatenate((x_only.params, block)))
    assert carrying.composition.ground_y
    _assert_same_run(simulate(carrying, transient=4, record=3), reference)


def test_mirror_symmetry_of_a_symmetric_scene():
    """A scene symmetric about y = 0 (e_y = e_x = 0, offset_y = 0, at rest) is mapped to
    itself by the mirror y -> -y, under which X stays, Y and th change sign, and so does
    u_gy. So ``ground_y_ratio -> -ground_y_ratio`` (u_gy exactly negated) mirrors the
    motion: X equal, Y, Y', th, th' negated, impacts at the same times with the contact
    point at -y. Every operation of the right-hand side, the step control (|err|) and
    the event location commutes with negation exactly in IEEE arithmetic, so the
    mirror is bitwise."""
    scene = load_preset("fig4-translational").with_params(ground_y_ratio=0.6,
                                                          ground_y_phase=0.3)
    assert scene.model_name == "towers"
    a = simulate(scene, transient=2, record=3)
    b = simulate(scene.with_params(ground_y_ratio=-0.6), transient=2, record=3)
    assert a.impacts.time.size > 0
    sign = np.array([1, 1, -1, -1, -1, -1] * 2, dtype=float)
    assert np.max(np.abs(a.final_state[[2, 4]])) > 1e-3  # Y and th are excited
    assert np.array_equal(b.final_state, sign * a.final_state)
    assert np.array_equal(b.strobe.state, sign * a.strobe.state)
    assert np.array_equal(b.impacts.time, a.impacts.time)
    assert np.array_equal(b.impacts.velocity, a.impacts.velocity)
    assert np.array_equal(b.impacts.contact_y, -a.impacts.contact_y)
    assert np.any(a.impacts.contact_y != 0.0)  # corner impacts, off the centre line


def test_pounding_with_y_input_converges_across_methods():
    """fig3a with a y component, with contact: DOPRI5 and DOP853 at rtol 1e-10 agree on
    every impact (time, velocity) and the final state over a short window."""
    scene = load_preset("fig3a").with_params(ground_y_ratio=0.5, ground_y_phase=0.9,
                                             rtol=1e-10, atol=1e-13)
    a = simulate(scene, transient=0, record=4)
    b = simulate(scene.with_params(method="dop853"), transient=0, record=4)
    assert a.impacts.time.size > 0 and a.impacts.time.size == b.impacts.time.size
    np.testing.assert_allclose(a.impacts.time, b.impacts.time, rtol=0, atol=1e-6)
    np.testing.assert_allclose(a.impacts.velocity, b.impacts.velocity, rtol=0, atol=1e-6)
    np.testing.assert_allclose(a.final_state, b.final_state, rtol=0, atol=1e-6)
    x_only = simulate(load_preset("fig3a").with_params(rtol=1e-10, atol=1e-13), transient=0,
                      record=4)
    assert np.max(np.abs(x_only.final_state - a.final_state)) > 1e-2


def test_tangent_dynamics_with_y_input():
    """The y input does not depend on the state, so the Jacobian is unchanged: the QR
    spectrum's sum equals the constant trace (minus the sum of the damping
    coefficients) to the integration tolerance with contact and a y input, and the
    propagator composition builds."""
    from chaospound.dynamics.lyapunov import lyapunov_spectrum

    scene = load_preset("tower-wall").with_params(ground_y_ratio=0.5, rtol=1e-9, atol=1e-12)
    system = System.from_scene(scene)
    assert system.composition.ground_y and system.model_name == "tower-wall"
    spectrum = lyapunov_spectrum(system, transient=5, tangent_transient=2, cycles=20,
                                 n_blocks=2)
    module = system.engine("qr").module
    assert float(np.sum(spectrum.exponents)) == pytest.approx(
        module.model_trace(system.params), rel=1e-6)
    assert system.engine("propagator").composition.ground_y


def test_a_y_ground_refuses_the_reductions_without_y():
    """A y ground motion drives Y even in a symmetric scene: "auto" picks towers
    (tower-wall against a wall), and a forced pair or wall model is refused."""
    symmetric = load_preset("fig4-translational")
    assert symmetric.model_name == "pair"
    assert symmetric.with_params(ground_y_ratio=0.3).model_name == "towers"
    wall = load_preset("wall")
    assert wall.model_name == "wall"
    assert wall.with_params(ground_y_ratio=0.3).model_name == "tower-wall"
    with pytest.raises(SceneError, match="ground_y_ratio"):
        symmetric.with_params(ground_y_ratio=0.3, model="pair")
    with pytest.raises(SceneError, match="ground_y_ratio"):
        wall.with_params(ground_y_ratio=0.3, model="wall")
    two = wall.with_params(ground="stochastic", ground_pga=0.3, length_unit=0.01,
                           tower_period=0.5, ground_components=2)
    assert two.model_name == "tower-wall" and System.from_scene(two).ground_y
    assert wall.with_params(ground="stochastic", ground_pga=0.3, length_unit=0.01,
                            tower_period=0.5).model_name == "wall"
    with pytest.raises(ValueError, match="Y degree of freedom"):
        Composition(model="pair", ground_y=True)
    with pytest.raises(ValueError, match="no y component"):
        Composition(model="towers", ground="none", ground_y=True)


def test_y_parameters_are_checked_and_round_trip():
    """ground_y_ratio only with the sine; finite values; TOML keeps them."""
    with pytest.raises(SceneError, match="ground_y_ratio"):
        Scene().with_params(ground="none", ground_y_ratio=0.5)
    with pytest.raises(SceneError, match="ground_y_phase"):
        Scene().with_params(ground_y_phase=float("nan"))
    scene = load_preset("fig3a").with_params(ground_y_ratio=0.5, ground_y_phase=0.25)
    again = Scene.from_toml(scene.to_toml())
    assert again == scene
    p = scene.pack()
    assert np.array_equal(p[-3:], [scene.excitation.period_ratio, 0.5, 0.25])
    assert load_preset("fig3a").pack().size == p.size - 3
