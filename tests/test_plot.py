"""Figures (chaospound.plot) and the ``chaospound lyapunov`` command.

The figures are checked for content: which panels, which labels, that the
drawn points are the results' numbers, that the numbered impacts are the
last cycle's impacts in order; save() for atomic writes. The command is
checked against the Lyapunov engine's invariants (the trace identity).
"""

from __future__ import annotations

import functools
import json
import os

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from chaospound import plot  # noqa: E402
from chaospound.cli import main  # noqa: E402
from chaospound.dynamics.impact_map import impact_map  # noqa: E402
from chaospound.dynamics.lyapunov import (  # noqa: E402
    largest_exponent_two_trajectory,
    lyapunov_spectrum,
)
from chaospound.dynamics.poincare import impact_section, stroboscopic_section  # noqa: E402
from chaospound.scene import load_preset  # noqa: E402
from chaospound.simulate import simulate  # noqa: E402

FIG3A = load_preset("fig3a")


@functools.cache
def fig3a_run():
    return simulate(FIG3A, transient=60, record=3, samples_per_cycle=120)


@functools.cache
def fig3a_spectrum():
    return lyapunov_spectrum(FIG3A, k=3, tangent_transient=5, cycles=30)


def numbered(ax) -> list:
    """The impact-number annotations of a panel, in drawing order."""
    return [t for t in ax.texts if (t.get_gid() or "").startswith("impact-")]


# ------------------------------------------------------------ phase diagrams
def test_phase_diagrams_of_towers_model():
    sim = fig3a_run()
    fig = plot.plot_phase_diagrams(sim)
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    expected = [("X_A", "dX_A"), ("th_A", "dth_A"), ("X_B", "dX_B"), ("th_B", "dth_B")]
    last = np.nonzero(sim.impacts.cycle == sim.transient + sim.record - 1)[0]
    assert len(last) == 3  # fig3a: three impacts per cycle
    for ax, (position, rate) in zip(fig.axes, expected, strict=True):
        assert ax.get_xlabel() == plot.axis_label(position)
        assert ax.get_ylabel() == plot.axis_label(rate)
        assert ax.get_title()
        # the record-window trajectory is drawn, as is
        i, j = sim.state_names.index(position), sim.state_names.index(rate)
        xs, ys = ax.lines[0].get_data()
        np.testing.assert_array_equal(xs, sim.trajectory.state[:, i])
        np.testing.assert_array_equal(ys, sim.trajectory.state[:, j])
        # impacts of the last cycle numbered 1, 2, 3 at their onset states, in time order
        notes = numbered(ax)
        assert [t.get_text() for t in notes] == [str(n + 1) for n in range(len(last))]
        for note, k in zip(notes, last, strict=True):
            assert note.xy == pytest.approx((sim.impacts.state[k, i], sim.impacts.state[k, j]))
    units = [fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel(), fig.axes[1].get_xlabel()]
    assert "A_g" in units[0] and r"\omega_{Ax}" in units[1] and "rad" in units[2]
    caption = fig._supxlabel.get_text()
    labels = [sim.impacts.labels[k] for k in last]
    assert labels == ["A+", "B-", "A+"]
    positions = [caption.index(f"({n + 1}) {label}") for n, label in enumerate(labels)]
    assert positions == sorted(positions)


@pytest.mark.parametrize(
    ("preset", "panels"),
    [
        ("fig4-translational", [("X_A", "dX_A"), ("X_B", "dX_B")]),
        ("tower-wall", [("X_A", "dX_A"), ("th_A", "dth_A")]),
        ("wall", [("X_A", "dX_A")]),
    ],
)
def test_phase_diagrams_of_reduced_models(preset, panels):
    sim = simulate(load_preset(preset), transient=20, record=2, samples_per_cycle=60)
    fig = plot.plot_phase_diagrams(sim)
    assert len(fig.axes) == len(panels)
    for ax, (position, rate) in zip(fig.axes, panels, strict=True):
        assert (ax.get_xlabel(), ax.get_ylabel()) == (
            plot.axis_label(position),
            plot.axis_label(rate),
        )
        n_last = int(np.sum(sim.impacts.cycle == sim.transient + sim.record - 1))
        assert len(numbered(ax)) == n_last


