"""Poincare sections and the impact map (docs/model.md section 11).

Every test compares a section against an independent route to the same
points: the simulator's own stroboscopic record, the dense trajectory of
another run, the contact geometry of the kernels, the paper's group-periodic
3-1 response of Fig. 3(a).
"""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from kernels_by_name import contact_ends, penetration_rate

from chaospound.dynamics.impact_map import ImpactMap, impact_map
from chaospound.dynamics.poincare import Section, impact_section, stroboscopic_section
from chaospound.dynamics.system import System, duffing
from chaospound.scene import load_preset
from chaospound.simulate import simulate

FIG3A = load_preset("fig3a")
#: fig3a converged to its period-1 orbit (residue of the transient < 1e-10)
SETTLED = 200


@functools.cache
def settled_fig3a() -> tuple:
    """fig3a after a long transient, 12 cycles recorded, at a tight tolerance."""
    scene = FIG3A.with_params(rtol=1e-9, atol=1e-11)
    return scene, simulate(scene, transient=SETTLED, record=12)


# ------------------------------------------------------- stroboscopic section
def test_phase_zero_section_is_the_simulators_strobe():
    section = stroboscopic_section(FIG3A, transient=40, cycles=8)
    sim = simulate(FIG3A, transient=40, record=8)
    assert isinstance(section, Section) and section.kind == "stroboscopic"
    assert len(section) == 9 and section.phase == 0.0 and section.labels is None
    np.testing.assert_array_equal(section.states, sim.strobe.state)
    np.testing.assert_array_equal(section.times, sim.strobe.time)
    np.testing.assert_array_equal(section.cycles, np.arange(40, 49))
    assert section.state_names == sim.state_names and section.model == "towers"


@pytest.mark.parametrize("phase", [0.0, 0.37])
def test_system_and_scene_routes_agree(phase):
    """A System built from the scene runs the same integrator: bitwise the same points."""
    by_scene = stroboscopic_section(FIG3A, phase=phase, transient=10, cycles=5)
    by_system = stroboscopic_section(System.from_scene(FIG3A), phase=phase, transient=10, cycles=5)
    np.testing.assert_array_equal(by_scene.states, by_system.states)
    np.testing.assert_allclose(
        by_scene.times, (phase + np.arange(10, 16)) * FIG3A.period, rtol=1e-15
    )


def test_half_phase_section_matches_dense_trajectory_of_phase_zero_run():
    """States at t = (k + 1/2) T from two different runs: sections vs dense output."""
    scene = FIG3A.with_params(rtol=1e-10, atol=1e-12)
    samples = 200  # even: sample 100 of each cycle is at (k + 1/2) T
    sim = simulate(scene, transient=40, record=8, samples_per_cycle=samples)
    section = stroboscopic_section(scene, phase=0.5, transient=40, cycles=7)
    rows = samples // 2 + samples * np.arange(8)
    np.testing.assert_allclose(sim.trajectory.time[rows], section.times, rtol=1e-14)
    scale = np.abs(sim.trajectory.state).max(axis=0)
    error = np.abs(sim.trajectory.state[rows] - section.states) / scale
    assert error.max() < 1e-7
    # and the half-phase points are not the phase-0 points (the test can fail)
    assert np.abs(section.states - sim.strobe.state[:-1]).max() > 0.1


def test_fig3a_period_one_section_collapses_to_one_point():
    """Group-periodic 3-1: one stroboscopic point per period, three impacts per cycle."""
    section = stroboscopic_section(FIG3A, transient=150, cycles=20)
    spread = np.linalg.norm(section.states - section.states[0], axis=1)
    assert spread.max() < 1e-3 * np.linalg.norm(section.states[0])
    # after the paper's 40 cycles the residue of the transient is still visible
    early = stroboscopic_section(FIG3A, transient=10, cycles=20)
    early_spread = np.linalg.norm(early.states - early.states[0], axis=1)
    assert early_spread.max() > 1e-2 * np.linalg.norm(early.states[0])


def test_reference_system_section():
    """Ueda's Duffing oscillator is chaotic: its section does not collapse."""
    section = stroboscopic_section(duffing(), transient=50, cycles=30)
    assert section.model == "duffing" and section.states.shape == (31, 2)
    assert np.all(np.isfinite(section.states))
    assert np.ptp(section.states[:, 0]) > 0.5


