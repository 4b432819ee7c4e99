"""Earthquake runs (chaospound.quake): peaks, finite-time Lyapunov exponent, ensembles.

The tests write their own small accelerograms. The run's peaks are those of a
direct simulate of the same scene; the relative displacements use a ground
displacement checked against the record's exact cubic; the finite-time exponent
of a run without impacts (a damped linear oscillator) equals the closed form
log |exp(A t) d0| / (|d0| t); an ensemble without perturbation has no spread.
"""

import math

import numpy as np
import pytest
import scipy.linalg

from chaospound import load_preset
from chaospound.quake import ensemble, quake, quake_scene
from chaospound.scene import SceneError
from chaospound.simulate import CORNER_LABELS, simulate


@pytest.fixture(scope="module")
def record_file(tmp_path_factory):
    """A 4 s accelerogram (time [s], acceleration [g]): a tapered 0.35 s sine."""
    path = tmp_path_factory.mktemp("quake") / "pulse.txt"
    t = np.arange(0.0, 4.0 + 1e-9, 0.01)
    a = 0.5 * np.sin(2.0 * np.pi * t / 0.35) * np.exp(-(((t - 1.5) / 1.0) ** 2))
    np.savetxt(path, np.column_stack([t, a]), header="time acceleration")
    return str(path)


def _wall(**extra):
    values = {"length_unit": 0.01, "tower_period": 0.5, "gap": 2.0, **extra}
    return load_preset("wall").with_params(**values)


def test_peaks_agree_with_a_direct_simulate(record_file):
    run = quake(_wall(), record=record_file, lyapunov=False)
    assert run.impacts > 3
    direct = simulate(quake_scene(_wall(), record_file).with_params(record=run.simulation.record))
    imp = direct.impacts
    assert np.array_equal(run.simulation.impacts.time, imp.time)
    for corner in run.corners:
        hit = imp.corner == CORNER_LABELS.index(corner.corner)
        assert corner.impacts == int(hit.sum())
        assert corner.peak_force == np.max(imp.peak_force[hit])
        assert corner.peak_velocity == np.max(imp.velocity[hit])
        assert corner.peak_penetration == np.max(imp.peak_penetration[hit])
    assert sum(c.impacts for c in run.corners) == len(imp)
    assert run.time >= run.motion_end > run.time - run.scene.period


def test_relative_displacement_uses_the_records_exact_ground(record_file):
    """u_g at the samples against the record block's cubic, evaluated here in numpy."""
    run = quake(_wall(), record=record_file, lyapunov=False)
    block = run.scene.excitation.ground_block()
    n = int(block[0])
    t, u, v, a = (block[3 + i * n:3 + (i + 1) * n] for i in range(4))
    times = run.simulation.trajectory.time
    k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, n - 2)
    s = times - t[k]
    jerk = (a[k + 1] - a[k]) / (t[k + 1] - t[k])
    cubic = u[k] + v[k] * s + a[k] * s**2 / 2 + jerk * s**3 / 6
    after = times >= t[-1]
    cubic[after] = u[-1] + v[-1] * (times[after] - t[-1])
    np.testing.assert_allclose(run.ground_displacement, cubic, rtol=0, atol=1e-12)
    x = run.simulation.trajectory.state[:, 0]
    assert run.towers[0].displacement == np.max(np.abs(x - cubic))


def test_finite_time_exponent_of_a_linear_run_is_the_closed_form(record_file):
    """No impacts (a huge gap): the difference of the two trajectories obeys d' = A d
    with A = [[0, 1], [-1, -2 zeta]], whatever the ground; renormalising keeps the
    direction, so the exponent is log |exp(A t) d0| / (|d0| t) exactly."""
    scene = _wall(gap=1e6, rtol=1e-10, atol=1e-13)
    run = quake(scene, record=record_file, tail=60.0, separation=1e-6, seed=4)
    assert run.impacts == 0
    ftle = run.lyapunov
    zeta = 0.03
    a = np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]])
    d0 = np.random.default_rng(4).normal(size=2)
    exact = math.log(np.linalg.norm(scipy.linalg.expm(a * ftle.time) @ d0)
                     / np.linalg.norm(d0)) / ftle.time
    assert ftle.exponent == pytest.approx(exact, abs=1e-9)
    assert ftle.exponent == pytest.approx(-zeta, abs=0.01)


def test_ensemble_without_perturbation_has_no_spread(record_file):
    scene = quake_scene(_wall(), record_file).with_params(record=12)
    zero = ensemble(scene, 3)
    assert zero.spread == 0.0
    assert len(set(zero.percentiles.values())) == 1
    assert zero.peak_force[0] == np.max(simulate(scene).impacts.peak_force)
    spread = ensemble(scene, 3, scale_spread=0.2, seed=1)
    assert spread.spread > 0.0


def test_bad_inputs(record_file, tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("0.0 0.1\n0.01 abc\n")
    with pytest.raises(SceneError) as info:
        quake(_wall(), record=str(bad))
    assert "bad.txt" in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(SceneError, match="needs a record"):
        quake(_wall())
    with pytest.raises(ValueError, match="scale_spread"):
        ensemble(quake_scene(_wall(), record_file), 2, scale_spread=1.5)


def test_contact_force_history_uses_the_episode_memory(record_file):
    """The sampled force of a memory law (hertzdamp: xi = zeta / v0 per episode) peaks
    within 2 % of the engine's recorded episode peaks; the fresh packed vector's
    v0 (simulate.contact_history's) would not."""
    from chaospound.quake import contact_force

    scene = _wall(contact_law="hertzdamp", restitution=0.6)
    run = quake(scene, record=record_file, lyapunov=False, samples_per_cycle=2000)
    force = contact_force(run)
    assert run.impacts > 3
    assert force.max() == pytest.approx(run.peak_force, rel=0.02)
    assert np.all(force[run.simulation.trajectory.state[:, 0] - run.ground_displacement
                        < 2.0 - 1e-9] == 0.0)


def test_ensemble_of_realisations_is_the_runs_of_each_seed():
    scene = quake_scene(_wall(ground="stochastic", ground_pga=0.4, ground_duration=3.0,
                              ground_t_rise=0.5, ground_t_plateau=2.0, gap=0.5,
                              ground_seed=5)).with_params(record=12)
    runs = ensemble(scene, 3, realisations=True)
    for i in range(3):
        alone = simulate(scene.with_params(ground_seed=5 + i)).impacts.peak_force
        assert runs.peak_force[i] == (np.max(alone) if alone.size else 0.0)
    assert runs.spread > 0.0
    with pytest.raises(ValueError, match="not stochastic"):
        ensemble(scene.with_params(ground="sine"), 2, realisations=True)