def test_phase_diagrams_need_a_trajectory():
    with pytest.raises(ValueError, match="samples_per_cycle"):
        plot.plot_phase_diagrams(simulate(FIG3A, transient=1, record=1))


def test_axis_labels_carry_units():
    assert plot.axis_label("X_B") == "$X_B/A_g$"
    assert plot.axis_label("dY_A") == r"$\dot Y_A/(A_g\,\omega_{Ax})$"
    assert plot.axis_label("th_A") == r"$\theta_A$ (rad)"
    assert "rad" in plot.axis_label("dth_B")
    assert plot.axis_label("x") == "x"


# ---------------------------------------------------------------- sections
def test_strobe_plot_draws_the_section_points():
    section = stroboscopic_section(FIG3A, phase=0.25, transient=10, cycles=6)
    fig = plot.plot_strobe(section)
    assert len(fig.axes) == 4
    names = section.state_names
    for ax, (_, position, rate) in zip(fig.axes, plot.phase_panels(names), strict=True):
        points = ax.collections[0].get_offsets()
        np.testing.assert_array_equal(points[:, 0], section.component(position))
        np.testing.assert_array_equal(points[:, 1], section.component(rate))
        assert ax.get_xlabel() and ax.get_ylabel()
    assert "phase 0.25" in fig.get_suptitle() and "7 points" in fig.get_suptitle()


def test_impact_section_plot_is_coloured_by_corner():
    section = impact_section(fig3a_run())
    fig = plot.plot_strobe(section)
    legend = fig.axes[0].get_legend()
    assert sorted(t.get_text() for t in legend.get_texts()) == ["A+", "B-"]
    drawn = sum(len(c.get_offsets()) for c in fig.axes[0].collections)
    assert drawn == len(section) == 9


# -------------------------------------------------------------- impact map
def test_impact_map_plot():
    imap = impact_map(fig3a_run())
    fig = plot.plot_impact_map(imap)
    assert len(fig.axes) == 3
    sequence, ret, phase_ret = fig.axes
    assert "phase" in sequence.get_xlabel() and "A_g" in sequence.get_ylabel()
    assert "V_n" in ret.get_xlabel() and "V_{n+1}" in ret.get_ylabel()
    # every impact drawn once in the sequence, every pair once in the return map
    assert sum(len(c.get_offsets()) for c in sequence.collections) == len(imap)
    pairs = np.concatenate([c.get_offsets() for c in ret.collections])
    assert pairs.shape == imap.velocity_pairs.shape
    np.testing.assert_allclose(np.sort(pairs[:, 0]), np.sort(imap.velocity_pairs[:, 0]))
    # the phase return map: every pair (phase_n, phase_n+1) once
    phases = np.concatenate([c.get_offsets() for c in phase_ret.collections])
    np.testing.assert_array_equal(np.sort(phases, axis=0), np.sort(imap.phase_pairs, axis=0))
    assert "varphi_n" in phase_ret.get_xlabel() and "varphi_{n+1}" in phase_ret.get_ylabel()
    labels = {t.get_text() for t in sequence.get_legend().get_texts()}
    assert labels == {"A+", "B-"}


# ---------------------------------------------------------------- lyapunov
def test_lyapunov_convergence_plot():
    spectrum = fig3a_spectrum()
    two = largest_exponent_two_trajectory(FIG3A.with_params(rtol=1e-10, atol=1e-12), cycles=20)
    fig = plot.plot_lyapunov_convergence(spectrum, two)
    ax = fig.axes[0]
    assert len(fig.axes) == 1
    histories = [line for line in ax.lines if len(line.get_xdata()) == spectrum.cycles]
    for i in range(3):
        np.testing.assert_array_equal(histories[i].get_ydata(), spectrum.history[:, i])
    dashed = [line for line in ax.lines if line.get_linestyle() == "--"]
    np.testing.assert_array_equal(dashed[0].get_ydata(), two.history)
    [legend] = fig.legends  # under the axes, in columns
    texts = [t.get_text() for t in legend.get_texts()]
    assert len(texts) == 4 and f"{spectrum.exponents[0]:.4g}" in texts[0]
    assert "omega_{Ax}" in ax.get_ylabel() and "cycles" in ax.get_xlabel()
    lo, hi = ax.get_ylim()
    assert lo < spectrum.exponents.min() and hi >= 0.0  # final values and zero visible


