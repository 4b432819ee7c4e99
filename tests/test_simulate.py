"""Physics of the event-aware simulator (docs/model.md sections 5-12).

Every test compares a run against an invariant or an independent result:
energy conservation, the exact reductions, the mirror symmetry, a fine
fixed-step reference for grazing contacts, the geometry of located events,
the closed-form periodic response of the linear oscillator, agreement between
Runge-Kutta schemes, the effect of landing steps on the contact kinks, and
determinism.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from kernels_by_name import models

from chaospound.kernels.params import MODEL_DIMS
from chaospound.scene import load_preset
from chaospound.simulate import simulate

# ------------------------------------------------------------------ helpers

#: 12-state indices of the lateral (Y, Y', th, th') states of A and B
LATERAL = (2, 3, 4, 5, 8, 9, 10, 11)
#: mirror y -> -y: X unchanged, Y and th negated
MIRROR = np.array([1, 1, -1, -1, -1, -1] * 2, dtype=float)
MIRRORED_LABEL = {"face": "face", "A+": "A-", "A-": "A+", "B+": "B-", "B-": "B+"}
PAIR_IN_TOWERS = [0, 1, 6, 7]


def end_series(scene, times, states):
    """(d_lo, d_hi, rate_lo, rate_hi) at each sample, shape (n, 4)."""
    model, p = scene.model_id(), scene.pack()
    out = np.empty(4)
    rows = np.empty((len(times), 4))
    for i, (t, y) in enumerate(zip(times, states, strict=True)):
        models.contact_ends(model, t, y, p, out)
        rows[i] = out
    return rows


def force_series(scene, times, states):
    """Resultant contact force on A along -x at each sample."""
    model, p = scene.model_id(), scene.pack()
    q = np.empty(6)
    pairs = zip(times, states, strict=True)
    return np.array([models.contact_forces(model, t, y, p, q) for t, y in pairs])


def parabola_vertex(t, v, i):
    """Value of the parabola through samples i-1, i, i+1 at its vertex."""
    tt, vv = t[i - 1 : i + 2], v[i - 1 : i + 2]
    a, b, c = np.polyfit(tt - tt[1], vv, 2)
    return c - b * b / (4.0 * a) if a < 0.0 else vv[1]


def downward_zero(t, v, start):
    """First time after ``start`` where ``v`` crosses 0 downwards (quadratic refine)."""
    j = np.searchsorted(t, start, side="right")
    k = j + int(np.argmax(v[j:] < 0.0))
    assert v[k] < 0.0 <= v[k - 1], "no release in the trajectory"
    lo = max(k - 2, 0)
    tt, vv = t[lo : k + 1], v[lo : k + 1]
    roots = np.roots(np.polyfit(tt - t[k - 1], vv, 2)) + t[k - 1]
    roots = roots[np.isreal(roots)].real
    roots = roots[(roots >= t[k - 1] - 1e-12) & (roots <= t[k] + 1e-12)]
    return float(roots[0]) if len(roots) else t[k - 1] - v[k - 1] * (t[k] - t[k - 1]) / (
        v[k] - v[k - 1]
    )


def contact_free_periodic(scene):
    """Complex amplitude Y of the contact-free steady response y = Re[Y exp(i t / r)].

    Without contact the equations of motion are linear, y' = J y + f(t) with
    f(t) = b cos(t/r) + a sin(t/r); J from the analytic Jacobian far from
    contact, a and b from the right-hand side at y = 0.
    """
    far = scene.with_params(gap=1e6, initial_state=None)
    model, p = far.model_id(), far.pack()
    n = MODEL_DIMS[model]
    jac = np.zeros((n, n))
    models.jacobian(model, 0.0, np.zeros(n), p, jac)
    r = scene.excitation.period_ratio
    f_cos, f_sin = np.empty(n), np.empty(n)
    models.rhs(model, 0.0, np.zeros(n), p, f_cos)
    models.rhs(model, 0.5 * math.pi * r, np.zeros(n), p, f_sin)
    return np.linalg.solve(1j / r * np.eye(n) - jac, f_cos - 1j * f_sin)


def contact_free_max_approach(scene, amplitude):
    """max over t of max(d_lo, d_hi) + gap on the contact-free periodic response."""
    far = scene.with_params(gap=1e6, initial_state=None)
    model, p = far.model_id(), far.pack()
    r = scene.excitation.period_ratio
    out = np.empty(4)

    def approach(t):
        models.contact_ends(model, t, np.real(amplitude * np.exp(1j * t / r)), p, out)
        return max(out[0], out[1]) + 1e6

    grid = np.linspace(0.0, scene.period, 4001)
    values = np.array([approach(t) for t in grid])
    i = int(np.argmax(values))
    lo, hi = grid[i - 1], grid[i + 1]
    for _ in range(200):  # golden section on the bracketing interval
        a = hi - 0.618033988749895 * (hi - lo)
        b = lo + 0.618033988749895 * (hi - lo)
        if approach(a) > approach(b):
            hi = b
        else:
            lo = a
    return approach(0.5 * (lo + hi))


# ========================================= 1. energy (docs/model.md section 7)
ENERGY_CASES = [
    # preset, initial state (12 entries), cycles; the scene picks the model
    ("fig3a", [0, 2, 0.5, 0.1, 0.01, -0.005, 0, -2, -0.3, 0.2, -0.01, 0.003], 200, "towers"),
    ("fig4-translational", [0, 2, 0, 0, 0, 0, 0, -2, 0, 0, 0, 0], 200, "pair"),
    ("tower-wall", [0, 2, 0.5, 0.1, 0.01, -0.005] + [0] * 6, 200, "tower-wall"),
    ("wall", [0, 2] + [0] * 10, 260, "wall"),
]


@pytest.mark.parametrize(("preset", "initial", "cycles", "model"), ENERGY_CASES,
                         ids=[c[0] for c in ENERGY_CASES])
def test_energy_is_conserved_without_damping_and_ground_motion(preset, initial, cycles, model):
    scene = load_preset(preset).with_params(
        zeta=0, ground="none", rtol=1e-10, atol=1e-12, initial_state=initial
    )
    sim = simulate(scene, transient=0, record=cycles, samples_per_cycle=40)
    assert sim.model == model
    assert len(sim.impacts) >= 200, f"only {len(sim.impacts)} impacts"
    mid, p = scene.model_id(), scene.pack()
    e0 = models.energy(mid, scene.initial_vector(), p)
    dense = np.array([models.energy(mid, y, p) for y in sim.trajectory.state])
    strobe = np.array([models.energy(mid, y, p) for y in sim.strobe.state])
    assert np.all(np.isfinite(dense)) and len(dense) == 40 * cycles + 1
    # the samples do see the contact: the potential takes a good share of E
    v_max = max(models.contact_potential(mid, 0.0, y, p) for y in sim.trajectory.state)
    assert v_max > 1e-3 * e0
    drift = max(np.max(np.abs(dense - e0)), np.max(np.abs(strobe - e0))) / e0
    assert drift <= 1e-6, f"relative energy drift {drift:.2e}"  # measured 5e-9 .. 1.3e-7


# ======================================= 2. reductions (docs/model.md section 9)
@pytest.mark.parametrize(
    ("preset", "flat", "model"),
    [
        ("fig3a", {}, "towers"),
        ("fig3b", {}, "towers"),
        ("fig4", {}, "towers"),
        ("fig4-translational", {}, "pair"),
        ("wall", {}, "wall"),
        ("tower-wall", {}, "tower-wall"),
        ("fig4-translational", {"model": "towers"}, "towers"),
        ("wall", {"model": "tower-wall"}, "tower-wall"),
    ],
)
def test_simulation_reports_the_model_it_ran(preset, flat, model):
    scene = load_preset(preset).with_params(**flat)
    sim = simulate(scene, transient=0, record=1)
    assert sim.model == model == scene.model_name
    assert sim.strobe.state.shape == (2, MODEL_DIMS[scene.model_id()])
    assert len(sim.state_names) == sim.final_state.shape[0]


def _compare_reduction(small, big, index):
    """Impacts and sections of a reduced run against the larger model's run."""
    ia, ib = small.impacts, big.impacts
    assert len(ia) == len(ib)
    assert set(ib.labels) <= {"face"}  # symmetric: d_lo == d_hi, a face impact
    np.testing.assert_allclose(ib.time, ia.time, rtol=0, atol=1e-8)
    np.testing.assert_allclose(ib.velocity, ia.velocity, rtol=0, atol=1e-8)
    np.testing.assert_allclose(ib.peak_penetration, ia.peak_penetration, rtol=1e-8, atol=0)
    np.testing.assert_allclose(ib.peak_force, ia.peak_force, rtol=1e-8, atol=0)
    np.testing.assert_allclose(ib.duration, ia.duration, rtol=0, atol=1e-8)
    np.testing.assert_allclose(ib.state[:, index], ia.state, rtol=0, atol=1e-8)
    np.testing.assert_allclose(big.strobe.state[:, index], small.strobe.state, rtol=0, atol=1e-8)


