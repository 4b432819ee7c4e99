"""The converged classification (chaospound.dynamics.converged), the sweep default.

Checked against known answers (the paper's fig3a group-periodic 3-1, chaos of
fig4 at T/T_Ax = 0.9, the wall model's two periodic branches), against the
careful adaptive classifier (an independent procedure: long transients, no
Newton), against Newton's orbit itself (the stored record repeats to within
the classification's tol), and for the warm starts: a scan run forward,
backward and from fresh starts names every point alike where the attractor is
unique.
"""

from __future__ import annotations

import numpy as np
import pytest

from chaospound.dynamics.classify import DEFAULT_TOL, classify, length_weights
from chaospound.dynamics.converged import classify_converged
from chaospound.scene import load_preset
from chaospound.store import open_sweep
from chaospound.sweep import SweepSpec, parse_axis, run_sweep

FIG4 = load_preset("fig4")
WALL = load_preset("wall").with_params(gap=5.0)


def labels(sweep, branch):
    return list(zip(sweep.regimes(branch), sweep.array("period_cycles", branch).tolist(),
                    sweep.array("impacts_per_period", branch).tolist(), strict=True))


def test_fig3a_is_group_periodic_3_1_confirmed_by_newton():
    scene = load_preset("fig3a")
    result = classify_converged(scene)
    regime = result.regime
    assert regime.label == "group-periodic 3-1"
    assert regime.evidence["confirmed_by"] == "newton"
    assert regime.evidence["orbit_residual"] < 1e-7
    assert regime.evidence["max_multiplier"] < 1.0  # the orbit is an attractor
    assert regime.confidence > 0.9
    # the record read is the orbit: a period-1 section repeats to well within tol
    states = result.record.strobe.state * length_weights(scene, result.record.state_names)
    scale = np.max(np.linalg.norm(states, axis=1))
    assert np.max(np.linalg.norm(np.diff(states, axis=0), axis=1)) / scale < DEFAULT_TOL / 10
    # the careful classifier, from rest with its own long transient, agrees
    careful = classify(scene)
    assert careful.label == regime.label
    assert regime.corner_sequence == careful.corner_sequence


def test_fig4_at_0_9_is_chaotic_by_more_than_three_sigma():
    regime = classify_converged(FIG4.with_params(period_ratio=0.9)).regime
    assert regime.regime == "chaotic"
    assert regime.max_exponent > 3 * regime.max_exponent_error > 0
    assert regime.period_cycles is None
    assert regime.evidence["decided_by"] == "exponent"
    assert regime.transient_used < 500  # far below the careful classifier's 2000 cycles


def test_wall_branches_none_and_periodic_1_1_coexist():
    """wall, gap 5: between T/T_Ax 0.575 and 0.875 the rest state's branch has no
    impact while the impacting 1-1 orbit (reached from a state on it) is stable too."""
    point = WALL.with_params(period_ratio=0.7)
    rest = classify_converged(point).regime
    assert rest.label == "none" and rest.period_cycles == 1
    impacting = classify_converged(WALL.with_params(period_ratio=0.95))
    assert impacting.regime.label == "periodic 1-1"
    # continue the impacting orbit down to 0.7 in steps: it stays periodic 1-1
    state = impacting.final_state
    for ratio in (0.9, 0.85, 0.8, 0.75, 0.7):
        result = classify_converged(WALL.with_params(period_ratio=ratio), start_state=state)
        assert result.regime.label == "periodic 1-1", ratio
        assert result.regime.evidence["max_multiplier"] < 1.0
        state = result.final_state
    assert len(result.record.impacts) == result.record.record  # one impact a cycle


@pytest.mark.parametrize("preset, grid, regime", [
    ("fig4-translational", "period_ratio=0.45:0.65#5", "periodic"),
    # 0.745, just below the chaotic band, is not such a point: its label there depends
    # on the path (group-periodic 5-14 or chaotic), and the last bit of any sum decides
    ("fig4", "period_ratio=0.705:0.735#4", "group-periodic"),
])
def test_warm_starts_change_nothing_where_the_attractor_is_unique(tmp_path, preset, grid,
                                                                  regime):
    """A short scan forward, backward and from fresh starts (the default, warm-started
    in blocks) names every point alike, and ends on the same orbit."""
    scene = load_preset(preset)
    axis = parse_axis(grid, scene)
    run_sweep(scene, SweepSpec(axes=(axis,), continuation="both"), tmp_path / "both.h5",
              progress=False)
    run_sweep(scene, SweepSpec(axes=(axis,)), tmp_path / "fresh.h5", progress=False)
    both, fresh = open_sweep(tmp_path / "both.h5"), open_sweep(tmp_path / "fresh.h5")
    assert labels(both, "forward") == labels(both, "backward") == labels(fresh, "fresh")
    assert set(fresh.regimes()) == {regime}
    for branch in ("forward", "backward"):
        np.testing.assert_allclose(both.array("final_state", branch),
                                   fresh.array("final_state"), rtol=0, atol=1e-4)


def test_a_budget_too_short_says_why():
    regime = classify_converged(FIG4.with_params(period_ratio=0.9), max_transient=30).regime
    assert regime.regime == "unresolved" and regime.confidence == 0.0
    assert "within 30 cycles" in regime.evidence["why"]


def test_the_sweep_default_is_converged_and_paper_is_the_window():
    axis = (parse_axis("period_ratio=0.9,1.0"),)
    assert SweepSpec(axes=axis).classify == "converged"
    assert SweepSpec(axes=axis, classify="paper").classify == "window"
    with pytest.raises(ValueError, match="converged, paper, window, full"):
        SweepSpec(axes=axis, classify="fast")
