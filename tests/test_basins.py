"""Basins of attraction (chaospound.basins): scans of initial conditions in the sweep store.

The bistable oscillator is the twin-well Duffing x'' + 0.25 x' - x + x^3 =
0.1 cos t: weakly forced, each well holds a period-1 attractor (about
x = +1.09 and -0.90 at the section t = 2 pi k), with the interleaved spiral
basins of Ueda and Moon's figures. Its damping makes the transient decay like
exp(-0.125 t), by 2e-14 over 40 periods, so a 40-period transient reaches
the attractor and an independent integrator (scipy's DOP853 at rtol 1e-10)
from any initial state must end on the attractor the map gives its cell.

The wall preset with the gap widened to 5 A_g (tests/test_sweep.py's hysteresis
scene) at T/T_Ax = 0.75 has a non-impacting response and a period-1 impacting
one; continuation forward (from below) and backward (from above) lands on one
each, and the basin map must find both, at the same section states.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from storecheck import assert_same_store

from chaospound import sweep as sweep_module
from chaospound.basins import (
    FAILED,
    PENDING,
    basin_entropy,
    basins,
    identify,
    open_basins,
)
from chaospound.dynamics.system import duffing
from chaospound.grid import initial_axis
from chaospound.scene import load_preset
from chaospound.store import open_sweep
from chaospound.sweep import SweepInterrupted, SweepSpec, parse_axis, run_sweep

DAMPING, FORCE, OMEGA = 0.25, 0.1, 1.0
TWIN_WELL = dataclasses.replace(
    duffing(damping=DAMPING, linear=-1.0, cubic=1.0, amplitude=FORCE, frequency=OMEGA),
    transient=40, record=8)
DUFFING_GRID = ("x=-2:2#24", "dx=-2:2#24")
WALL = load_preset("wall").with_params(gap=5.0, period_ratio=0.75, transient=100, record=8)
WALL_GRID = ("X_A=-8:4#10", "dX_A=-12:12#10")


@pytest.fixture(scope="module")
def twin_well(tmp_path_factory):
    path = tmp_path_factory.mktemp("basins") / "duffing.h5"
    summary, result = basins(TWIN_WELL, DUFFING_GRID, path, progress=False)
    return path, summary, result


def test_twin_well_has_two_period_one_attractors(twin_well):
    _, summary, result = twin_well
    assert summary.computed == 24 * 24 and summary.failed == 0
    assert len(result.attractors) == 2
    wells = sorted(result.attractors, key=lambda a: a.sections[0, 0])
    for a, sign in zip(wells, (-1, 1), strict=True):
        assert a.regime == "none" and a.period_cycles == 1  # no gap: no impacts
        assert np.sign(a.sections[0, 0]) == sign and 0.5 < abs(a.sections[0, 0]) < 1.5
    assert sum(a.count for a in result.attractors) == 24 * 24
    assert math.isclose(sum(a.share for a in result.attractors), 1.0)
    # interleaved basins: both attractors meet in many boxes
    assert 0.1 < result.entropy < math.log(2)
    assert result.boundary_boxes > 0 and result.boundary_entropy >= result.entropy


def duffing_rhs(t, y):
    x, v = y
    return [v, FORCE * math.cos(OMEGA * t) - DAMPING * v + x - x**3]


def test_twin_well_map_agrees_with_brute_force_scipy(twin_well):
    """100 random initial states integrated by scipy's DOP853 (independent of the engine):
    each ends on the attractor of its nearest cell, wherever that cell's neighbours
    (within one cell) all reach the same attractor."""
    _, _, result = twin_well
    x, dx = result.grid["x"], result.grid["dx"]
    rng = np.random.default_rng(17)
    starts = rng.uniform(-2.0, 2.0, size=(100, 2))
    period = 2.0 * math.pi / OMEGA
    cycles = TWIN_WELL.transient + TWIN_WELL.record
    compared = 0
    for y0 in starts:
        i, j = int(np.argmin(np.abs(x - y0[0]))), int(np.argmin(np.abs(dx - y0[1])))
        block = result.labels[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2]
        if np.any(block != block.flat[0]):
            continue  # within a cell of a boundary: the grid cannot say
        sol = solve_ivp(duffing_rhs, (0.0, cycles * period), y0, method="DOP853",
                        rtol=1e-10, atol=1e-12)
        assert sol.success
        end = sol.y[:, -1]
        distances = [np.max(np.abs(end - a.sections[0])) for a in result.attractors]
        assert min(distances) < 1e-6  # on an attractor's section state
        assert int(np.argmin(distances)) == result.labels[i, j], (y0, end)
        compared += 1
    assert compared >= 40


def test_wall_basins_find_both_hysteresis_branches(tmp_path):
    """At T/T_Ax = 0.75 the hysteresis sweep's forward branch does not impact and its
    backward branch impacts once per cycle; the basin map finds exactly these two
    attractors, at the branches' section states."""
    _, result = basins(WALL, WALL_GRID, tmp_path / "wall.h5", progress=False)
    labels = {a.label: a for a in result.attractors}
    assert sorted(labels) == ["none 0-1", "periodic 1-1 (face)"]
    assert all(a.share > 0.05 for a in result.attractors)
    assert result.failed == 0
    # the hysteresis: continuation both ways over 0.45..1.0 lands on one attractor each
    scene = WALL.with_params(transient=100)
    axis = parse_axis("period_ratio=0.45:1.0:0.05", scene)
    run_sweep(scene, SweepSpec((axis,), continuation="both"), tmp_path / "hyst.h5",
              progress=False)
    hysteresis = open_sweep(tmp_path / "hyst.h5")
    at = int(np.flatnonzero(hysteresis.grid["period_ratio"] == 0.75)[0])
    forward = hysteresis.array("final_state", "forward")[at]
    backward = hysteresis.array("final_state", "backward")[at]
    assert hysteresis.impacts(at, "forward")["time"].size == 0
    assert hysteresis.array("impacts_per_period", "backward")[at] == 1
    for state, label in ((forward, "none 0-1"), (backward, "periodic 1-1 (face)")):
        section = labels[label].sections[0]
        assert np.max(np.abs(state - section)) < 1e-3 * np.max(np.abs(section))
    # the initial conditions at the attractors' own section states are in their basins
    for a in result.attractors:
        i = int(np.argmin(np.abs(result.grid["X_A"] - a.sections[0, 0])))
        j = int(np.argmin(np.abs(result.grid["dX_A"] - a.sections[0, 1])))
        block = result.labels[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2]
        if np.all(block == block.flat[0]):
            assert result.labels[i, j] == a.number