def test_lyapunov_convergence_of_twelve_exponents_is_readable():
    """12 distinct colours, the curves take the figure's width, the scene is named."""
    from matplotlib.colors import to_hex

    scene = load_preset("fig4").with_params(period_ratio=0.9, transient=5)
    spectrum = lyapunov_spectrum(scene, tangent_transient=5, cycles=20)
    assert spectrum.exponents.size == 12
    fig = plot.plot_lyapunov_convergence(spectrum, scene="fig4, T/T_Ax = 0.9")
    ax = fig.axes[0]
    histories = [line for line in ax.lines if len(line.get_xdata()) == spectrum.cycles]
    assert len({to_hex(line.get_color()) for line in histories}) == 12
    assert ax.get_title().startswith("fig4, T/T_Ax = 0.9: Lyapunov exponents")
    fig.draw_without_rendering()  # constrained layout
    box = ax.get_position()
    assert box.width > 0.8  # was 0.6: the legend's column left a third of the width empty
    assert fig.legends[0].get_window_extent().y1 < box.y0 * fig.bbox.height


def test_plots_draw_into_given_axes():
    fig = Figure()
    ax = fig.add_subplot()
    assert plot.plot_lyapunov_convergence(fig3a_spectrum(), ax=ax) is fig
    empty = Figure()
    assert plot.plot_impact_map(impact_map(fig3a_run()), fig=empty) is empty
    with pytest.raises(ValueError, match="already has axes"):
        plot.plot_impact_map(impact_map(fig3a_run()), fig=fig)


# ------------------------------------------------------------- bifurcation
@functools.cache
def small_sweep():
    """Translational pair model at three period ratios (the paper's Fig. 4 dots)."""
    ratios = [0.6, 0.8, 1.2]
    runs = [
        simulate(
            load_preset("fig4-translational").with_params(period_ratio=r), transient=30, record=4
        )
        for r in ratios
    ]
    return ratios, [run.impacts.velocity for run in runs]


def test_bifurcation_diagram_points_and_regimes():
    ratios, velocities = small_sweep()
    regimes = ["periodic 1-1", "chaotic", "periodic 1-1"]
    fig = plot.plot_bifurcation(ratios, velocities, regimes=regimes)
    assert len(fig.axes) == 1
    ax = fig.axes[0]
    assert ax.get_xlabel() == plot.PERIOD_RATIO_LABEL and "A_g" in ax.get_ylabel()
    drawn = {c.get_label(): c.get_offsets() for c in ax.collections}
    assert set(drawn) == {"periodic", "chaotic"}
    assert len(drawn["periodic"]) == len(velocities[0]) + len(velocities[2])
    np.testing.assert_array_equal(drawn["chaotic"][:, 0], ratios[1])
    np.testing.assert_array_equal(drawn["chaotic"][:, 1], velocities[1])


def test_bifurcation_with_exponent_panel():
    ratios, velocities = small_sweep()
    fig = plot.plot_bifurcation(ratios, velocities, exponents=[-0.1, np.nan, -0.05])
    assert len(fig.axes) == 2
    bottom = fig.axes[1]
    assert "lambda" in bottom.get_ylabel() and bottom.get_xlabel() == plot.PERIOD_RATIO_LABEL
    assert len(bottom.collections[0].get_offsets()) == 2  # the NaN point is left out
    with pytest.raises(ValueError, match="exponents"):
        plot.plot_bifurcation(ratios, velocities, exponents=[0.1])
    with pytest.raises(ValueError, match="regimes"):
        plot.plot_bifurcation(ratios, velocities, regimes=["chaotic"])


