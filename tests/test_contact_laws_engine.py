"""The contact laws inside the composed engine: wired, checked by independent means.

The laws' own formulas are tests/test_contact_laws.py's subject; here they run
in the engine: an impact against the wall integrated by the engine equals the
same equations integrated by scipy at tight tolerance, the engine's monodromy
matrix with a rate-dependent law equals a finite difference of its flow (the
damping terms of the variational equations), Hertz stays bitwise Hertz, and
what the engine cannot linearise yet is refused with one clear line.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from chaospound import load_preset
from chaospound.dynamics.system import System, advance, monodromy
from chaospound.kernels.params import P_GAP, P_PERIOD, T_CX, T_MU, T_OM2, TOWER_A
from chaospound.physics.contact import hertzdamp, hunt_crossley, jankowski, kelvin_voigt
from chaospound.simulate import simulate

DISSIPATIVE = ["hertzdamp", "hunt-crossley", "jankowski", "kelvin-voigt"]
MODULES = {"hertzdamp": hertzdamp, "hunt-crossley": hunt_crossley, "jankowski": jankowski,
           "kelvin-voigt": kelvin_voigt}


def _wall(law: str, e: float = 0.6):
    """The wall model at rest on its spring, ground still, struck at 2 A_g omega_Ax."""
    return load_preset("wall").with_params(
        contact_law=law, restitution=e, ground="none", gap=0.5, method="dop853",
        rtol=1e-12, atol=1e-14, initial_state=[0.0, 2.0] + [0.0] * 10)


@pytest.mark.parametrize("law", DISSIPATIVE)
def test_an_impact_in_the_engine_equals_scipy(law):
    scene = _wall(law)
    system = System.from_scene(scene)
    p = system.params.copy()
    module = MODULES[law]
    base = p.size - len(module.PARAMETERS) - len(module.MEMORY)
    c, om2, mu, gap = (p[TOWER_A + T_CX], p[TOWER_A + T_OM2], p[TOWER_A + T_MU], p[P_GAP])
    t_end = 3.0  # one impact: approach, contact, rebound, free flight

    def rhs(t, y):
        d = y[0] - gap
        return [y[1], -c * y[1] - om2 * y[0] - mu * module.point_force(p, base, d, y[1])]

    def touch(t, y):
        return y[0] - gap
    touch.direction = 1.0
    touch.terminal = True
    # free flight to the onset, the law's memory set there, then through the impact
    first = solve_ivp(rhs, (0.0, t_end), [0.0, 2.0], method="DOP853", rtol=1e-13,
                      atol=1e-15, events=touch)
    t_on, y_on = first.t_events[0][0], first.y_events[0][0]
    module.on_onset(p, base, y_on[1])
    rest = solve_ivp(rhs, (t_on, t_end), y_on, method="DOP853", rtol=1e-13, atol=1e-15)
    reference = rest.y[:, -1]

    assert rest.y[0].max() > gap + 1e-3  # the reference went through an impact
    # the engine over one section interval of length t_end (the packed P_PERIOD)
    engine_p = system.params.copy()
    engine_p[P_PERIOD] = t_end
    y = np.array([0.0, 2.0])
    stats = np.zeros(6, dtype=np.int64)
    system.engine().run_cycles(engine_p, y, np.zeros(3), 1, 1, 1e-12, 1e-14, 0.1, 10**6, True,
                               0, np.zeros((1, 2)), np.zeros((1, 3)), np.zeros((0, 9)),
                               np.zeros((0, 2)), stats, np.zeros((0, 0)))
    assert stats[5] == 0  # STATUS_OK
    assert np.max(np.abs(y - reference)) < 1e-8


@pytest.mark.parametrize("preset", [
    "fig3a",
    pytest.param("tower-wall", marks=pytest.mark.slow),  # two engines of its own: -m slow
])
def test_monodromy_with_a_rate_dependent_law_is_the_flows_derivative(preset):
    """Jankowski's damping enters the variational equations of the line contact (no
    memory, no jumps)."""
    scene = load_preset(preset).with_params(contact_law="jankowski", restitution=0.6,
                                            method="dop853", rtol=1e-12, atol=1e-14)
    system = System.from_scene(scene)
    state, _, _ = advance(system, system.initial_state, 30, from_time_zero=True)
    _, matrix = monodromy(system, state, 1)
    n = state.size
    reference = np.empty((n, n))
    for j in range(n):  # 5-point stencil
        step = 1e-4 * max(1.0, abs(state[j]))
        values = []
        for m in (-2, -1, 1, 2):
            shifted = state.copy()
            shifted[j] += m * step
            values.append(advance(system, shifted, 1)[0])
        reference[:, j] = (values[0] - 8 * values[1] + 8 * values[2] - values[3]) / (12 * step)
    assert np.max(np.abs(matrix - reference)) < 1e-6 * np.max(np.abs(reference))


def test_elastic_laws_keep_the_hertz_results():
    """An explicit contact_law = "hertz" is the default scene, bit for bit."""
    scene = load_preset("fig3a")
    a = simulate(scene, transient=5, record=2)
    b = simulate(scene.with_params(contact_law="hertz", restitution=0.3), transient=5, record=2)
    assert a.final_state.tobytes() == b.final_state.tobytes()
    assert a.impacts.velocity.tobytes() == b.impacts.velocity.tobytes()


def test_dissipation_lowers_the_rebound():
    """The same impact rebounds slower the lower e (a physics sanity check)."""
    rebound = []
    for e in (0.9, 0.6, 0.3):
        sim = simulate(_wall("hertzdamp", e).with_params(rtol=1e-9, atol=1e-12),
                       transient=0, record=1)
        rebound.append(-sim.strobe.state[-1][1])
    assert rebound[0] > rebound[1] > rebound[2]


def test_tangent_dynamics_are_composed_for_every_law_on_the_point_models():
    """Every law's tangent dynamics on the point models: the laws with memory carry its
    sensitivity (tests/test_contact_tangent.py), Kelvin-Voigt's jumping force its
    saltation matrix (tests/test_saltation.py) and Jankowski's singular Jacobian the
    approach phase's shift (tests/test_jankowski_tangent.py), which only its point
    modules compile, and a run without vectors skips (a plain run shares the tangent
    module); a model that does not carry a law's memory is refused."""
    from chaospound.engine.compose import Composition, check_tangent, generate_source

    for model in ("wall", "pair"):
        for law in ("jankowski", "kelvin-voigt", "hertzdamp", "hunt-crossley"):
            check_tangent(Composition(model, law, tangent="propagator"))
        assert "LAW_SHIFTED = True" in generate_source(Composition(model, "jankowski",
                                                                   tangent="qr"))
        plain = Composition(model, "jankowski")
        assert plain.compiled() == Composition(model, "jankowski", tangent="qr")
        assert generate_source(plain) == generate_source(plain.with_tangent("propagator"))
        assert "LAW_SHIFTED = False" in generate_source(Composition(model, "kelvin-voigt",
                                                                    tangent="qr"))
    assert "LAW_SHIFTED = False" in generate_source(Composition("towers", "jankowski",
                                                                tangent="qr"))
    with pytest.raises(ValueError, match="not available"):
        check_tangent(Composition("lorenz", "hertzdamp", tangent="qr"))
    # ... and its plain runs keep a module of their own
    assert Composition("lorenz", "hertzdamp").compiled().tangent == "none"


def test_a_law_rejects_an_impossible_restitution():
    from chaospound.scene import SceneError

    with pytest.raises(SceneError, match="restitution"):
        load_preset("wall").with_params(contact_law="hertzdamp", restitution=1.5)
