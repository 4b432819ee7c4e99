"""Batch scans: determinism (workers, interruption, resume), continuation and
hysteresis, failed points, the ``sweep`` and ``plot`` commands, bounded memory.

The hysteresis scene (test_continuation_shows_the_hysteresis_loop): the
``wall`` preset (one symmetric tower, zeta = 0.03, Hertz contact beta = 1000,
chi = 1.5, against a ground-borne rigid wall) with the gap widened to
a = 5 A_g. Without contact the steady relative amplitude is
X/A_g = r^2 / sqrt((1 - r^2)^2 + (2 zeta r)^2), r = T_Ax/T, which reaches the
gap at T/T_Ax = 0.8986; above resonance (T/T_Ax < 1) the contact stiffens the
tower and bends the resonance peak to higher frequencies, so for
0.55 <= T/T_Ax <= 0.89 a non-impacting response (X < a) coexists with a
period-1 impacting one (one impact per cycle, V/(A_g omega_Ax) from 3.9 at
0.89 up to about 45 at 0.55). Increasing T/T_Ax (forward) stays on the
non-impacting branch until the linear amplitude reaches the gap, then jumps
up; decreasing T/T_Ax (backward) stays on the impacting branch down to about
0.54, then drops. Below 0.53 both branches are non-impacting, above 0.91
both impact with the same velocities.
"""

from __future__ import annotations

import contextlib
import gc
import io
import math
import os
import resource
import signal
import subprocess
import sys
import textwrap
import time
import tracemalloc
from pathlib import Path

import h5py
import numpy as np
import pytest
from storecheck import assert_same_store, bitwise, store_contents  # noqa: F401

from chaospound import cli
from chaospound.cli import main
from chaospound.plot import plot_bifurcation
from chaospound.scene import Scene, load_preset
from chaospound.store import REGIMES, SweepStoreError, open_sweep, sweep_progress
from chaospound.sweep import (
    CONTINUATIONS,
    SweepInterrupted,
    SweepSpec,
    axes_from_scene,
    parse_axis,
    restore_blas_threads,
    run_sweep,
    set_blas_threads,
)

ROOT = Path(__file__).resolve().parents[1]
SHORT = ["--set", "transient=20", "--set", "record=4"]  #: 20 + 4 cycles per point
WALL = load_preset("wall").with_params(transient=20, record=4)
FIG4 = load_preset("fig4").with_params(transient=20, record=4)


# ------------------------------------------------------------------ helpers











def spec_of(scene: Scene, *grids: str, **options) -> SweepSpec:
    return SweepSpec(tuple(parse_axis(g, scene) for g in grids), **options)


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code: int, out: str, err: str, *words: str) -> None:
    assert code == 2, err
    assert out == ""
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("chaospound: error: ")
    for word in words:
        assert word in lines[0], lines[0]


def subprocess_env() -> dict:
    return dict(os.environ,
                PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))


def mean_velocity(sweep, branch: str, i: int) -> float:
    v = sweep.impacts(i, branch)["velocity"]
    return float(np.mean(v)) if v.size else 0.0


# ------------------------------------------------------------- grid syntax


def test_grid_syntax():
    axis = parse_axis("period_ratio=0.3:2.0:0.005", WALL)
    assert len(axis) == 341 and axis.values[0] == 0.3 and math.isclose(axis.values[-1], 2.0)
    assert bitwise(parse_axis("period_ratio=0.3:2.0#1000", WALL).values,
                   np.linspace(0.3, 2.0, 1000))
    assert list(parse_axis("gap = 1, 2.5,4", WALL).values) == [1.0, 2.5, 4.0]
    # the presets' [sweep] tables: the paper's 1000 points of T/T_Ax over 0.3-2.0
    for name in ("fig4", "fig4-translational", "fig5"):
        [axis] = axes_from_scene(load_preset(name))
        assert axis.name == "period_ratio"
        assert bitwise(axis.values, np.linspace(0.3, 2.0, 1000))
    assert cli.SWEEP_CONTINUATIONS == CONTINUATIONS