@pytest.mark.parametrize("period_ratio", [0.5, 0.7, 1.0, 1.3])
def test_pair_model_equals_towers_model_on_a_symmetric_scene(period_ratio):
    scene = load_preset("fig4-translational").with_params(
        period_ratio=period_ratio, rtol=1e-11, atol=1e-13
    )
    pair = simulate(scene, transient=20, record=4, samples_per_cycle=50)
    towers = simulate(scene.with_params(model="towers"), transient=20, record=4,
                      samples_per_cycle=50)
    assert (pair.model, towers.model) == ("pair", "towers")
    assert len(pair.impacts) > 0
    lateral = list(LATERAL)
    # Y and th stay identically zero, not just small
    assert np.all(towers.trajectory.state[:, lateral] == 0.0)
    assert np.all(towers.strobe.state[:, lateral] == 0.0)
    assert np.all(towers.impacts.state[:, lateral] == 0.0)
    _compare_reduction(pair, towers, PAIR_IN_TOWERS)  # measured <= 1.2e-9


@pytest.mark.parametrize("period_ratio", [0.5, 0.7, 1.0, 1.3])
def test_wall_model_equals_tower_wall_model_without_eccentricity(period_ratio):
    scene = load_preset("wall").with_params(period_ratio=period_ratio, rtol=1e-11, atol=1e-13)
    wall = simulate(scene, transient=20, record=4, samples_per_cycle=50)
    tower = simulate(scene.with_params(model="tower-wall"), transient=20, record=4,
                     samples_per_cycle=50)
    assert (wall.model, tower.model) == ("wall", "tower-wall")
    assert len(wall.impacts) > 0
    assert np.all(tower.trajectory.state[:, 2:] == 0.0)
    assert np.all(tower.impacts.state[:, 2:] == 0.0)
    _compare_reduction(wall, tower, [0, 1])  # measured <= 3e-10