def test_resume_after_interruption_gives_the_same_file(tmp_path, monkeypatch):
    """A Ctrl-C after some tasks keeps their points; the resumed scan's file (points and
    /basins) is bitwise the uninterrupted one's, timing fields aside."""
    reference = tmp_path / "whole.h5"
    basins(WALL, WALL_GRID, reference, progress=False, chunk=4)
    path = tmp_path / "interrupted.h5"
    real, calls = sweep_module.run_task, []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 8:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(sweep_module, "run_task", interrupted)
    with pytest.raises(SweepInterrupted):
        basins(WALL, WALL_GRID, path, progress=False, chunk=4)
    monkeypatch.setattr(sweep_module, "run_task", real)
    partial = open_basins(path)  # the journal's points: identified, the rest pending
    done = int(np.sum(partial.labels != PENDING))
    assert 0 < done < partial.labels.size
    basins(WALL, WALL_GRID, path, progress=False, chunk=4, resume=True)
    assert_same_store(path, reference)
    again = open_basins(path)
    assert np.array_equal(again.labels, open_basins(reference).labels)


def test_a_scan_killed_before_its_basins_group_is_completed_by_resume(tmp_path):
    """The points are consolidated first, the /basins group is added after: a file
    without the group (a kill in between) is identified on reading, and --resume
    adds the group, the uninterrupted scan's file again."""
    reference = tmp_path / "whole.h5"
    _, whole = basins(WALL, WALL_GRID, reference, progress=False)
    path = tmp_path / "points-only.h5"
    axes = tuple(initial_axis(g, WALL) for g in WALL_GRID)
    run_sweep(WALL, SweepSpec(axes), path, progress=False)  # what a kill would leave
    assert np.array_equal(open_basins(path).labels, whole.labels)
    summary, _ = basins(WALL, WALL_GRID, path, progress=False, resume=True)
    assert summary.finished_before and summary.computed == 0
    assert_same_store(path, reference)


def test_one_and_two_workers_give_identical_files(tmp_path):
    one, two = tmp_path / "one.h5", tmp_path / "two.h5"
    basins(TWIN_WELL, ("x=-2:2#8", "dx=-2:2#8"), one, progress=False)
    basins(TWIN_WELL, ("x=-2:2#8", "dx=-2:2#8"), two, progress=False, workers=2)
    assert_same_store(one, two)