def test_sweep_table_of_a_scene_file(tmp_path, capsys):
    """Without --param the scene's [sweep] table is the grid; the summary is printed."""
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(WALL.to_toml() + '\n[sweep]\nperiod_ratio = "0.5:1.0#4"\n')
    code, out, err = run(capsys, "sweep", scene_file, "-o", tmp_path / "table.h5", "--quiet")
    assert code == 0, err
    assert err == ""
    lines = out.splitlines()
    assert "4 points computed (4 in the grid)" in lines[0] and "points/s" in lines[0]
    assert lines[1].startswith("regimes: ") and lines[1].endswith("failed: 0")
    sweep = open_sweep(tmp_path / "table.h5")
    assert bitwise(sweep.grid["period_ratio"], np.linspace(0.5, 1.0, 4))
    assert set(sweep.status()) == {"done"}


# --------------------------------------------- 1 vs 2 workers: bitwise equal


def test_an_in_process_sweep_gives_back_the_blas_threads(tmp_path):
    """One worker runs in the caller's process with one BLAS thread (its small matrices
    are faster so), and the caller's thread count is restored afterwards."""
    before = set_blas_threads(2)
    try:
        expected = [threads for _, _, threads in set_blas_threads(2)]
        if not expected or expected == [1] * len(expected):
            pytest.skip("no OpenBLAS with more than one thread in this process")
        run_sweep(WALL, spec_of(WALL, "period_ratio=0.5:1.0#3"), tmp_path / "x.h5",
                  progress=False)
        assert [threads for _, _, threads in set_blas_threads(2)] == expected
    finally:
        restore_blas_threads(before)


@pytest.mark.parametrize("case", ["1-D fresh", "2-D both"])
def test_workers_give_identical_files(tmp_path, case):
    """One worker and two (tasks of one point, arriving out of order) write the same file."""
    if case == "1-D fresh":
        scene, spec = FIG4, spec_of(FIG4, "period_ratio=0.4:1.9#16")
    else:  # continuation chains along gap, one per period ratio, both directions
        scene = WALL
        spec = spec_of(WALL, "period_ratio=0.5:1.5#6", "gap=1,2,3", continuation="both")
    one, two = tmp_path / "one.h5", tmp_path / "two.h5"
    summary_one = run_sweep(scene, spec, one, workers=1, progress=False)
    summary_two = run_sweep(scene, spec, two, workers=2, chunk=1, progress=False)
    assert summary_two.workers == 2
    assert summary_one.regimes == summary_two.regimes
    assert_same_store(one, two)
    sweep = open_sweep(two)
    assert sweep.shape == spec.shape
    for branch in sweep.branches:
        assert set(sweep.status(branch)) == {"done"}
        assert sum(len(v) for v in sweep.impact_velocities(branch)) > 0


# ---------------------------------------------- continuation and hysteresis