# ================================================= 3. mirror symmetry y -> -y
def _assert_mirror(a, b, tol):
    ia, ib = a.impacts, b.impacts
    assert len(ia) == len(ib) > 0
    np.testing.assert_allclose(ib.time, ia.time, rtol=0, atol=tol)
    np.testing.assert_allclose(ib.velocity, ia.velocity, rtol=0, atol=tol)
    np.testing.assert_allclose(ib.peak_penetration, ia.peak_penetration, rtol=tol, atol=0)
    np.testing.assert_allclose(ib.contact_y, -ia.contact_y, rtol=0, atol=tol)
    np.testing.assert_allclose(ib.state * MIRROR, ia.state, rtol=0, atol=tol)
    np.testing.assert_allclose(b.strobe.state * MIRROR, a.strobe.state, rtol=0, atol=tol)
    assert ib.labels == [MIRRORED_LABEL[c] for c in ia.labels]


def test_fig3b_is_the_mirror_image_of_fig3a():
    tight = {"rtol": 1e-10, "atol": 1e-13}
    a = simulate(load_preset("fig3a").with_params(**tight))
    b = simulate(load_preset("fig3b").with_params(**tight))
    assert a.scene.tower_A.e_y == -b.scene.tower_A.e_y != 0.0
    _assert_mirror(a, b, 1e-9)  # measured: bitwise equal
    labels = set(a.impacts.labels)
    assert labels & {"A+", "B+", "A-", "B-"}, "fig3a should have corner impacts"


def test_mirror_symmetry_of_a_general_asymmetric_scene():
    state = [0.3, 0.5, 0.4, -0.2, 0.004, 0.01, -0.2, -0.4, -0.3, 0.1, -0.003, 0.02]
    base = load_preset("fig3a").with_params(
        ecc_x_A=3.0, ecc_y_A=7.0, ecc_x_B=-2.0, ecc_y_B=-4.0, length_B=80.0,
        offset_y=6.0, period_ratio=0.8, rtol=1e-10, atol=1e-13,
    )
    mirrored = base.with_params(
        ecc_y_A=-7.0, ecc_y_B=4.0, offset_y=-6.0,
        initial_state=list(np.array(state) * MIRROR),
    )
    a = simulate(base.with_params(initial_state=state), transient=10, record=6)
    b = simulate(mirrored, transient=10, record=6)
    _assert_mirror(a, b, 1e-9)


