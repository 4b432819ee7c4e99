"""``simulate --plot``, ``section`` and ``impact-map`` (issue 18, item 6): the figures'
data and the JSON documents against the library and the physics of fig3a."""

from __future__ import annotations

import json

import numpy as np
import pytest

from chaospound import plot as plot_module
from chaospound.cli import main
from chaospound.dynamics.impact_map import impact_map
from chaospound.dynamics.poincare import stroboscopic_section
from chaospound.scene import load_preset
from chaospound.simulate import contact_history, simulate

FIG3A = load_preset("fig3a")
#: cycles after which fig3a's group-periodic 3-1 response has settled (tests/test_sections.py)
SETTLED = "200"


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys, *argv: str) -> dict:
    code, out, err = run(capsys, *argv, "--json")
    assert code == 0, err
    return json.loads(out)


@pytest.fixture
def saved(monkeypatch):
    """The figures the CLI saves, by path (chaospound.plot.save still writes them)."""
    figures = {}
    real = plot_module.save

    def capture(fig, path, **kwargs):
        figures[str(path)] = fig
        real(fig, path, **kwargs)

    monkeypatch.setattr(plot_module, "save", capture)
    return figures


def panel(fig, label: str):
    """The Axes of a time-history panel (plot.HISTORY_PANELS), anywhere in the figure."""
    found = [ax for ax in fig.get_axes() if ax.get_label() == label]
    assert len(found) == 1, f"no single {label!r} panel"
    return found[0]


# ------------------------------------------------------------ simulate --plot
def test_simulate_plot_force_is_zero_where_the_gap_is_open(capsys, tmp_path, saved):
    """Read back from the figure's lines: the contact force vanishes wherever the
    clearance is positive, is positive in contact, and every impact sits at zero
    clearance; the towers model shows X, Y and rotations of both towers."""
    target = tmp_path / "run.png"
    code, out, err = run(capsys, "simulate", "--preset", "fig3a", "--plot", str(target))
    assert code == 0, err
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote              {target}" in out
    fig = saved[str(target)]
    (t_gap, gap), = [line.get_data() for line in panel(fig, "clearance").get_lines()
                     if line.get_label() == r"$-d_{max}$"]
    (t_force, force), = [line.get_data() for line in panel(fig, "force").get_lines()]
    np.testing.assert_array_equal(t_gap, t_force)
    open_gap = gap > 0.0
    assert open_gap.sum() > 0.5 * gap.size  # mostly apart
    assert np.all(force[open_gap] == 0.0)
    assert np.all(force[gap < -1e-6] > 0.0) and np.any(gap < -1e-3)  # in contact: pushing
    # impact onsets drawn at zero clearance, and they are the run's 24 impacts (3 per cycle)
    marks = [line for line in panel(fig, "clearance").get_lines()
             if line.get_label().startswith("impact")]
    onsets = np.sort(np.concatenate([line.get_xdata() for line in marks]))
    assert onsets.size == 24
    assert np.all(np.concatenate([line.get_ydata() for line in marks]) == 0.0)
    nearest = np.searchsorted(t_gap, onsets)
    assert np.all(np.abs(gap[nearest]) < 0.05)  # the sampled curve passes 0 at each onset
    # displacements of both towers, with units on every axis
    for label, unit in (("X", "A_g"), ("Y", "A_g"), ("th", "rad"), ("clearance", "A_g"),
                        ("force", "k_{Ax}")):
        ax = panel(fig, label)
        assert unit in ax.get_ylabel()
        if label in ("X", "Y", "th"):
            assert len(ax.get_lines()) == 2
    assert r"\omega_{Ax}" in panel(fig, "force").get_xlabel()
    # the phase diagrams beside them (4 panels of the towers model)
    phase_axes = [ax for ax in fig.get_axes() if ax.get_title().startswith("Tower")]
    assert len(phase_axes) == 4


def test_contact_history_matches_the_impacts():
    """The clearance at the samples around each onset changes sign; the force peaks
    equal the impact table's peak forces to sampling accuracy."""
    sim = simulate(FIG3A, samples_per_cycle=2000)
    contact = contact_history(sim)
    np.testing.assert_array_equal(contact.clearance, -contact.penetration)
    peaks = []
    for onset, duration in zip(sim.impacts.time, sim.impacts.duration, strict=True):
        inside = (contact.time >= onset) & (contact.time <= onset + duration)
        peaks.append(contact.force[inside].max())
    np.testing.assert_allclose(peaks, sim.impacts.peak_force, rtol=2e-3)