def test_continuation_shows_the_hysteresis_loop(tmp_path):
    """wall preset, gap 5 A_g: forward and backward branches differ on 0.575-0.875 (no impact
    against one impact per cycle) and agree below 0.5 and above 0.9 (see the module
    docstring); forward jumps up where the linear amplitude reaches the gap."""
    scene = WALL.with_params(gap=5.0)
    grid = "period_ratio=0.45:1.0:0.025"
    both, fresh = tmp_path / "both.h5", tmp_path / "fresh.h5"
    # 20 + 4 cycles resolve a period to about 1 % (the impacting branch's slow transient)
    run_sweep(scene, spec_of(scene, grid, continuation="both", window_tol=0.03,
                            classify="paper"), both,
              progress=False)
    run_sweep(scene, spec_of(scene, grid, window_tol=0.03, classify="paper"), fresh, progress=False)
    sweep, alone = open_sweep(both), open_sweep(fresh)
    p = sweep.grid["period_ratio"]
    n = p.size
    assert n == 23
    forward = np.array([sweep.impacts(i, "forward")["velocity"].size for i in range(n)])
    backward = np.array([sweep.impacts(i, "backward")["velocity"].size for i in range(n)])

    # forward: impacts where the linear steady amplitude exceeds the gap (2 % either side;
    # at 0.9 it exceeds it by 1.3 %, and the transient decides within 24 cycles)
    r = 1.0 / p
    linear = r**2 / np.sqrt((1 - r**2) ** 2 + (2 * 0.03 * r) ** 2)
    assert np.all(forward[linear < 0.98 * 5.0] == 0)
    assert np.all(forward[linear > 1.02 * 5.0] > 0)
    assert np.count_nonzero(np.abs(linear / 5.0 - 1) <= 0.02) <= 1
    # the overlap: forward does not impact, backward impacts once per cycle
    overlap = (p > 0.56) & (p < 0.89)
    assert overlap.sum() == 13
    assert np.all(forward[overlap] == 0)
    assert np.all(backward[overlap] == scene.run.record)
    regimes = np.array(sweep.regimes("backward"))
    assert set(regimes[overlap]) == {"periodic"}
    assert np.all(sweep.array("impacts_per_period", "backward")[overlap] == 1)
    # on the impacting branch the impact velocity grows as the forcing gets faster
    v_backward = np.array([mean_velocity(sweep, "backward", i) for i in range(n)])
    assert np.all(np.diff(v_backward[overlap]) < 0)
    assert v_backward[overlap][0] > 5 * v_backward[overlap][-1]
    # outside the loop the branches agree
    below = p < 0.51
    assert np.all(forward[below] == 0) and np.all(backward[below] == 0)
    above = (p > 0.91) & (p < 0.99)  # 1.0 starts the backward chain from rest
    assert above.sum() == 3
    for i in np.flatnonzero(above):
        assert forward[i] == backward[i] == scene.run.record
        assert math.isclose(mean_velocity(sweep, "forward", i),
                            mean_velocity(sweep, "backward", i), rel_tol=0.02)
    # the backward branch drops between 0.5 and 0.575
    assert backward[p < 0.51].max() == 0 and backward[(p > 0.56) & (p < 0.58)].min() > 0

    # each chain's first point is the fresh run's point (the scene's initial state)
    for branch, i in (("forward", 0), ("backward", n - 1)):
        for name in ("time", "velocity", "phase", "peak_force"):
            assert bitwise(sweep.impacts(i, branch)[name], alone.impacts(i)[name])
        assert bitwise(sweep.strobe(i, branch), alone.strobe(i))
        assert bitwise(sweep.array("final_state", branch)[i], alone.array("final_state")[i])
    # runs from rest in the overlap end on one of the two coexisting responses, and both
    # are reached: the loop is bistability, not an artefact of continuation
    from_rest = set()
    for i in np.flatnonzero(overlap):
        count = alone.impacts(i)["velocity"].size
        assert count in (0, scene.run.record)
        if count:
            assert math.isclose(mean_velocity(alone, "fresh", i), v_backward[i], rel_tol=0.05)
        from_rest.add(count > 0)
    assert from_rest == {False, True}


# ---------------------------------------------------------- failed points