# ================================= 4. grazing contacts (docs/model.md section 8)
GRAZE_PRESETS = ("wall", "tower-wall", "fig3a")
GRAZE_DEPTHS = (2e-6, 1e-5, 1e-4, 1e-3)
GRAZE_CYCLES = 3


@functools.cache
def grazing_case(preset, depth):
    """A scene whose steady contact-free approach overshoots the gap by ``depth``.

    The run starts on the contact-free periodic orbit, so every cycle grazes
    with a peak penetration close to ``depth``. Returns the scene, the
    initial state and a fine fixed-step RK4 reference run that resolves every
    contact (20000 steps per cycle, steps landed on the kinks).
    """
    base = load_preset(preset)
    amplitude = contact_free_periodic(base)
    start = np.real(amplitude)
    scene = base.with_params(gap=contact_free_max_approach(base, amplitude) - depth)
    fine = simulate(scene.with_params(method="rk4", steps_per_cycle=20000),
                    transient=0, record=GRAZE_CYCLES, initial_state=start)
    return scene, start, fine


def _coarse(preset, depth, method, rtol):
    scene, start, fine = grazing_case(preset, depth)
    coarse = simulate(scene.with_params(method=method, rtol=rtol, atol=1e-12),
                      transient=0, record=GRAZE_CYCLES, initial_state=start)
    return coarse, fine


@pytest.mark.parametrize("depth", GRAZE_DEPTHS)
@pytest.mark.parametrize("preset", GRAZE_PRESETS)
def test_grazing_reference_grazes(preset, depth):
    _, _, fine = grazing_case(preset, depth)
    assert len(fine.impacts) == GRAZE_CYCLES  # one graze per cycle
    pen = fine.impacts.peak_penetration
    assert np.all((pen > 0.5 * depth) & (pen < 3.0 * depth)), pen
    assert np.all(fine.impacts.duration < 0.1)  # far shorter than a cycle


GRAZE_SOLVERS = [
    ("dopri5", 1e-8), ("dop853", 1e-8), ("cash-karp", 1e-8),
    ("dopri5", 1e-10), ("dop853", 1e-10), ("cash-karp", 1e-10),
]


@pytest.mark.parametrize(("method", "rtol"), GRAZE_SOLVERS)
@pytest.mark.parametrize("depth", GRAZE_DEPTHS)
@pytest.mark.parametrize("preset", GRAZE_PRESETS)
def test_no_graze_is_missed_by_large_adaptive_steps(preset, depth, method, rtol):
    """Every contact of the fine run, however short, is found by the coarse run.

    The coarse steps are 10 to 300 times longer than the grazes (dop853 at
    rtol 1e-8: steps ~0.3 against contacts of 1e-3), so a graze lies inside one
    step; its trajectory error is well below the graze depth.
    """
    coarse, fine = _coarse(preset, depth, method, rtol)
    ic, iff = coarse.impacts, fine.impacts
    assert len(ic) == len(iff), (ic.time, iff.time)
    # one-to-one: each onset within a quarter of the fine contact's duration
    assert np.all(np.abs(ic.time - iff.time) < 0.25 * iff.duration), ic.time - iff.time
    assert ic.labels == iff.labels
    np.testing.assert_allclose(ic.duration, iff.duration, rtol=0.5)


@pytest.mark.parametrize("method", ["dopri5", "dop853", "cash-karp"])
@pytest.mark.parametrize("preset", GRAZE_PRESETS)
def test_millesimal_grazes_are_found_at_the_default_tolerance(preset, method):
    coarse, fine = _coarse(preset, 1e-3, method, 1e-6)
    assert len(coarse.impacts) == len(fine.impacts) == GRAZE_CYCLES
    assert np.all(np.abs(coarse.impacts.time - fine.impacts.time)
                  < 0.25 * fine.impacts.duration)