# -------------------------------------------------------------------- save
def test_save_writes_png_atomically(tmp_path):
    fig = plot.plot_impact_map(impact_map(fig3a_run()))
    target = tmp_path / "map.png"
    plot.save(fig, target)
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert os.listdir(tmp_path) == ["map.png"]  # no temporary left behind
    with pytest.raises(FileNotFoundError, match="does not exist"):
        plot.save(fig, tmp_path / "missing" / "map.png")
    assert not (tmp_path / "missing").exists()
    with pytest.raises(ValueError):
        plot.save(fig, tmp_path / "map.unknown-format")
    assert os.listdir(tmp_path) == ["map.png"]  # a failed write leaves nothing


# ------------------------------------------------------ chaospound lyapunov
def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_lyapunov_json(capsys):
    code, out, err = run_cli(
        capsys, "lyapunov", "--preset", "fig3a", "--k", "2", "--cycles", "40", "--json"
    )
    assert code == 0 and err == ""
    document = json.loads(out)
    for key in (
        "exponents",
        "errors",
        "max_exponent",
        "per_cycle",
        "errors_per_cycle",
        "sum",
        "trace",
        "kaplan_yorke",
        "model",
        "scene",
    ):
        assert key in document
    assert document["model"] == "towers" and len(document["exponents"]) == 2
    assert document["sum"] == pytest.approx(sum(document["exponents"]), rel=1e-12)
    period = document["period"]
    assert document["per_cycle"] == pytest.approx([e * period for e in document["exponents"]])
    assert document["max_exponent"] == max(document["exponents"])
    assert document["max_exponent"] < 0  # fig3a is periodic
    assert "two_trajectory" not in document


def test_cli_lyapunov_full_spectrum_obeys_trace_identity(capsys, tmp_path):
    figure = tmp_path / "lyap.png"
    code, out, _ = run_cli(
        capsys,
        "lyapunov",
        "--preset",
        "fig3a",
        "--cycles",
        "40",
        "--tangent-transient",
        "5",
        "--two-trajectory",
        "--json",
        "--plot",
        str(figure),
    )
    assert code == 0
    document = json.loads(out)
    assert len(document["exponents"]) == 12 and document["full_spectrum"]
    assert document["sum"] == pytest.approx(document["trace"], rel=1e-3)
    two = document["two_trajectory"]
    assert abs(two["exponent"] - document["max_exponent"]) < 3 * (two["error"] + 0.005)
    assert figure.read_bytes()[:4] == b"\x89PNG"


def test_cli_lyapunov_report(capsys):
    code, out, _ = run_cli(capsys, "lyapunov", "--preset", "fig3a", "--k", "3", "--cycles", "20")
    assert code == 0
    assert "lambda (per unit t)" in out and "lambda T (per cycle)" in out
    assert "Kaplan-Yorke dimension" in out and "sum" in out and "trace identity" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--k", "13"], "--k 13"),
        (["--k", "0"], "--k 0"),
        (["--k", "two"], "--k"),
        (["--cycles", "5"], "--cycles 5"),
    ],
)
def test_cli_lyapunov_bad_input_exits_2_with_one_line(capsys, tmp_path, argv, message):
    target = tmp_path / "out.png"
    code, out, err = run_cli(capsys, "lyapunov", "--preset", "fig3a", *argv, "--plot", str(target))
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("chaospound: error:") and message in err
    assert not target.exists()


def test_cli_lyapunov_plot_into_missing_folder(capsys, tmp_path):
    code, out, err = run_cli(
        capsys,
        "lyapunov",
        "--preset",
        "fig3a",
        "--cycles",
        "10",
        "--plot",
        str(tmp_path / "no" / "lyap.png"),
    )
    assert code == 2 and out == "" and "does not exist" in err