def test_failed_points_are_recorded_and_the_sweep_goes_on(tmp_path, capsys):
    """With a step budget between the points' needs, exactly the points that need more
    steps fail (status failed, a message, NaN state, no impacts); the others are bitwise
    the unlimited run's, and the summary counts the failures."""
    grid = "period_ratio=0.3:2.0#14"
    unlimited = tmp_path / "unlimited.h5"
    # the window procedure: one run per point, whose steps the budget bounds
    code, out, err = run(capsys, "sweep", "--preset", "wall", *SHORT, "--param", grid,
                         "--classify", "paper", "-o", unlimited, "--quiet")
    assert code == 0, err
    reference = open_sweep(unlimited)
    need = reference.array("steps") + reference.array("rejected")  # the budget counts both
    ordered = np.sort(need)
    gaps = [(abs(k - need.size / 2), k) for k in range(1, need.size)
            if ordered[k] - ordered[k - 1] >= 4]
    _, k = min(gaps)
    budget = int((ordered[k - 1] + ordered[k]) // 2)
    should_fail = need > budget
    assert 0 < should_fail.sum() < need.size

    limited = tmp_path / "limited.h5"
    code, out, err = run(capsys, "sweep", "--preset", "wall", *SHORT, "--set",
                         f"max_steps={budget}", "--param", grid, "--classify", "paper",
                         "-o", limited, "--quiet")
    assert code == 0, err
    assert err == ""
    assert f"failed: {int(should_fail.sum())}" in out
    assert "14 points computed" in out and "points/s" in out
    sweep = open_sweep(limited)
    status = np.array(sweep.status())
    assert np.array_equal(status == "failed", should_fail)
    assert np.all(status[~should_fail] == "done")
    messages = sweep.messages()
    for i in np.flatnonzero(should_fail):
        assert "max_steps" in messages[i] and str(budget) in messages[i]
        assert sweep.regimes()[i] == "failed"
        assert np.all(np.isnan(sweep.array("final_state")[i]))
        assert sweep.impacts(i)["velocity"].size == 0 and sweep.strobe(i).size == 0
    for i in np.flatnonzero(~should_fail):
        assert messages[i] == ""
        assert bitwise(sweep.impacts(i)["velocity"], reference.impacts(i)["velocity"])
        assert bitwise(sweep.strobe(i), reference.strobe(i))

    # a budget no point meets: the file is complete, the run a numerical failure (exit 1),
    # and the summary names no regime ("none" is the regime without impacts)
    hopeless = tmp_path / "hopeless.h5"
    code, out, err = run(capsys, "sweep", "--preset", "wall", *SHORT, "--set",
                         f"max_steps={int(ordered[0]) - 1}", "--param", grid, "--classify",
                         "paper", "-o", hopeless, "--quiet")
    assert code == 1 and "regimes: no point classified; failed: 14" in out
    assert err.count("\n") == 1 and "every point of" in err and "max_steps" in err
    assert open_sweep(hopeless).status() == ["failed"] * 14


# ------------------------------------------------------ interruption, resume


@pytest.fixture(scope="module")
def references(tmp_path_factory):
    """Uninterrupted CLI runs of the wall sweep with n points, made on demand."""
    folder = tmp_path_factory.mktemp("reference")
    made = {}

    def reference(n: int) -> Path:
        if n not in made:
            path = folder / f"wall-{n}.h5"
            with contextlib.redirect_stdout(io.StringIO()):
                assert main(["sweep", "--preset", "wall", *SHORT, "--param",
                             f"period_ratio=0.3:2.0#{n}", "-o", str(path), "--quiet"]) == 0
            made[n] = path
        return made[n]

    return reference


def interrupt_midway(path: Path, sig: int, *extra: str) -> tuple[int, int, str, int]:
    """Start the CLI sweep in a subprocess, send ``sig`` once a quarter to three
    quarters of the points are in the file (a window wider than one commit: the sweep
    commits 256 points at a time, or what a second brings); retry with four times the
    points if it finished first. SIGINT goes to the whole process group (workers
    included), as a terminal's Ctrl-C does.

    Returns (points, exit code, stderr, points done when the signal was sent). Points are
    committed about once a second, so the sweep must run for a few seconds (~1000 points).
    """
    n = 960
    for _ in range(4):
        if path.exists():
            path.unlink()
        command = [sys.executable, "-m", "chaospound", "sweep", "--preset", "wall", *SHORT,
                   "--param", f"period_ratio=0.3:2.0#{n}", "-o", str(path), "--quiet",
                   "--chunk", "2", *extra]
        proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, env=subprocess_env(), start_new_session=True)
        try:
            done, deadline = 0, time.monotonic() + 120
            while proc.poll() is None and time.monotonic() < deadline:
                try:  # the running sweep holds the file; its journal counts the committed
                    # points cheaply (open_sweep would read every point's data at each poll:
                    # seconds on a loaded machine once thousands are in, so polls skipped
                    # the window below and the sweep ran to the end)
                    done = sweep_progress(path)[0]
                except (SweepStoreError, OSError):
                    done = 0
                if n // 4 <= done < 3 * n // 4:
                    if sig == signal.SIGINT:
                        os.killpg(proc.pid, sig)
                    else:
                        proc.send_signal(sig)
                    break
                time.sleep(0.02)
            _, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        if proc.returncode not in (0, None) and 0 < done < n:
            return n, proc.returncode, err, done
        n *= 4  # finished (or never got going) before the signal: a longer sweep
    pytest.fail("could not interrupt the sweep midway")