@pytest.mark.parametrize(("method", "rtol"), GRAZE_SOLVERS)
@pytest.mark.parametrize("depth", GRAZE_DEPTHS)
@pytest.mark.parametrize("preset", GRAZE_PRESETS)
def test_graze_peak_penetration_is_located(preset, depth, method, rtol):
    """A recorded graze has a positive peak penetration close to the fine run's."""
    coarse, fine = _coarse(preset, depth, method, rtol)
    pen = coarse.impacts.peak_penetration
    assert np.all(pen > 0.0), pen
    if len(pen) == len(fine.impacts):
        np.testing.assert_allclose(pen, fine.impacts.peak_penetration, rtol=0.2)


# ============================ 5. located events (docs/model.md sections 8, 10)
EVENT_SCENES = [
    ("fig3a", {}),
    ("fig5", {}),
    ("fig4-translational", {}),
    ("wall", {}),
    ("tower-wall", {}),
    ("fig3a", {"phase": 0.3}),
    ("fig4-translational", {"phase": 0.65, "period_ratio": 1.0}),
]
EVENT_SOLVER = {"rtol": 1e-10, "atol": 1e-12}
EVENT_TRANSIENT, EVENT_RECORD = 10, 4
EVENT_SAMPLES = 20000  #: dense samples per cycle of the event tests


@functools.cache
def event_run(preset, flat_items, samples):
    scene = load_preset(preset).with_params(**dict(flat_items), **EVENT_SOLVER)
    sim = simulate(scene, transient=EVENT_TRANSIENT, record=EVENT_RECORD,
                   samples_per_cycle=samples)
    return scene, sim


def _event_ids():
    return ["-".join([p] + [f"{k}={v}" for k, v in f.items()]) for p, f in EVENT_SCENES]


@pytest.mark.parametrize("preset", ["fig3a", "fig4", "tower-wall", "wall", "fig4-translational"])
@pytest.mark.parametrize("rtol", [1e-5, 1e-6])
def test_recorded_onsets_lie_on_the_contact_surface_at_loose_tolerances(preset, rtol):
    """A landed step misses the surface by about the local error (~1e-6 at rtol 1e-5);
    the onset is moved onto it to first order, so the recorded state has d_max ~ 0."""
    scene = load_preset(preset).with_params(rtol=rtol)
    sim = simulate(scene, transient=10, record=10)
    assert len(sim.impacts) >= 10
    ends = end_series(scene, sim.impacts.time, sim.impacts.state)
    d_max = np.maximum(ends[:, 0], ends[:, 1])
    assert np.max(np.abs(d_max)) < 1e-10, d_max  # measured <= 4e-12 (1e-5 .. 1e-6 unmoved)


@pytest.mark.parametrize(("preset", "flat"), EVENT_SCENES, ids=_event_ids())
def test_impacts_are_located_on_the_contact_onset(preset, flat):
    scene, sim = event_run(preset, tuple(flat.items()), EVENT_SAMPLES)
    imp = sim.impacts
    assert len(imp) > 0
    mid, p = scene.model_id(), scene.pack()
    y_lo, y_hi = scene.overlap
    ends = end_series(scene, imp.time, imp.state)
    d_max = np.maximum(ends[:, 0], ends[:, 1])
    assert np.max(np.abs(d_max)) < 1e-9, d_max  # measured <= 3e-11
    # contact point and label: the end with the larger penetration
    for i, label in enumerate(imp.labels):
        if label == "face":
            assert abs(ends[i, 0] - ends[i, 1]) < 1e-9 * max(1.0, abs(d_max[i]))
            assert imp.contact_y[i] == pytest.approx(0.5 * (y_lo + y_hi), abs=1e-12)
        elif label.endswith("+"):
            assert ends[i, 1] >= ends[i, 0] and imp.contact_y[i] == pytest.approx(y_hi)
        else:
            assert ends[i, 0] >= ends[i, 1] and imp.contact_y[i] == pytest.approx(y_lo)
    # relative velocity: positive, the penetration rate at the contact point
    assert np.all(imp.velocity > 0.0)
    rates = [models.penetration_rate(mid, t, y, p, yc)
             for t, y, yc in zip(imp.time, imp.state, imp.contact_y, strict=True)]
    np.testing.assert_allclose(imp.velocity, rates, rtol=1e-12, atol=1e-14)
    # ... and the slope of the penetration at the contact point along the trajectory,
    # fitted on the contact-free approach (smooth) up to the located onset
    tr = sim.trajectory
    tr_ends = end_series(scene, tr.time, tr.state)
    checked = 0
    for i, label in enumerate(imp.labels):
        if label == "face":
            d_path = 0.5 * (tr_ends[:, 0] + tr_ends[:, 1])
            d_on = 0.5 * (ends[i, 0] + ends[i, 1])
        else:
            column = 0 if label.endswith("-") else 1
            d_path, d_on = tr_ends[:, column], ends[i, column]
        before = np.flatnonzero(tr.time < imp.time[i])[-5:]
        if len(before) < 5 or imp.time[i] - tr.time[before[0]] > 6 * scene.period / EVENT_SAMPLES:
            continue
        times = np.append(tr.time[before], imp.time[i]) - imp.time[i]
        coeffs = np.polyfit(times, np.append(d_path[before], d_on), 3)
        assert coeffs[-2] == pytest.approx(imp.velocity[i], rel=1e-6)
        checked += 1
    assert checked >= len(imp) - 1