def test_initial_phase_axis_starts_the_forcing_there(tmp_path):
    """With x, x' = 0 at forcing phase phi (the time phi T), scipy from t = phi T
    to the section 48 T later ends where the scan's point does."""
    _, result = basins(TWIN_WELL, ("initial_phase=0:0.75#4", "x=0.5:1.5#3"),
                       tmp_path / "phase.h5", progress=False)
    sweep = open_sweep(tmp_path / "phase.h5")
    period = 2.0 * math.pi / OMEGA
    for k, phi in enumerate(result.grid["initial_phase"]):
        for m, x0 in enumerate(result.grid["x"]):
            index = k * 3 + m
            start = phi * period - (period if phi > 0 else 0.0)
            end = (TWIN_WELL.transient + TWIN_WELL.record) * period
            sol = solve_ivp(duffing_rhs, (start, end), [x0, 0.0], method="DOP853",
                            rtol=1e-11, atol=1e-13)
            assert np.max(np.abs(sweep.array("final_state")[index] - sol.y[:, -1])) < 1e-6


def test_identification_is_exact_on_made_up_grids():
    """Basin entropy of known label grids (Daza et al.'s definition)."""
    one = np.zeros((10, 10), dtype=int)
    assert basin_entropy(one, 5) == (0.0, 0.0, 4, 0)
    halves = np.zeros((10, 10), dtype=int)
    halves[:, 5:] = 1  # a straight boundary between boxes: no box holds it
    assert basin_entropy(halves, 5)[:2] == (0.0, 0.0)
    halves[:, 3:] = 1  # through two boxes of four, 2:3 each
    s = -(0.4 * math.log(0.4) + 0.6 * math.log(0.6))
    sb, sbb, boxes, boundary = basin_entropy(halves, 5)
    assert math.isclose(sb, s / 2) and math.isclose(sbb, s) and (boxes, boundary) == (4, 2)
    checker = np.indices((10, 10)).sum(axis=0) % 3  # three outcomes, evenly mixed
    assert basin_entropy(checker, 5)[1] > math.log(2)
    failed = np.full((5, 5), FAILED)
    assert basin_entropy(failed, 5)[0] == 0.0


def test_a_grid_smaller_than_a_box_has_no_entropy_and_says_so(tmp_path, capsys):
    """Three initial conditions on a line: no whole 5-cell box, so no basin entropy
    (NaN in the result), which the report and the figure say in words."""
    from chaospound.cli import main

    assert np.isnan(basin_entropy(np.zeros(3, dtype=int), 5)[:2]).all()
    assert basin_entropy(np.zeros(3, dtype=int), 5)[2:] == (0, 0)
    figure = tmp_path / "line.png"
    assert main(["basins", "--preset", "wall", "--set", "gap=5", "--set", "period_ratio=0.75",
                 "--grid", "X_A=0:1#3", "-o", str(tmp_path / "line.h5"), "--quiet",
                 "--plot", str(figure)]) == 0
    out = capsys.readouterr().out
    assert "basin entropy: none (no whole box of 5 cells a side fits the grid of 3 cells)" in out
    assert "nan" not in out and figure.stat().st_size > 0


def test_bad_axes_are_one_line_errors(tmp_path):
    with pytest.raises(ValueError, match=r"unknown initial-condition axis 'X_B'.*valid: "
                                         r"X_A, dX_A, initial_phase"):
        initial_axis("X_B=0:1#3", WALL)
    with pytest.raises(ValueError, match="did you mean 'dX_A'"):
        initial_axis("dXA=0:1#3", WALL)
    with pytest.raises(ValueError, match=r"in \[0, 1\)"):
        initial_axis("initial_phase=0:1#3", WALL)
    record = tmp_path / "quake.txt"  # time (s), acceleration (g)
    np.savetxt(record, np.column_stack([np.arange(100) * 0.01,
                                        0.1 * np.sin(np.arange(100) * 0.3)]))
    quake = WALL.with_params(ground="record", ground_file=str(record), length_unit=0.01,
                             tower_period=0.5)
    with pytest.raises(ValueError, match="needs a periodic forcing"):
        initial_axis("initial_phase=0:0.5#3", quake)
    with pytest.raises(ValueError, match="is a parameter"):
        basins(WALL, [parse_axis("gap=1:2#2", WALL)], tmp_path / "no.h5", progress=False)
    assert not (tmp_path / "no.h5").exists()
    scene = WALL.with_params(transient=4, record=4)
    run_sweep(scene, SweepSpec((parse_axis("gap=1:2#2", scene),)), tmp_path / "sweep.h5",
              progress=False)
    with pytest.raises(ValueError, match="not a scan of initial conditions"):
        identify(open_sweep(tmp_path / "sweep.h5"))