def assert_done_points_complete(path: Path, reference: Path) -> int:
    """The file opens; every point marked done equals the uninterrupted run's point."""
    partial, full = open_sweep(path), open_sweep(reference)
    status = partial.status()
    done = [i for i, s in enumerate(status) if s == "done"]
    assert 0 < len(done) < len(status)
    for i in done:
        for name in ("time", "velocity", "phase", "corner", "peak_force", "duration"):
            assert np.array_equal(partial.impacts(i)[name], full.impacts(i)[name])
        assert bitwise(partial.strobe(i), full.strobe(i))
        for name in ("final_state", "regime", "steps", "strobe_mismatch"):
            assert bitwise(partial.array(name)[i], full.array(name)[i])
    return len(done)


def test_resume_after_sigkill_equals_an_uninterrupted_run(tmp_path, references):
    path = tmp_path / "killed.h5"
    n, code, _, _ = interrupt_midway(path, signal.SIGKILL)
    assert code == -signal.SIGKILL
    reference = references(n)
    assert_done_points_complete(path, reference)
    assert main(["sweep", "--preset", "wall", *SHORT, "--param", f"period_ratio=0.3:2.0#{n}",
                 "-o", str(path), "--quiet", "--resume"]) == 0
    assert_same_store(path, reference)


@pytest.mark.parametrize("continuation", ["none", "forward"])
def test_points_finished_out_of_order_are_committed_at_a_ctrl_c(tmp_path, monkeypatch,
                                                                continuation):
    """Workers finish tasks in any order. Every finished point is committed when a
    Ctrl-C stops the sweep, not only those that follow the grid's order without a gap
    (the points behind a gap used to be dropped: the message said 160 of 1000 while
    the progress bar had shown 192). Here the backend hands back the newest task first
    and Ctrl-C comes at the sixth: five tasks are done, grid order has none of them first."""
    from chaospound import sweep as sweep_module

    grid = ("gap=4,5", "period_ratio=0.5:1.0#6") if continuation != "none" else (
        "period_ratio=0.5:1.0#12",)
    spec = spec_of(WALL, *grid, continuation=continuation)
    straight = tmp_path / "straight.h5"
    run_sweep(WALL, spec, straight, progress=False, chunk=1)
    calls = []
    result = sweep_module._LocalBackend.result

    def newest_first(self, futures):
        return futures[-1:]

    def interrupted(self, fut):
        calls.append(1)
        if len(calls) == 6:
            raise KeyboardInterrupt
        return result(self, fut)

    path = tmp_path / "resumed.h5"
    with monkeypatch.context() as m:
        m.setattr(sweep_module._LocalBackend, "wait_some", newest_first)
        m.setattr(sweep_module._LocalBackend, "result", interrupted)
        with pytest.raises(SweepInterrupted) as stopped:
            run_sweep(WALL, spec, path, progress=False, chunk=1)
    assert stopped.value.done == 5
    assert sum(s == "done" for s in open_sweep(path).status()) == 5
    summary = run_sweep(WALL, spec, path, resume=True, progress=False, chunk=1)
    assert summary.computed == 12 - 5
    assert_same_store(path, straight)