def test_wall_model_plot_has_one_tower(capsys, tmp_path, saved):
    target = tmp_path / "wall.svg"
    code, _, err = run(capsys, "simulate", "--preset", "wall", "--plot", str(target),
                       "--record", "3")
    assert code == 0, err
    fig = saved[str(target)]
    assert len(panel(fig, "X").get_lines()) == 1
    assert not [ax for ax in fig.get_axes() if ax.get_label() in ("Y", "th")]


# -------------------------------------------------------------------- section
def test_fig3a_section_collapses_to_one_point(capsys):
    """fig3a is group-periodic 3-1: three impacts a cycle, but the orbit closes after
    one excitation period, so after a long transient the strobe is a single point."""
    doc = run_json(capsys, "section", "--preset", "fig3a", "--transient", SETTLED,
                   "--cycles", "12", "--rtol", "1e-9", "--atol", "1e-11")
    states = np.array(doc["states"])
    assert states.shape == (13, 12)
    assert doc["distinct_points"] == 1
    assert np.max(np.ptp(states, axis=0)) < 1e-7 * np.max(np.abs(states))
    assert doc["cycles"] == list(range(200, 213)) and doc["transient_cycles"] == 200
    assert doc["units"]["length"].startswith("A_g")


def test_short_transient_section_has_not_settled(capsys):
    """The same scene after only 5 cycles: the points have not collapsed (the transient
    matters, and the distinct count sees it)."""
    doc = run_json(capsys, "section", "--preset", "fig3a", "--transient", "5", "--cycles", "6")
    assert doc["distinct_points"] > 1


@pytest.mark.parametrize("phase", ["0", "0.37"])
def test_section_json_is_the_library_bitwise(capsys, phase):
    doc = run_json(capsys, "section", "--preset", "fig4", "--set", "period_ratio=0.9",
                   "--transient", "10", "--cycles", "7", "--phase", phase)
    scene = load_preset("fig4").with_params(period_ratio=0.9, transient=10, phase=float(phase))
    section = stroboscopic_section(scene, phase=float(phase), cycles=7)
    assert doc["phase"] == float(phase) and doc["kind"] == "stroboscopic"
    np.testing.assert_array_equal(np.array(doc["states"]), section.states)
    np.testing.assert_array_equal(np.array(doc["times"]), section.times)
    assert doc["state_names"] == list(section.state_names)
    assert doc["distinct_points"] == 8  # chaotic: every point its own


def test_section_report_and_plot(capsys, tmp_path, saved):
    target = tmp_path / "section.png"
    code, out, err = run(capsys, "section", "--preset", "fig3a", "--transient", SETTLED,
                         "--cycles", "4", "--plot", str(target))
    assert code == 0, err
    assert "distinct points  1 (within 1e-06" in out and "5 points" in out
    assert "A_g omega_Ax" in out  # the unit row under the state columns
    fig = saved[str(target)]
    assert "1 distinct" in fig.get_suptitle()
    # coinciding points: the panels are not zoomed into rounding noise
    for ax in fig.get_axes():
        low, high = ax.get_xlim()
        assert high - low > 1e-3 * max(abs(low), abs(high))