def test_cli_figures_are_redrawn_but_data_files_are_not_replaced(capsys, tmp_path):
    """A figure is a derived product: --plot redraws an existing figure without
    --overwrite; a data file (.json, .h5) is never replaced by a figure."""
    target = tmp_path / "lyap.png"
    target.write_bytes(b"an old figure")
    argv = ["lyapunov", "--preset", "wall", "--transient", "5", "--cycles", "10"]
    code, out, err = run_cli(capsys, *argv, "--plot", str(target))
    assert code == 0, err
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, out, err = run_cli(capsys, *argv, "--plot", str(target))  # again
    assert code == 0 and err == "" and "wrote" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lyap.png"]
    for name in ("run.json", "fig4.h5"):
        data = tmp_path / name
        data.write_text("results", encoding="utf-8")
        code, out, err = run_cli(capsys, *argv, "--plot", str(data))
        assert code == 2 and out == "" and "not a figure format" in err and name in err
        assert data.read_text(encoding="utf-8") == "results"


def test_cli_classify_phase_diagrams_are_smooth(capsys, tmp_path, monkeypatch):
    """2000 dense samples per cycle: about 90 across a contact (10 before: polygons)."""
    import chaospound.plot

    drawn = []
    real_save = chaospound.plot.save
    monkeypatch.setattr(chaospound.plot, "save", lambda fig, path: (drawn.append(fig),
                                                                    real_save(fig, path)))
    target = tmp_path / "phase.png"
    code, out, err = run_cli(capsys, "classify", "--preset", "fig3a", "--transient", "5",
                             "--max-transient", "40", "--plot", str(target))
    assert code == 0, err
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    [fig] = drawn
    for ax in fig.axes:
        whole, last_cycle = ax.lines[:2]
        assert len(last_cycle.get_xdata()) >= 2000


# ------------------------------------------------ chaospound plot (issue 18 item 3)
@pytest.fixture(scope="module")
def hysteresis_file(tmp_path_factory):
    """The README's hysteresis sweep on a coarse grid: wall, gap 5, both ways."""
    path = tmp_path_factory.mktemp("hysteresis") / "hysteresis.h5"
    assert main(["sweep", "--preset", "wall", "--set", "gap=5", "--param",
                 "period_ratio=0.45:1.0#12", "--continuation", "both", "-o", str(path),
                 "--quiet"]) == 0
    return path


def test_parameter_labels_are_symbols_with_units():
    from chaospound.scene import PARAMETERS, Scene

    assert plot.parameter_label("period_ratio") == r"$T/T_{Ax}$"
    assert plot.parameter_label("gap") == r"$a/A_g$"
    assert plot.parameter_label("ecc_y_ratio_A") == r"$e_{Ay}/l_{A}$"
    assert plot.parameter_label("zeta_t_B") == r"$\zeta_{B\theta}$"
    numeric = [name for name in PARAMETERS
               if isinstance(Scene().to_dict()[name], int | float)
               and not isinstance(Scene().to_dict()[name], bool) and name != "max_steps"]
    assert [name for name in numeric if plot.parameter_label(name) == name] == []


def test_hysteresis_overlays_both_branches_and_marks_points_without_impacts(hysteresis_file):
    from chaospound import cli
    from chaospound.store import open_sweep

    sweep = open_sweep(hysteresis_file)
    fig = cli._sweep_figure(sweep, sweep.branches)
    [ax] = fig.axes  # one axis, both branches
    assert ax.get_xlabel() == r"$T/T_{Ax}$" and "fresh" not in ax.get_title()
    forward, backward = ax.collections
    assert forward.get_paths()[0] != backward.get_paths()[0]  # > and < markers
    for branch, points in (("forward", forward), ("backward", backward)):
        counts = sweep.array("impact_count", branch)
        assert len(points.get_offsets()) == int(counts.sum())
        rug = [line for line in ax.lines if line.get_label().startswith(f"{branch}: no impact")]
        silent = int(np.count_nonzero(counts == 0))
        if silent:
            [line] = rug
            np.testing.assert_array_equal(line.get_xdata(),
                                          sweep.grid["period_ratio"][counts == 0])
        else:
            assert rug == []
    # the README's case coexists: the backward branch pounds where the forward one does not
    assert np.count_nonzero(sweep.array("impact_count", "backward")) > \
        np.count_nonzero(sweep.array("impact_count", "forward"))