@pytest.mark.parametrize("workers", ["1", "2"])
def test_ctrl_c_exits_130_and_the_file_resumes(tmp_path, references, capsys, workers):
    """Ctrl-C (SIGINT to the process group): exit 130 with one line, the finished points
    committed, and --resume completes the file."""
    path = tmp_path / "interrupted.h5"
    n, code, err, done = interrupt_midway(path, signal.SIGINT, "--workers", workers)
    assert code == 130
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("chaospound: error: interrupted after")
    assert "--resume" in lines[0]
    reference = references(n)
    committed = assert_done_points_complete(path, reference)
    assert committed >= done  # what was in the file stays; Ctrl-C commits finished points
    assert lines[0].startswith(f"chaospound: error: interrupted after {committed} of {n} ")
    # a plain rerun is refused, --resume finishes it (here with one worker)
    argv = ["sweep", "--preset", "wall", *SHORT, "--param", f"period_ratio=0.3:2.0#{n}",
            "-o", path, "--quiet"]
    assert_one_line_error(*run(capsys, *argv), "exists", "--resume")
    code, out, err = run(capsys, *argv, "--resume")
    assert code == 0, err
    assert f"({n} in the grid)" in out
    assert_same_store(path, reference)


# ------------------------------------------------------- bad definitions


@pytest.fixture(scope="module")
def existing_files(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("existing")
    text = folder / "text.h5"
    text.write_text("period_ratio,velocity\n0.5,1.0\n")
    other = folder / "other.h5"
    with h5py.File(other, "w") as f:
        f["velocity"] = np.arange(4.0)
        f.attrs["format"] = "something else"
    sweep = folder / "sweep.h5"
    run_sweep(WALL, spec_of(WALL, "period_ratio=0.5:1.0#3"), sweep, progress=False)
    return {"text": text, "other": other, "sweep": sweep}


BAD_SWEEPS = [
    (["--param", "perod_ratio=0.3:2.0:0.1"], ["perod_ratio", "period_ratio"]),
    (["--param", "period_ratio=2.0:1.0:0.1"], ["period_ratio=2.0:1.0:0.1", "empty range"]),
    (["--param", "period_ratio=0.3:1.0:0"], ["empty range"]),
    (["--param", "period_ratio=0.3:1.0#0"], ["empty range"]),
    (["--param", "period_ratio=0.3:abc"], ["0.3:abc", "not a grid"]),
    (["--param", "period_ratio=0.3;1.0;2"], ["not a grid"]),
    (["--param", "period_ratio"], ["NAME=GRID"]),
    (["--param", "gap=-1:1#3"], ["gap"]),
    (["--param", "gap=1,2", "--param", "gap=3,4"], ["gap", "twice"]),
    (["--param", "gap=1,2", "--param", "beta=1e3,1e4", "--param", "chi=1.5"], ["--param"]),
    ([], ["nothing to sweep", "--param"]),
    (["--param", "gap=1,2", "--continuation", "sideways"], ["sideways"]),
    (["--param", "gap=1,2", "--classify", "guess"], ["guess"]),
    (["--param", "gap=1,2", "--lyapunov", "0"], ["--lyapunov"]),
    (["--param", "gap=1,2", "--lyapunov", "3"], ["3", "exponents"]),
    (["--param", "gap=1,2", "--lyapunov-cycles", "5"], ["lyapunov_cycles"]),
    (["--param", "gap=1,2", "--workers", "0"], ["--workers"]),
    (["--param", "gap=1,2", "--chunk", "0"], ["--chunk"]),
    (["--param", "gap=1,2", "--window-tol", "2"], ["window_tol"]),
    (["--param", "gap=1,2", "--resume", "--overwrite"], ["--resume", "--overwrite"]),
]


@pytest.mark.parametrize(("argv", "words"), BAD_SWEEPS)
def test_bad_sweep_definitions_write_nothing(tmp_path, capsys, argv, words):
    output = tmp_path / "out.h5"
    code, out, err = run(capsys, "sweep", "--preset", "wall", *argv, "-o", output)
    assert_one_line_error(code, out, err, *words)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("which", "options", "words"), [
    ("sweep", [], ["exists", "--resume", "--overwrite"]),
    ("text", [], ["not a readable HDF5 file", "left as it is"]),
    ("text", ["--resume"], ["not a readable HDF5 file"]),
    ("other", ["--resume"], ["not a chaospound sweep store"]),
    ("sweep", ["--resume"], ["different sweep"]),
    # --overwrite replaces a store only, never a file of the user's own
    ("text", ["--overwrite"], ["not a readable HDF5 file", "left as it is"]),
    ("other", ["--overwrite"], ["not a chaospound sweep store", "left as it is"]),
])
def test_existing_files_are_refused_and_unchanged(capsys, existing_files, which, options,
                                                  words):
    path = existing_files[which]
    before = (path.read_bytes(), os.stat(path).st_mtime_ns)
    code, out, err = run(capsys, "sweep", "--preset", "wall", "--param",
                         "period_ratio=0.5:1.0#4", "-o", path, *options)
    assert_one_line_error(code, out, err, str(path), *words)
    assert (path.read_bytes(), os.stat(path).st_mtime_ns) == before