@pytest.mark.parametrize("argv, words", [
    (["--cycles", "0"], "--cycles"),
    (["--phase", "1.5"], "phase"),
    (["--tol", "-1"], "--tol"),
    (["--plot", "x.h5"], "not a figure format"),
])
def test_section_bad_input_is_one_line_exit_2(capsys, argv, words):
    code, out, err = run(capsys, "section", "--preset", "fig3a", *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and words in err


# ----------------------------------------------------------------- impact-map
def test_impact_map_pairs_are_consecutive_impacts_of_simulate(capsys):
    doc = run_json(capsys, "impact-map", "--preset", "fig3a", "--record", "5")
    sim = simulate(FIG3A.with_params(record=5))
    imp = sim.impacts
    assert len(doc["impacts"]) == len(imp) == 15
    velocity = np.array(doc["pairs"]["velocity"])
    phase = np.array(doc["pairs"]["phase"])
    np.testing.assert_array_equal(velocity, np.column_stack((imp.velocity[:-1], imp.velocity[1:])))
    np.testing.assert_array_equal(phase, np.column_stack((imp.phase[:-1], imp.phase[1:])))
    assert doc["pairs"]["corner"][:3] == [["A+", "B-"], ["B-", "A+"], ["A+", "A+"]]
    assert doc["pairs"] == impact_map(sim).to_json_dict()["pairs"]
    assert doc["units"]["velocity"] == "A_g omega_Ax"
    assert doc["record_cycles"] == 5 and doc["transient_cycles"] == 40


def test_impact_map_report_and_plot(capsys, tmp_path, saved):
    target = tmp_path / "map.pdf"
    code, out, err = run(capsys, "impact-map", "--preset", "fig3a", "--plot", str(target))
    assert code == 0, err
    assert "impacts    24 (3 per cycle), 23 pairs" in out
    assert "phase n+1" in out and "A_g omega_Ax" in out
    fig = saved[str(target)]
    assert len(fig.get_axes()) == 3 and "fig3a" in fig.get_suptitle()
    assert target.read_bytes()[:4] == b"%PDF"


def test_impact_map_without_impacts(capsys):
    code, out, err = run(capsys, "impact-map", "--preset", "fig3a", "--set", "gap=50",
                         "--transient", "5", "--record", "2")
    assert code == 0, err
    assert "0 impacts in the record window: no pair n -> n+1" in out


# ------------------------------------------------- a user's system, FILE.py:ATTR
def test_section_and_impact_map_of_a_system_file_are_the_library_bitwise(
        capsys, tmp_path, saved):
    """``section`` and ``impact-map`` take FILE.py:ATTR like simulate and classify: the
    JSON is the library's stroboscopic_section and impact_map of the loaded system."""
    from test_sweep_system import SYSTEM_FILE

    from chaospound.userfile import load_system

    file = tmp_path / "stop.py"
    file.write_text(SYSTEM_FILE)
    spec = f"{file}:system"
    system = load_system(spec).with_params(gap=0.8)
    doc = run_json(capsys, "section", spec, "--set", "gap=0.8", "--transient", "30",
                   "--cycles", "6", "--quiet")
    section = stroboscopic_section(system, transient=30, cycles=6)
    np.testing.assert_array_equal(np.array(doc["states"]), section.states)
    np.testing.assert_array_equal(np.array(doc["times"]), section.times)
    assert doc["model"] == "custom" and doc["state_names"] == ["x", "dx"]
    assert doc["system"]["parameter_values"]["gap"] == 0.8 and "scene" not in doc
    doc = run_json(capsys, "impact-map", spec, "--set", "gap=0.8", "--transient", "30",
                   "--record", "4", "--quiet")
    imap = impact_map(system, transient=30, cycles=4)
    assert len(imap) >= 4 and doc["pairs"] == imap.to_json_dict()["pairs"]
    assert {row["corner"] for row in doc["impacts"]} == {"face"}
    # the text reports name the system; its units are its own
    code, out, err = run(capsys, "section", spec, "--transient", "30", "--cycles", "3",
                         "--quiet")
    assert code == 0 and "custom (2 states: x dx)" in out and "A_g" not in out, err
    figure = tmp_path / "map.png"
    code, out, err = run(capsys, "impact-map", spec, "--record", "3", "--quiet", "--plot",
                         str(figure))
    assert code == 0 and "phase n+1" in out and "A_g" not in out, err
    assert "stop" in saved[str(figure)].get_suptitle()


def test_impact_map_of_a_system_without_gap_is_one_line_exit_2(capsys, tmp_path):
    from test_sweep_system import SYSTEM_FILE

    file = tmp_path / "smooth.py"
    file.write_text(SYSTEM_FILE + "\nsmooth = custom_system(rhs, jacobian, params=(0.06, 1.0, "
                    "1000.0, 0.7), period=1.0, initial_state=(0.0, 0.0))\n")
    code, out, err = run(capsys, "impact-map", f"{file}:smooth")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "has no gap function" in err