def test_plot_command_size_dpi_limits_and_vector_output(hysteresis_file, capsys, monkeypatch):
    from matplotlib.image import imread

    import chaospound.plot

    drawn = []
    real_save = chaospound.plot.save
    monkeypatch.setattr(chaospound.plot, "save", lambda fig, path, **kw: (
        drawn.append(fig), real_save(fig, path, **kw)))
    png = hysteresis_file.with_name("small.png")
    code, out, err = run_cli(capsys, "plot", str(hysteresis_file), "-o", str(png), "--size",
                             "4,3", "--dpi", "50", "--xlim", "0.5,0.9", "--ylim", "0,30")
    assert code == 0, err
    assert imread(png).shape[:2] == (150, 200)  # 3 x 4 inches at 50 dpi
    main_axis = drawn[-1].axes[0]
    assert main_axis.get_xlim() == (0.5, 0.9) and main_axis.get_ylim() == (0.0, 30.0)
    for suffix, magic in ((".svg", b"<?xml"), (".pdf", b"%PDF")):
        target = hysteresis_file.with_name("vector" + suffix)
        code, out, err = run_cli(capsys, "plot", str(hysteresis_file), "-o", str(target))
        assert code == 0 and target.read_bytes().startswith(magic)
    for bad in (["--size", "0,3"], ["--xlim", "2,1"], ["--dpi", "0"], ["--ylim", "1"]):
        code, out, err = run_cli(capsys, "plot", str(hysteresis_file), *bad)
        assert code == 2 and out == "" and err.count("\n") == 1 and bad[0] in err
    # a raster image too large for memory is refused before matplotlib allocates it
    for bad in (["--size", "1000,1000"], ["--dpi", "100000"]):
        huge = hysteresis_file.with_name("huge.png")
        code, out, err = run_cli(capsys, "plot", str(hysteresis_file), "-o", str(huge), *bad)
        assert code == 2 and out == "" and err.count("\n") == 1 and "too large" in err
        assert not huge.exists()
    code, out, err = run_cli(capsys, "plot", "--help")
    assert code == 0
    for word in ("--dpi", "--size", "--xlim", "--ylim", ".pdf", ".svg", "vector"):
        assert word in out


def test_paper_fig4_regimes_titles_stay_on_the_canvas(monkeypatch):
    """analysis/reproduce_paper.py: panel (b)'s title ran off the 11-inch canvas."""
    import importlib.util
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "analysis" / "reproduce_paper.py"
    spec = importlib.util.spec_from_file_location("reproduce_paper_titles", script)
    paper = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, paper)  # for its dataclasses
    spec.loader.exec_module(paper)
    values = np.linspace(0.3, 2.0, 30)
    regimes = ["periodic 1-1"] * 15 + ["chaotic"] * 15
    scan = {"values": values, "regime": regimes, "lam": np.full(30, 0.01),
            "lam_err": np.full(30, 0.001), "velocities": [[1.0]] * 30}
    adaptive = {"values": values, "regime": regimes,
                "points": [{"lam": 0.02}] * 30}
    drawn = []
    monkeypatch.setattr(paper.cplot, "save", lambda fig, path: drawn.append(fig))
    paper.figure_fig4_regimes(Path("unused.png"), {"translational": scan, "torsional": scan},
                              {"translational": adaptive, "torsional": adaptive}, {})
    [fig] = drawn
    fig.draw_without_rendering()
    width = fig.bbox.width
    for ax in fig.axes:
        box = ax.title.get_window_extent()
        assert box.x0 >= 0 and box.x1 <= width, ax.get_title()


# ------------------------------- exponent maps and orbit diagrams (issue 17 items 2, 3)
WALL_SWEEP = ["sweep", "--preset", "wall", "--set", "transient=20", "--set", "record=4",
              "--param", "period_ratio=0.5:1.5#6", "--quiet"]