@pytest.mark.slow  # ~20 s: the cluster's start; the sweep's Dask path is tested by default
def test_dask_cluster_gives_the_local_file(tmp_path):
    """The scan's tasks on a Dask LocalCluster of two processes: the same file."""
    pytest.importorskip("distributed")
    from chaospound.distributed import connect, disconnect

    local, dask = tmp_path / "local.h5", tmp_path / "dask.h5"
    basins(TWIN_WELL, ("x=-2:2#6", "dx=-2:2#6"), local, progress=False)
    client, cluster = connect("local", 2)
    try:
        basins(TWIN_WELL, ("x=-2:2#6", "dx=-2:2#6"), dask, progress=False, client=client)
    finally:
        disconnect(client, cluster)
    assert_same_store(local, dask)


# ------------------------------------------------------------------ the command


def test_cli_scans_plots_and_resumes(tmp_path, capsys):
    from chaospound.cli import main

    path, figure = tmp_path / "wall.h5", tmp_path / "wall.png"
    argv = ["basins", "--preset", "wall", "--set", "gap=5", "--set", "period_ratio=0.75",
            "--set", "transient=100", "--grid", WALL_GRID[0], "--grid", WALL_GRID[1],
            "-o", str(path), "--quiet"]
    assert main([*argv, "--plot", str(figure)]) == 0
    out = capsys.readouterr().out
    assert "2 attractor(s) on 100 initial conditions (X_A x dX_A)" in out
    assert "periodic 1-1 (face)" in out and "none 0-1" in out and "basin entropy" in out
    assert figure.stat().st_size > 0
    library = basins(WALL, WALL_GRID, tmp_path / "library.h5", progress=False)[1]
    assert np.array_equal(open_basins(path).labels, library.labels)
    assert main([*argv, "--resume"]) == 0  # finished: identified again, nothing computed
    assert "finished already" in capsys.readouterr().out
    drawn = tmp_path / "drawn.png"
    assert main(["plot", str(path), "-o", str(drawn)]) == 0
    assert "basin map of X_A x dX_A" in capsys.readouterr().out
    assert drawn.stat().st_size > 0


def test_cli_says_what_an_unresolved_attractor_is_and_what_names_it(tmp_path, capsys):
    """fig4 at T/T_Ax 0.9 is chaotic: the window of a short transient finds no period, the
    report's attractor is 'unresolved', and a note points to --lyapunov (which names it)."""
    from chaospound.cli import main

    argv = ["basins", "--preset", "fig4", "--set", "period_ratio=0.9", "--set", "transient=20",
            "--grid", "X_A=-0.5:0.5#2", "--quiet"]
    assert main([*argv, "-o", str(tmp_path / "a.h5")]) == 0
    out, err = capsys.readouterr()
    assert "#0 unresolved" in out
    [note] = err.splitlines()
    assert note.startswith("chaospound: note: 'unresolved' here") and "--lyapunov" in note
    assert main([*argv, "-o", str(tmp_path / "b.h5"), "--lyapunov"]) == 0
    out, err = capsys.readouterr()
    assert "#0 chaotic" in out and err == ""


@pytest.mark.parametrize("grids, message", [
    (["X_B=0:1#3"], "unknown initial-condition axis 'X_B' (did you mean 'X_A'?); valid: "
                    "X_A, dX_A, initial_phase"),
    (["gap=0:1#3"], "'gap' is a parameter, not an initial condition (fix it with --set)"),
    (["initial_phase=0:1#3"], "the initial phase is a fraction of the period, in [0, 1)"),
    (["X_A=0:1#3", "X_A=0:2#3"], "--grid X_A given twice"),
    ([], "nothing to scan: give --grid NAME=GRID"),
])
def test_cli_bad_grid_is_one_line_exit_2(tmp_path, capsys, grids, message):
    from chaospound.cli import main

    argv = ["basins", "--preset", "wall", "-o", str(tmp_path / "b.h5")]
    for grid in grids:
        argv += ["--grid", grid]
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("chaospound: error: ")
    assert message in lines[0]
    assert captured.out == "" and list(tmp_path.iterdir()) == []
