"""Sweeps, the CLI and the analyses on a user's own System (issue 14, item 6).

The system is Davis's (1992) tower against a ground-borne wall written as a
custom system (the functions of tests/test_custom.py, with named parameters
``c, gap, beta, chi, r`` and the period 2 pi r following ``r``). Swept over its
gap or its period ratio it must give what the built-in "wall" scene swept over
the same values gives: the same regimes and impact counts, impacts and
sections to the integration tolerance (the two are not bitwise equal: the
built-in engine carries the ground's phase from step to step by angle
addition, the user's function calls the library sine at every stage). The
sweep machinery itself adds nothing: every stored point is bitwise the direct
run of ``system.with_params(...)``, 1 and 2 workers give bitwise the same
file, and an interrupted sweep resumed gives bitwise the straight run's file.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from storecheck import assert_same_store
from test_custom import duffing_jac, duffing_rhs, wall_gap, wall_jac, wall_rhs

import chaospound.point
from chaospound import custom_system, load_preset
from chaospound.cli import main
from chaospound.dynamics.system import System
from chaospound.kernels.params import N_PARAMS
from chaospound.simulate import simulate
from chaospound.store import SweepStoreError, open_sweep
from chaospound.sweep import SweepInterrupted, SweepSpec, parse_axis, run_sweep

ROOT = Path(__file__).resolve().parents[1]
TOL = {"rtol": 1e-10, "atol": 1e-12}
#: the wall preset at tight tolerances, 40 + 8 cycles per point (the paper's window)
SCENE = load_preset("wall").with_params(**TOL)
#: the scene's names of the custom system's parameters
SCENE_NAME = {"gap": "gap", "r": "period_ratio"}


def wall_system(**solver) -> System:
    flat = SCENE.to_dict()
    params = {"c": 2 * flat["zeta_x_A"], "gap": flat["gap"], "beta": flat["beta"],
              "chi": flat["chi"], "r": flat["period_ratio"]}
    settings = {**TOL, **solver}
    return custom_system(wall_rhs, wall_jac, wall_gap, params=params,
                         period=lambda q: 2 * math.pi * q["r"], initial_state=(0.0, 0.0),
                         state_names=("X_A", "dX_A"), name="wall (user)", **settings)


USER = wall_system()


def spec_of(target, *grids: str, **options) -> SweepSpec:
    return SweepSpec(tuple(parse_axis(g, target) for g in grids), **options)


# ------------------------------------------------------------ named parameters


def test_named_parameters_and_with_params():
    assert USER.parameter_names == ("c", "gap", "beta", "chi", "r")
    assert USER.parameter_values["r"] == 0.7 and USER.period == SCENE.period
    moved = USER.with_params(r=0.9, gap=2.0)
    assert moved.parameter_values == {**USER.parameter_values, "r": 0.9, "gap": 2.0}
    assert moved.period == 2 * math.pi * 0.9  # the period follows r
    assert USER.parameter_values["r"] == 0.7  # a copy
    with pytest.raises(ValueError, match="its parameters are: c, gap, beta, chi, r"):
        USER.with_params(zeta=0.1)
    plain = custom_system(duffing_rhs, duffing_jac, params=(0.05, 0.0, 1.0, 7.5, 1.0),
                          period=2 * math.pi, initial_state=(1.0, 0.0))
    assert plain.parameter_names == ("q0", "q1", "q2", "q3", "q4")
    assert plain.with_params(q3=5.0).params[N_PARAMS + 3] == 5.0  # q[3] of the packed vector
    # a system of a scene: rebuilt from scene.with_params, its solver settings kept
    of_scene = System.from_scene(load_preset("wall")).with_solver(rtol=1e-11, atol=1e-13)
    wider = of_scene.with_params(gap=2.0)
    assert wider.parameter_values["gap"] == 2.0 and (wider.rtol, wider.atol) == (1e-11, 1e-13)


# ---------------------------------------------------- the user's wall = the wall


def _compare_with_scene(user_file, scene_file, branches):
    mine, theirs = open_sweep(user_file), open_sweep(scene_file)
    assert mine.meta["model"] == "custom" and theirs.meta["model"] == "wall"
    for branch in branches:
        for name in ("status", "regime", "period_cycles", "impacts_per_period",
                     "impact_count", "strobe_count"):
            np.testing.assert_array_equal(mine.array(name, branch), theirs.array(name, branch),
                                          err_msg=f"{branch} {name}")
        for i in range(int(np.prod(mine.shape))):
            a, b = mine.impacts(i, branch), theirs.impacts(i, branch)
            np.testing.assert_allclose(a["time"], b["time"], rtol=0, atol=1e-7)
            np.testing.assert_allclose(a["velocity"], b["velocity"], rtol=1e-6)
            np.testing.assert_allclose(mine.strobe(i, branch), theirs.strobe(i, branch),
                                       rtol=0, atol=1e-7)
    return mine, theirs


@pytest.mark.parametrize("name, grid", [("r", "0.6,0.7,0.8,1.1"), ("gap", "0.5,1.0,2.0")])
def test_user_wall_sweep_is_the_wall_scene_sweep(tmp_path, name, grid):
    # the paper's window procedure: each point's record is the point's own simulate run
    spec = spec_of(USER, f"{name}={grid}", classify="paper")
    run_sweep(USER, spec, tmp_path / "user.h5", progress=False)
    scene_spec = spec_of(SCENE, f"{SCENE_NAME[name]}={grid}", classify="paper")
    run_sweep(SCENE, scene_spec, tmp_path / "scene.h5", progress=False)
    mine, theirs = _compare_with_scene(tmp_path / "user.h5", tmp_path / "scene.h5", ["fresh"])
    regimes = mine.regimes()
    assert "periodic" in regimes and all(n > 0 for n in mine.array("impact_count"))
    # the sweep adds nothing: each point is bitwise the direct run of with_params
    for i, value in enumerate(spec.axes[0].values):
        run = simulate(USER.with_params(**{name: float(value)}))
        assert np.array_equal(mine.strobe(i), run.strobe.state)
        assert np.array_equal(mine.impacts(i)["velocity"], run.impacts.velocity)
    xr = mine.to_xarray()
    assert list(xr[name].values) == list(spec.axes[0].values)
    assert json.loads(xr.attrs["parameter_names"]) == list(USER.parameter_names)


def test_two_axes_with_continuation_both_ways_match_the_scene(tmp_path):
    """c x r with the two continuation branches, a = 5 A_g: the wall's hysteresis
    (tests/test_sweep.py), non-impacting forward and impacting backward at T/T_Ax = 0.7,
    from a non-impacting start at 0.5 and an impacting one at 0.95."""
    user = USER.with_params(gap=5.0)
    scene = SCENE.with_params(gap=5.0)
    spec = spec_of(user, "c=0.06,0.08", "r=0.5,0.7,0.95", continuation="both")
    run_sweep(user, spec, tmp_path / "user.h5", progress=False)
    scene_spec = spec_of(scene, "zeta_x_A=0.03,0.04", "period_ratio=0.5,0.7,0.95",
                         continuation="both")
    run_sweep(scene, scene_spec, tmp_path / "scene.h5", progress=False)
    mine, _ = _compare_with_scene(tmp_path / "user.h5", tmp_path / "scene.h5",
                                  ["forward", "backward"])
    assert mine.shape == (2, 3)
    forward = mine.array("impact_count", "forward").reshape(2, 3)
    backward = mine.array("impact_count", "backward").reshape(2, 3)
    assert forward[0, 1] == 0 < backward[0, 1]  # coexisting responses at r = 0.7
    assert forward[0, 0] == backward[0, 0] == 0 < forward[0, 2] == backward[0, 2]


def test_a_system_of_a_scene_sweeps_as_its_scene(tmp_path):
    """System.from_scene(...).with_solver(...) is stored as the scene with those settings."""
    short = load_preset("wall").with_params(transient=10, record=2)
    system = System.from_scene(short).with_solver(**TOL)
    run_sweep(system, spec_of(system, "gap=1,2"), tmp_path / "system.h5", progress=False)
    scene = short.with_params(**TOL)
    run_sweep(scene, spec_of(scene, "gap=1,2"), tmp_path / "scene.h5", progress=False)
    assert_same_store(tmp_path / "system.h5", tmp_path / "scene.h5")


# ------------------------------------------------------------- determinism


def test_one_and_two_workers_give_the_same_file(tmp_path):
    spec = spec_of(USER, "r=0.6:1.2#6", continuation="forward", lyapunov=-1,
                   lyapunov_cycles=20)
    run_sweep(USER, spec, tmp_path / "one.h5", workers=1, progress=False)
    summary = run_sweep(USER, spec, tmp_path / "two.h5", workers=2, chunk=2, progress=False)
    assert summary.workers == 2 and summary.failed == 0
    assert_same_store(tmp_path / "one.h5", tmp_path / "two.h5")
    exponents = open_sweep(tmp_path / "one.h5").array("exponents")
    assert exponents.shape == (6, 2) and np.all(exponents[:, 0] < 0.0)  # periodic: contracting


def test_an_interrupted_sweep_resumed_is_the_straight_run(tmp_path, monkeypatch):
    spec = spec_of(USER, "gap=0.5,1.0,2.0", "r=0.6:1.0#4", continuation="forward")
    straight = tmp_path / "straight.h5"
    run_sweep(USER, spec, straight, progress=False, chunk=1)
    run = chaospound.point.run_system_point
    calls = []

    def interrupted(*args, **kwargs):
        calls.append(1)
        if len(calls) == 7:
            raise KeyboardInterrupt
        return run(*args, **kwargs)

    path = tmp_path / "resumed.h5"
    monkeypatch.setattr(chaospound.point, "run_system_point", interrupted)
    with pytest.raises(SweepInterrupted):
        run_sweep(USER, spec, path, progress=False, chunk=1)
    monkeypatch.setattr(chaospound.point, "run_system_point", run)
    assert 0 < sum(s == "done" for s in open_sweep(path).status()) < 12
    summary = run_sweep(USER, spec, path, resume=True, progress=False, chunk=1)
    assert 0 < summary.computed < 12
    assert_same_store(path, straight)
    # another system (here: another base damping) is refused, in one line
    with pytest.raises(SweepStoreError, match=r"different system \(parameter_values") as err:
        run_sweep(USER.with_params(c=0.07), spec, path, resume=True, progress=False)
    assert "\n" not in str(err.value)
    with pytest.raises(SweepStoreError, match="sweep of a system, not of a scene"):
        run_sweep(SCENE, spec_of(SCENE, "period_ratio=0.6,0.7"), path, resume=True,
                  progress=False)


def test_a_system_without_gap_is_stored_unclassified(tmp_path):
    ueda = custom_system(duffing_rhs, duffing_jac, params={"d": 0.05, "a": 0.0, "b": 1.0,
                                                           "g": 7.5, "w": 1.0},
                         period=lambda q: 2 * math.pi / q["w"], initial_state=(1.0, 0.0),
                         transient=10, record=4, **TOL)
    summary = run_sweep(ueda, spec_of(ueda, "g=7.0,7.5"), tmp_path / "ueda.h5",
                        progress=False)
    assert summary.regimes == {"unresolved": 2} and summary.failed == 0
    assert summary.format().count("no gap function") == 1
    sweep = open_sweep(tmp_path / "ueda.h5")
    assert sweep.meta["classified"].startswith("no")
    assert sweep.strobe(1).shape == (5, 2)
    np.testing.assert_array_equal(sweep.strobe(1), simulate(ueda.with_params(g=7.5)).strobe.state)


# ---------------------------------------------------------------- the CLI

SYSTEM_FILE = '''\
"""A wall oscillator: Hertz contact against a sinusoidally moving stop."""
import math

from numba import njit

from chaospound import custom_system


@njit
def rhs(t, y, q, out):
    c, gap, beta, r = q[0], q[1], q[2], q[3]
    ug, vg = math.sin(t / r), math.cos(t / r) / r
    d = y[0] - ug - gap
    out[0] = y[1]
    out[1] = -c * (y[1] - vg) - (y[0] - ug) - (beta * d**1.5 if d > 0.0 else 0.0)


@njit
def jacobian(t, y, q, jac):
    d = y[0] - math.sin(t / q[3]) - q[1]
    jac[0, 0], jac[0, 1] = 0.0, 1.0
    jac[1, 0] = -1.0 - (1.5 * q[2] * math.sqrt(d) if d > 0.0 else 0.0)
    jac[1, 1] = -q[0]


@njit
def gap(t, y, q):
    r = q[3]
    return q[1] - (y[0] - math.sin(t / r)), -(y[1] - math.cos(t / r) / r)


def make():
    return custom_system(rhs, jacobian, gap, params={"c": 0.06, "gap": 1.0, "beta": 1000.0,
                                                     "r": 0.7},
                         period=lambda q: 2 * math.pi * q["r"], initial_state=(0.0, 0.0),
                         state_names=("x", "dx"), name="stop", rtol=1e-9, atol=1e-11)


system = make()
not_a_system = 42
'''


def _cli(capsys, *argv) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_runs_a_system_file_end_to_end(tmp_path, capsys):
    file = tmp_path / "my_oscillator.py"
    file.write_text(SYSTEM_FILE)
    out = tmp_path / "x.h5"
    code, text, err = _cli(capsys, "sweep", f"{file}:system", "--param", "gap=0.5,1.0,2.0",
                           "--set", "transient=30", "--set", "record=4", "-o", out, "--quiet",
                           "--workers", "2",  # the workers import the file's module by name
                           "--classify", "paper")
    assert code == 0, err
    assert "3 points computed" in text and "2 worker(s)" in text
    sweep = open_sweep(out)
    assert sweep.meta["source"] == "my_oscillator.py:system"
    assert sweep.meta["source_sha256"] == __import__("hashlib").sha256(
        file.read_bytes()).hexdigest()
    assert sweep.to_xarray().sizes["gap"] == 3
    # the same points from the API: the file's system is the system of the sweep
    code, text, err = _cli(capsys, "simulate", f"{file}:make", "--set", "gap=2",
                           "--transient", "30", "--record", "4", "--json")
    assert code == 0, err
    document = json.loads(text)
    assert document["system"]["parameter_values"]["gap"] == 2.0
    np.testing.assert_array_equal(np.array(document["strobe"]), sweep.strobe(2))
    code, text, err = _cli(capsys, "classify", f"{file}:system", "--json", "--quiet")
    assert code == 0, err
    assert json.loads(text)["label"] == "periodic 1-1"
    code, text, err = _cli(capsys, "lyapunov", f"{file}:system", "--cycles", "20", "--quiet")
    assert code == 0, err
    assert "custom (2 states: x dx)" in text
    figure = tmp_path / "phase.png"
    code, text, err = _cli(capsys, "simulate", f"{file}:system", "--record", "2", "--plot",
                           figure, "--quiet")
    assert code == 0 and figure.stat().st_size > 0 and "(phase diagrams)" in text, err
    # a changed file is another system: resume refuses it in one line
    file.write_text(SYSTEM_FILE.replace('"c": 0.06', '"c": 0.07'))
    code, _, err = _cli(capsys, "sweep", f"{file}:system", "--param", "gap=0.5,1.0,2.0",
                        "--set", "transient=30", "--set", "record=4", "-o", out, "--resume",
                        "--classify", "paper")
    assert code == 2 and "different system (source_sha256" in err and err.count("\n") == 1


@pytest.mark.parametrize("spec, words", [
    ("missing.py:system", "not found"),
    ("FILE:nothing", "has no attribute 'nothing' (it defines the systems: system)"),
    ("FILE:not_a_system", "is a int, not a System"),
    ("FILE", "give FILE.py:ATTR"),
    ("BROKEN:system", "importing it failed: ZeroDivisionError"),
])
def test_cli_bad_system_specs_are_one_line_and_exit_2(tmp_path, capsys, spec, words):
    file = tmp_path / "osc.py"
    file.write_text(SYSTEM_FILE)
    broken = tmp_path / "broken.py"
    broken.write_text("x = 1 / 0\n")
    spec = spec.replace("FILE", str(file)).replace("BROKEN", str(broken))
    for command in ("simulate", "classify", "lyapunov", "sweep"):
        extra = ["--param", "gap=1,2", "-o", tmp_path / "y.h5"] if command == "sweep" else []
        code, out, err = _cli(capsys, command, spec, *extra)
        assert code == 2 and words in err and err.count("\n") == 1, (command, err)
        assert not (tmp_path / "y.h5").exists()
    code, _, err = _cli(capsys, "sweep", f"{file}:system", "--param", "zeta=1,2", "-o",
                        tmp_path / "y.h5")
    assert code == 2 and "system 'stop' has: c, gap, beta, r" in err


@pytest.mark.parametrize("rtol", ["1", "2", "1e3"])
def test_an_rtol_of_one_or_more_is_refused_for_scenes_and_systems(tmp_path, capsys, rtol):
    """rtol >= 1 asks for no accuracy at all: refused in one line (it used to run into a
    non-finite state, exit 1)."""
    file = tmp_path / "osc.py"
    file.write_text(SYSTEM_FILE)
    for target in ([f"{file}:system"], ["--preset", "wall"]):
        for option in (["--rtol", rtol], ["--set", f"rtol={rtol}"]):
            code, out, err = _cli(capsys, "simulate", *target, *option)
            assert code == 2 and out == "" and err.count("\n") == 1, err
            assert "rtol" in err and "(0, 1)" in err


def test_a_second_process_loads_the_system_from_the_disk_cache(tmp_path):
    """The first process compiles the user's engine (into a fresh cache); the second finds
    the same content-hashed module, hence numba's cached machine code."""
    file = tmp_path / "osc.py"
    file.write_text(SYSTEM_FILE)
    env = {**os.environ, "CHAOSPOUND_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": str(ROOT)}
    probe = textwrap.dedent(f"""
        import time
        from chaospound.userfile import load_system
        from chaospound.simulate import simulate
        system = load_system({str(file)!r} + ":system")
        cached = system.engine().is_cached()
        run = simulate(system, transient=10, record=2)
        print(cached, len(run.impacts))
    """)
    times, outputs = [], []
    for _ in range(2):
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True,
                              text=True, timeout=300, cwd=tmp_path)
        times.append(time.perf_counter() - start)
        assert done.returncode == 0, done.stderr
        outputs.append(done.stdout.split())
    assert outputs[0][0] == "False" and outputs[1][0] == "True", outputs
    assert outputs[0][1] == outputs[1][1] != "0"
    assert times[1] < times[0] / 2, times
    assert list((tmp_path / "cache" / "user").glob("chaospound_user_*.py"))