def test_bad_files_in_a_real_process(existing_files, tmp_path):
    """The console entry point: exit 2, one line, no traceback, files untouched."""
    text = existing_files["text"]
    before = (text.read_bytes(), os.stat(text).st_mtime_ns)
    for argv in (["sweep", "--preset", "wall", "--param", "period_ratio=0.5:1#3", "-o",
                  str(text), "--resume"],
                 ["plot", str(text)],
                 ["plot", str(existing_files["other"]), "-o", str(tmp_path / "x.png")],
                 ["sweep", "--preset", "wall", "--param", "period_ratio=0.5:1#3", "-o",
                  str(tmp_path / "missing" / "x.h5")]):
        proc = subprocess.run([sys.executable, "-m", "chaospound", *argv], capture_output=True,
                              text=True, env=subprocess_env(), timeout=120)
        assert_one_line_error(proc.returncode, proc.stdout, proc.stderr)
    assert (text.read_bytes(), os.stat(text).st_mtime_ns) == before
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------- plot


@pytest.fixture(scope="module")
def lyapunov_sweep(tmp_path_factory) -> Path:
    """fig4, 12 points, forward and backward, with the largest exponent."""
    path = tmp_path_factory.mktemp("plot") / "fig4.h5"
    assert main(["sweep", "--preset", "fig4", *SHORT, "--param", "period_ratio=0.5:1.6#12",
                 "--lyapunov", "--lyapunov-cycles", "10", "--continuation", "both", "-o",
                 str(path), "--quiet"]) == 0
    return path


def scatter_points(ax) -> int:
    return sum(len(c.get_offsets()) for c in ax.collections)


def test_plot_command_writes_the_bifurcation_diagram(lyapunov_sweep, capsys):
    png = lyapunov_sweep.with_suffix(".png")
    code, out, err = run(capsys, "plot", lyapunov_sweep)
    assert code == 0, err
    assert out.startswith(f"wrote {png}") and "bifurcation diagram" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # a figure is derived: redrawn a second time, no --overwrite needed (issue 18)
    png.write_bytes(b"stale")
    code, out, err = run(capsys, "plot", lyapunov_sweep)
    assert code == 0 and err == "" and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, out, err = run(capsys, "plot", lyapunov_sweep, "--branch", "backward", "-o",
                         png.with_name("backward.pdf"))
    assert code == 0 and png.with_name("backward.pdf").read_bytes()[:4] == b"%PDF"
    assert_one_line_error(*run(capsys, "plot", lyapunov_sweep, "--branch", "fresh"),
                          "fresh", "forward, backward")

    sweep = open_sweep(lyapunov_sweep)
    for branch in sweep.branches:
        velocities = sweep.impact_velocities(branch)
        total = int(sweep.array("impact_count", branch).sum())
        assert total == sum(v.size for v in velocities) > 0
        fig = plot_bifurcation(sweep.grid["period_ratio"], velocities,
                               regimes=sweep.regimes(branch),
                               exponents=sweep.array("max_exponent", branch))
        top, bottom = fig.axes
        assert scatter_points(top) == total
        assert scatter_points(bottom) == 12  # every point has its exponent
        assert np.all(np.isfinite(sweep.array("max_exponent", branch)))
    # the command's figure: forward and backward overlaid on one axis, exponents below
    fig = cli._sweep_figure(sweep, sweep.branches)
    assert len(fig.axes) == 2
    top = fig.axes[0]
    assert scatter_points(top) == sum(int(sweep.array("impact_count", branch).sum())
                                      for branch in sweep.branches)