@pytest.mark.parametrize(("preset", "flat"), EVENT_SCENES, ids=_event_ids())
def test_impact_times_phases_and_durations(preset, flat):
    scene, sim = event_run(preset, tuple(flat.items()), EVENT_SAMPLES)
    imp = sim.impacts
    period = scene.period
    t0 = scene.run.phase * period
    # onsets inside the record window, phases and cycles consistent with the time
    assert np.all(imp.time >= t0 + EVENT_TRANSIENT * period)
    assert np.all(imp.time < t0 + (EVENT_TRANSIENT + EVENT_RECORD) * period)
    assert np.all((imp.phase >= 0.0) & (imp.phase < 1.0))
    np.testing.assert_allclose(imp.phase, np.mod(imp.time, period) / period, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(imp.cycle, np.floor((imp.time - t0) / period + 1e-12))
    assert np.all(np.diff(imp.time) > 0.0)
    # duration: the next downward zero of d_max along the dense trajectory
    tr = sim.trajectory
    ends = end_series(scene, tr.time, tr.state)
    d_max = np.maximum(ends[:, 0], ends[:, 1])
    for i in range(len(imp)):
        if imp.time[i] + imp.duration[i] >= tr.time[-1]:
            continue  # the episode runs past the window: followed, not sampled
        release = downward_zero(tr.time, d_max, imp.time[i])
        assert imp.duration[i] == pytest.approx(release - imp.time[i], abs=1e-7)
        # no separation inside an episode, and episodes do not overlap
        inside = (tr.time > imp.time[i] + 1e-9) & (tr.time < release - 1e-9)
        assert np.all(d_max[inside] > -1e-12)
        if i + 1 < len(imp):
            assert imp.time[i + 1] > imp.time[i] + imp.duration[i]


def _episode_maxima(preset, flat, samples, series):
    """(recorded, reference) peaks of every episode that ends inside the window.

    The reference is the maximum of ``series`` (d_max or the contact force)
    over the dense trajectory of the same run, refined by a parabola through
    the largest sample and its neighbours (relative accuracy ~1e-8 at
    EVENT_SAMPLES per cycle).
    """
    scene, sim = event_run(preset, tuple(flat.items()), samples)
    _, dense = event_run(preset, tuple(flat.items()), EVENT_SAMPLES)
    imp, tr = sim.impacts, dense.trajectory
    values = series(scene, tr.time, tr.state)
    recorded, reference = [], []
    for i in range(len(imp)):
        if imp.time[i] + imp.duration[i] >= tr.time[-1]:
            continue
        inside = np.flatnonzero((tr.time > imp.time[i]) & (tr.time < imp.time[i] + imp.duration[i]))
        assert len(inside) >= 5
        k = inside[np.argmax(values[inside])]
        recorded.append(i)
        reference.append(parabola_vertex(tr.time, values, k))
    assert recorded
    return imp, np.array(recorded), np.array(reference)


def _d_max_series(scene, times, states):
    ends = end_series(scene, times, states)
    return np.maximum(ends[:, 0], ends[:, 1])


@pytest.mark.parametrize("samples", [0, EVENT_SAMPLES], ids=["no-samples", "samples"])
@pytest.mark.parametrize(("preset", "flat"), EVENT_SCENES[:5], ids=_event_ids()[:5])
def test_peak_penetration_is_the_episode_maximum(preset, flat, samples):
    """max of d_max over the episode (docs/model.md 8), whether or not samples are stored."""
    imp, rows, reference = _episode_maxima(preset, flat, samples, _d_max_series)
    error = np.max(np.abs(imp.peak_penetration[rows] / reference - 1.0))
    assert error < 1e-6, f"peak penetration off by {error:.2e} (relative)"  # samples: 3e-9


@pytest.mark.parametrize("samples", [0, EVENT_SAMPLES], ids=["no-samples", "samples"])
@pytest.mark.parametrize(("preset", "flat"), EVENT_SCENES[:5], ids=_event_ids()[:5])
def test_peak_force_is_the_episode_maximum(preset, flat, samples):
    """max over the episode of the force on A along -x, -Q_XA (docs/model.md 8)."""
    imp, rows, reference = _episode_maxima(preset, flat, samples, force_series)
    error = np.max(np.abs(imp.peak_force[rows] / reference - 1.0))
    assert error < 1e-6, f"peak force off by {error:.2e} (relative)"


# ======================================== 6. forcing phase over 1e5 cycles
def wall_periodic_state(scene, t):
    """Closed-form steady response of the contact-free wall model at time t.

    X'' + 2 zeta (X' - u') + (X - u) = 0 with u = sin(w t), w = 1/r: the
    relative motion z = X - u obeys z'' + 2 zeta z' + z = w^2 sin(w t), so
    z = Im[G exp(i w t)], G = w^2 / (1 - w^2 + 2 i zeta w).
    """
    w = 1.0 / scene.excitation.period_ratio
    zeta = scene.tower_A.zeta_x
    gain = w * w / (1.0 - w * w + 2j * zeta * w)
    rotor = np.exp(1j * w * t)
    return np.array([
        math.sin(w * t) + (gain * rotor).imag,
        w * math.cos(w * t) + (1j * w * gain * rotor).imag,
    ])


@pytest.mark.parametrize("cycles", [
    pytest.param(100_000, id="1e5-cycles"),
    pytest.param(1_000_000, id="1e6-cycles", marks=pytest.mark.slow),
])
def test_forcing_phase_does_not_drift_over_long_runs(cycles):
    scene = load_preset("wall").with_params(
        gap=100.0, phase=0.37, method="dop853", rtol=1e-11, atol=1e-13, max_steps=10**9
    )
    period = scene.period
    t0 = scene.run.phase * period
    periodic = wall_periodic_state(scene, t0)
    long_run = simulate(scene, transient=cycles, record=1)
    assert len(long_run.impacts) == 0
    np.testing.assert_array_equal(long_run.strobe.cycle, [cycles, cycles + 1])
    sections = np.array([cycles, cycles + 1])
    np.testing.assert_array_equal(long_run.strobe.time, t0 + sections * period)
    # the last sections sit on the closed-form periodic orbit (measured 1.2e-12)
    np.testing.assert_allclose(long_run.strobe.state, np.tile(periodic, (2, 1)), rtol=0, atol=1e-9)
    # and equal a short run started on that orbit at the section time
    short = simulate(scene, transient=0, record=1, initial_state=periodic, start_at_section=True)
    np.testing.assert_array_equal(short.strobe.time, t0 + np.array([0, 1]) * period)
    np.testing.assert_allclose(long_run.strobe.state[-1], short.strobe.state[-1], rtol=0, atol=1e-9)


def test_section_phase_shifts_the_strobe_times():
    scene = load_preset("wall").with_params(gap=100.0, phase=0.25, rtol=1e-10, atol=1e-12)
    sim = simulate(scene, transient=3, record=2)
    np.testing.assert_array_equal(sim.strobe.cycle, [3, 4, 5])
    period = scene.period
    np.testing.assert_array_equal(sim.strobe.time, 0.25 * period + np.arange(3, 6) * period)
    # the run starts at t = 0 (rest), so the sections are not on the periodic orbit
    # yet, but each one is the state at its own time: compare with a run from rest
    # sampled densely (phase 0 sections) at the same times
    dense = simulate(scene.with_params(phase=0.0), transient=0, record=6, samples_per_cycle=4)
    k = np.searchsorted(dense.trajectory.time, sim.strobe.time[0] - 1e-9)
    np.testing.assert_allclose(dense.trajectory.time[k], sim.strobe.time[0], rtol=1e-14)
    np.testing.assert_allclose(dense.trajectory.state[k], sim.strobe.state[0], rtol=0, atol=1e-8)


# ======================================= 7. integrators agree at tight tolerance
INTEGRATORS = {
    "dopri5": {"method": "dopri5", "rtol": 1e-10, "atol": 1e-13},
    "dop853": {"method": "dop853", "rtol": 1e-12, "atol": 1e-14},
    "cash-karp": {"method": "cash-karp", "rtol": 1e-10},
    "rk4": {"method": "rk4", "steps_per_cycle": 20000},
}


@functools.cache
def fig3a_reference():
    scene = load_preset("fig3a").with_params(method="dop853", rtol=1e-13, atol=1e-15)
    return simulate(scene, transient=10, record=4)


@pytest.mark.parametrize("name", list(INTEGRATORS))
def test_integrators_agree_on_a_pounding_scene(name):
    ref = fig3a_reference()
    sim = simulate(load_preset("fig3a").with_params(**INTEGRATORS[name]), transient=10, record=4)
    assert len(ref.impacts) >= 9
    assert len(sim.impacts) == len(ref.impacts)
    assert sim.impacts.labels == ref.impacts.labels
    # measured: dopri5 5e-9, dop853 8e-11, cash-karp 6e-9, rk4 1.6e-9
    np.testing.assert_allclose(sim.impacts.time, ref.impacts.time, rtol=0, atol=1e-7)
    np.testing.assert_allclose(sim.impacts.velocity, ref.impacts.velocity, rtol=0, atol=1e-7)
    np.testing.assert_allclose(sim.strobe.state, ref.strobe.state, rtol=0, atol=1e-7)


# ============================ 8. landing steps on the kinks (docs/model.md 10)
@pytest.mark.parametrize("method", ["dopri5", "dop853", "cash-karp"])
def test_restarting_at_kinks_reduces_impact_velocity_errors(method):
    rtol = 1e-9
    landed, through = [], []
    for period_ratio in (0.5, 0.7, 1.0, 1.3):
        scene = load_preset("fig4-translational").with_params(period_ratio=period_ratio)
        ref = simulate(scene.with_params(method="dop853", rtol=1e-13, atol=1e-15),
                       transient=20, record=8)
        assert len(ref.impacts) > 0
        for restart, errors in ((True, landed), (False, through)):
            sim = simulate(scene.with_params(method=method, rtol=rtol, atol=1e-12,
                                             restart_at_kinks=restart), transient=20, record=8)
            assert sim.model == "pair" and len(sim.impacts) == len(ref.impacts)
            errors.append(np.max(np.abs(sim.impacts.velocity - ref.impacts.velocity)))
    # measured (max over r): landed 1e-8 .. 4e-8, through 4e-6 .. 1e-5
    assert max(landed) < 100 * rtol, landed
    assert max(through) > 10 * max(landed), (landed, through)


# ============================================================ 9. determinism
def test_runs_are_bitwise_reproducible():
    scene = load_preset("fig3a").with_params(transient=20, record=4)
    a = simulate(scene, samples_per_cycle=20)
    b = simulate(scene, samples_per_cycle=20)
    for field in ("time", "phase", "velocity", "corner", "contact_y", "peak_penetration",
                  "peak_force", "duration", "cycle", "state"):
        np.testing.assert_array_equal(getattr(a.impacts, field), getattr(b.impacts, field))
    np.testing.assert_array_equal(a.strobe.state, b.strobe.state)
    np.testing.assert_array_equal(a.trajectory.state, b.trajectory.state)
    np.testing.assert_array_equal(a.final_state, b.final_state)
    assert a.stats.steps == b.stats.steps and a.stats.rejected == b.stats.rejected


def test_dense_sampling_does_not_change_the_solution():
    scene = load_preset("fig3a").with_params(transient=20, record=4)
    plain = simulate(scene)
    sampled = simulate(scene, samples_per_cycle=100)
    for field in ("time", "velocity", "corner", "duration", "state"):
        np.testing.assert_allclose(getattr(sampled.impacts, field), getattr(plain.impacts, field),
                                   rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(sampled.strobe.state, plain.strobe.state, rtol=1e-12, atol=1e-14)
    # the sampled trajectory passes through the sections
    np.testing.assert_array_equal(sampled.trajectory.state[::100], sampled.strobe.state)