@pytest.fixture(scope="module")
def wall_sweeps(tmp_path_factory):
    """Small wall sweeps: one parameter with exponents, two parameters with exponents,
    and a converged one (long transient, tight tolerances) for periodic orbits."""
    folder = tmp_path_factory.mktemp("maps")
    one, two, tight = folder / "one.h5", folder / "two.h5", folder / "tight.h5"
    lyapunov = ["--lyapunov", "--lyapunov-cycles", "10"]
    assert main([*WALL_SWEEP, *lyapunov, "-o", str(one)]) == 0
    assert main([*WALL_SWEEP, "--param", "gap=1,2", *lyapunov, "-o", str(two)]) == 0
    assert main(["sweep", "--preset", "wall", "--set", "transient=300", "--set", "record=4",
                 "--set", "rtol=1e-10", "--set", "atol=1e-12", "--param",
                 "period_ratio=0.9,1.1,1.5", "--quiet", "-o", str(tight)]) == 0
    return {"one": one, "two": two, "tight": tight}


def panels(fig, label):
    return [ax for ax in fig.axes if ax.get_label() == label]


def test_exponent_map_is_the_stored_largest_exponent(wall_sweeps):
    from matplotlib.colors import TwoSlopeNorm

    from chaospound import cli
    from chaospound.store import open_sweep

    sweep = open_sweep(wall_sweeps["two"])
    fig = cli._sweep_figure(sweep, sweep.branches)
    [regimes] = panels(fig, "main")
    [lam_ax] = panels(fig, "exponents")
    [mesh] = lam_ax.collections
    lam = sweep.array("max_exponent").reshape(sweep.shape)
    status = np.asarray(sweep.status(), dtype=object).reshape(sweep.shape)
    data = mesh.get_array()
    assert data.shape == lam.T.shape  # rows: the second parameter (gap)
    failed = (status == "failed") | (status == "pending") | ~np.isfinite(lam)
    np.testing.assert_array_equal(np.ma.getmaskarray(data), failed.T)
    np.testing.assert_array_equal(data.compressed(), lam.T[~failed.T])
    assert np.isfinite(lam).all() and (status == "done").all()
    # diverging, centred on zero, with a labelled colour bar in the exponent's unit
    assert mesh.get_cmap().name.startswith("RdBu_r")
    assert isinstance(mesh.norm, TwoSlopeNorm) and mesh.norm.vcenter == 0.0
    [bar] = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    assert bar.get_ylabel() == plot.EXPONENT_LABEL and r"\omega_{Ax}" in bar.get_ylabel()
    for ax in (regimes, lam_ax):
        assert ax.get_xlabel() == r"$T/T_{Ax}$" and ax.get_ylabel() == r"$a/A_g$"
    # a failed point is masked (grey), not drawn as an exponent
    x, y = sweep.grid["period_ratio"], sweep.grid["gap"]
    missing = np.zeros(lam.shape, dtype=bool)
    missing[2, 1] = True
    fig = plot.plot_exponent_map(x, y, lam, missing=missing)
    data = fig.axes[0].collections[0].get_array()
    assert np.ma.getmaskarray(data)[1, 2] and data.count() == lam.size - 1
    assert tuple(fig.axes[0].collections[0].get_cmap().get_bad()[:3]) == pytest.approx(
        (0.75, 0.75, 0.75))


def test_one_parameter_exponent_panel_has_error_bars(wall_sweeps):
    from chaospound import cli
    from chaospound.store import open_sweep

    sweep = open_sweep(wall_sweeps["one"])
    fig = cli._sweep_figure(sweep, sweep.branches)
    [lam_ax] = panels(fig, "exponents")
    [bars] = lam_ax.containers
    lam, err = sweep.array("max_exponent"), sweep.array("max_exponent_error")
    segments = bars.lines[2][0].get_segments()
    assert len(segments) == lam.size
    for segment, value, error in zip(segments, lam, err, strict=True):
        np.testing.assert_allclose(segment[:, 1], [value - error, value + error])
    # kept whenever exponents exist, whatever the classification: here the sweep's
    # own --lyapunov flag is hidden and the stored exponents decide
    sweep.sweep["lyapunov"] = 0
    assert len(panels(cli._sweep_figure(sweep, sweep.branches), "exponents")) == 1