def test_plot_command_draws_a_regime_map_for_two_parameters(tmp_path, capsys):
    path = tmp_path / "map.h5"
    spec = spec_of(WALL, "period_ratio=0.5:1.5#6", "gap=1,3,5")
    run_sweep(WALL, spec, path, progress=False)
    code, out, err = run(capsys, "plot", path)
    assert code == 0, err
    assert "regime map of period_ratio x gap" in out
    assert path.with_suffix(".png").stat().st_size > 0
    sweep = open_sweep(path)
    fig = cli._sweep_figure(sweep, sweep.branches)
    [ax] = fig.axes
    [mesh] = ax.collections
    codes = np.asarray(mesh.get_array()).reshape(3, 6)  # gap along y, period_ratio along x
    assert np.array_equal(codes, sweep.array("regime").reshape(6, 3).T)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    regimes = sweep.regimes()
    assert legend == [f"{r} ({regimes.count(r)})" for r in REGIMES if r in regimes]


# ----------------------------------------------------------------- memory


def sweep_peak(points: int, path: Path) -> int:
    """tracemalloc peak of a cheap wall sweep (the paper's window procedure, 1 + 2 cycles
    per point)."""
    scene = load_preset("wall").with_params(transient=1, record=2)
    spec = spec_of(scene, f"period_ratio=0.3:2.0#{points}", classify="paper")
    gc.collect()  # the kernels' first load leaves cyclic garbage: free it before measuring
    tracemalloc.start()
    try:
        run_sweep(scene, spec, path, overwrite=True, progress=False)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_memory_does_not_grow_with_the_number_of_points(tmp_path):
    """Results stream to disk: doubling the points adds index arrays and the grid's JSON
    (the journal's positions and statuses, the sweep definition: under 100 bytes a point),
    not the points' results (over 1 kB a point: 2 MB more here). The runs are past the
    first 1000 points, below which allocator pools still fill up."""
    sweep_peak(1000, tmp_path / "warm.h5")  # every code path has run, pools are warm
    small = sweep_peak(2000, tmp_path / "small.h5")
    large = sweep_peak(4000, tmp_path / "large.h5")
    assert large - small < 400_000, (small, large)
    assert large < 5_000_000
    assert open_sweep(tmp_path / "large.h5").array("impact_count").sum() > 1000


@pytest.mark.slow
def test_resident_memory_of_a_long_sweep(tmp_path):
    """20 000 points: the peak resident set grows by less than 20 MB over a 2 000-point run
    (results kept in memory would take over 40 MB)."""
    scene = load_preset("wall").with_params(transient=1, record=2)

    def peak_rss_after(points: int) -> int:
        run_sweep(scene, spec_of(scene, f"period_ratio=0.3:2.0#{points}"),
                  tmp_path / f"{points}.h5", progress=False)
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # kB on Linux

    short = peak_rss_after(2000)
    long = peak_rss_after(20000)
    assert long - short < 20_000, f"{short} kB -> {long} kB"


def test_sweep_workers_run_one_blas_thread():
    """A worker's idle OpenBLAS threads spin on the cores the other workers need: the
    worker initialiser gives every OpenBLAS loaded (numpy's and scipy's) one thread. Checked
    in a fresh interpreter through each library's own thread getter."""
    code = textwrap.dedent("""
        import ctypes, numpy, scipy.linalg
        from chaospound.sweep import single_thread_blas
        done = single_thread_blas()
        assert done, "no OpenBLAS found"
        for path in done:
            lib = ctypes.CDLL(path)
            getters = [getattr(lib, s.replace("set", "get"), None)
                       for s in ("openblas_set_num_threads", "openblas_set_num_threads64_",
                                 "scipy_openblas_set_num_threads",
                                 "scipy_openblas_set_num_threads64_")]
            counts = [g() for g in getters if g is not None]
            assert counts == [1], (path, counts)
        print(len(done))
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert int(proc.stdout) >= 1