@pytest.mark.parametrize(
    "kwargs", [{"phase": 1.0}, {"phase": -0.1}, {"cycles": 0}, {"transient": -1}]
)
def test_bad_section_arguments_name_the_parameter(kwargs):
    name = next(iter(kwargs))
    with pytest.raises(ValueError, match=name):
        stroboscopic_section(FIG3A, **kwargs)


# ------------------------------------------------------------ impact section
def test_impact_section_points_are_on_the_contact_surface():
    """At every impact onset d_max = max(d_lo, d_hi) = 0 and the contact point closes."""
    scene, sim = settled_fig3a()
    section = impact_section(sim)
    assert section.kind == "impact" and section.phase is None
    assert len(section) == len(sim.impacts) == 36
    assert section.labels == tuple(sim.impacts.labels)
    model, p = scene.model_id(), scene.pack()
    ends = np.empty(4)
    for t, y, v, y_at in zip(
        section.times, section.states, sim.impacts.velocity, sim.impacts.contact_y, strict=True
    ):
        contact_ends(model, t, y, p, ends)
        assert abs(max(ends[0], ends[1])) < 1e-8
        assert penetration_rate(model, t, y, p, y_at) == pytest.approx(v, rel=1e-12)
        assert v > 0.0
    # the outer corner hits the lower (A+ at y_hi) or upper (B- at y_lo) end
    hi = np.array([label == "A+" for label in section.labels])
    assert np.all(sim.impacts.contact_y[hi] > 0) and np.all(sim.impacts.contact_y[~hi] < 0)


# ---------------------------------------------------------------- impact map
def test_impact_map_pairs_are_consecutive_impacts():
    _, sim = settled_fig3a()
    imap = impact_map(sim)
    assert isinstance(imap, ImpactMap) and len(imap) == len(sim.impacts)
    n = len(imap)
    assert imap.velocity_pairs.shape == imap.phase_pairs.shape == (n - 1, 2)
    np.testing.assert_array_equal(imap.velocity_pairs[:-1, 1], imap.velocity_pairs[1:, 0])
    np.testing.assert_array_equal(imap.phase_pairs[:-1, 1], imap.phase_pairs[1:, 0])
    np.testing.assert_array_equal(imap.velocity_pairs[:, 0], sim.impacts.velocity[:-1])
    np.testing.assert_array_equal(imap.velocity_pairs[:, 1], sim.impacts.velocity[1:])
    np.testing.assert_array_equal(imap.corner_pairs[:, 1], sim.impacts.corner[1:])
    assert np.all(np.diff(imap.time) > 0)


def test_fig3a_impact_map_has_period_three():
    """Paper Fig. 3(a): impacts at corners C, F, C in every cycle; the map has period 3."""
    _, sim = settled_fig3a()
    imap = impact_map(sim)
    labels = imap.labels
    assert labels[:3] == ("A+", "B-", "A+")
    assert all(labels[i] == labels[i + 3] for i in range(len(labels) - 3))
    assert labels[0] != labels[1]  # not period 1 in corners
    v = imap.velocity
    np.testing.assert_allclose(v[3:], v[:-3], rtol=1e-6)
    assert np.ptp(v[:3]) > 1.0  # three different impacts in the group
    # the map V_n -> V_{n+1} visits three fixed points of its third iterate
    assert len(np.unique(np.round(imap.velocity_pairs, 4), axis=0)) == 3


def test_impact_map_json_round_trip():
    _, sim = settled_fig3a()
    imap = impact_map(sim)
    document = json.loads(json.dumps(imap.to_json_dict()))
    assert len(document["impacts"]) == len(imap)
    assert document["pairs"]["velocity"][0] == [imap.velocity[0], imap.velocity[1]]
    assert document["pairs"]["corner"][0] == ["A+", "B-"]
    assert document["impacts"][2]["corner"] == "A+"


def test_impact_map_without_impacts():
    """Far from resonance with a wide gap the towers never touch: an empty map."""
    sim = simulate(FIG3A.with_params(gap=50.0), transient=5, record=3)
    imap = impact_map(sim)
    assert len(imap) == 0 and imap.velocity_pairs.shape == (0, 2)
    assert impact_section(sim).states.shape == (0, 12)