def test_orbit_diagram_draws_the_stored_strobe_component(wall_sweeps, capsys, monkeypatch):
    import chaospound.plot
    from chaospound.store import open_sweep

    drawn = []
    real_save = chaospound.plot.save
    monkeypatch.setattr(chaospound.plot, "save", lambda fig, path, **kw: (
        drawn.append(fig), real_save(fig, path, **kw)))
    path = wall_sweeps["one"]
    sweep = open_sweep(path)
    for state in sweep.state_names:
        code, out, err = run_cli(capsys, "plot", str(path), "--orbit", state)
        assert code == 0, err
        fig = drawn[-1]
        assert len(panels(fig, "main")) == 1  # beside the impact-velocity spectrum
        [orbit] = panels(fig, "orbit")
        k = sweep.state_names.index(state)
        offsets = orbit.collections[-1].get_offsets()
        n = len(sweep.grid["period_ratio"])
        expected_y = np.concatenate([sweep.strobe(i)[:, k] for i in range(n)])
        expected_x = np.repeat(sweep.grid["period_ratio"], sweep.array("strobe_count"))
        np.testing.assert_array_equal(offsets[:, 1], expected_y)
        np.testing.assert_array_equal(offsets[:, 0], expected_x)
        assert orbit.get_ylabel() == plot.axis_label(state)
        assert orbit.get_xlabel() == r"$T/T_{Ax}$"
    code, out, err = run_cli(capsys, "plot", str(path), "--orbit", "Q_A")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert all(name in err for name in sweep.state_names)


def test_orbit_diagram_of_periodic_points_collapses_to_period_cycles_values(wall_sweeps):
    from chaospound import cli
    from chaospound.store import open_sweep

    sweep = open_sweep(wall_sweeps["tight"])
    fig = cli._sweep_figure(sweep, sweep.branches, orbit="X_A")
    [orbit] = panels(fig, "orbit")
    offsets = orbit.collections[-1].get_offsets()
    periods = sweep.array("period_cycles")
    regimes = sweep.regimes()
    assert regimes.count("periodic") >= 2 and set(periods[:2]) == {1}
    counts = sweep.array("strobe_count")
    start = np.concatenate(([0], np.cumsum(counts)[:-1]))
    for i, regime in enumerate(regimes):
        if regime.split()[0] != "periodic":
            continue
        ys = offsets[start[i]:start[i] + counts[i], 1]
        p = int(periods[i])
        np.testing.assert_allclose(ys[p:], ys[:-p], atol=1e-6)  # repeats after p cycles
        distinct = 1 + np.count_nonzero(np.diff(np.sort(ys)) > 1e-6)
        assert distinct == p  # period 1: every strobe point within 1e-6 of the others


def test_branch_curves_follow_their_impact_where_the_list_rotates():
    """An orbit lists its impacts from the section; where one crosses the section the
    list rotates. The diagram's curves follow each impact (no vertical jump), and a row
    with another number of impacts (a grazing) is left as it is."""
    from chaospound.plot import _follow_curves

    lam = np.linspace(0.0, 1.0, 11)
    low, high = 1.0 + 0.1 * lam, 5.0 - 0.2 * lam
    curves = np.stack([low, high], axis=1)
    curves[6:] = curves[6:, ::-1]  # rotated from row 6 on
    curves = np.vstack([curves, [[7.0, np.nan]]])  # one impact fewer
    _follow_curves(curves)
    assert np.array_equal(curves[:11, 0], low) and np.array_equal(curves[:11, 1], high)
    assert curves[11, 0] == 7.0 and np.isnan(curves[11, 1])
