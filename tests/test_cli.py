"""The command line: exit codes, one-line errors, and output that matches the library."""

from __future__ import annotations

import importlib
import io
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from chaospound import cli
from chaospound.cli import main
from chaospound.kernels.params import P_CHI
from chaospound.scene import PARAMETERS, Scene, list_presets, load_preset

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("fig3a", "fig3b", "fig4", "fig4-translational", "fig5", "tower-wall", "wall")
CORNERS = {"A+", "A-", "B+", "B-", "face"}
SHORT = ["--transient", "5", "--record", "2"]  # where the physics does not matter


def run(capsys, *argv: str) -> tuple[int, str, str]:
    """main() in-process: (exit code, stdout, stderr)."""
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys, *argv: str) -> dict:
    code, out, err = run(capsys, "simulate", *argv, "--json")
    assert code == 0, err
    assert err == ""
    return json.loads(out)


def run_subprocess(*argv: str, code: str | None = None) -> subprocess.CompletedProcess:
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    )
    command = [sys.executable, "-c", code] if code else [sys.executable, "-m", "chaospound", *argv]
    return subprocess.run(command, capture_output=True, text=True, env=env, timeout=120)


def assert_one_line_error(code: int, out: str, err: str, *names: str, exit_code: int = 2) -> None:
    assert code == exit_code
    assert out == ""
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("chaospound: error: ")
    for name in names:
        assert name in lines[0]


# ============================================================ bad input
@pytest.fixture
def bad_toml(tmp_path: Path) -> Path:
    path = tmp_path / "broken.toml"
    path.write_text('name = "broken"\n[contact\nbeta = 1000.0\n', encoding="utf-8")
    return path


@pytest.fixture
def scene_file(tmp_path: Path) -> Path:
    path = tmp_path / "mine.toml"
    path.write_text(load_preset("fig3a").to_toml(), encoding="utf-8")
    return path


BAD_SCENE_OPTIONS = [
    (["--preset", "fig3a", "--set", "beta=-1"], ["beta", "-1"]),
    (["--preset", "fig3a", "--set", "betta=1"], ["betta"]),
    (["--preset", "fig3a", "--set", "beta"], ["beta"]),
    (["--preset", "fig3a", "--set", "=3"], ["=3"]),
    (["--preset", "nope"], ["nope"]),
    ([], ["--preset"]),
    (["--preset", "fig3a", "--rtol", "-1e-3"], ["rtol"]),
    (["--preset", "fig3a", "--rtol", "tight"], ["rtol", "tight"]),
    (["--preset", "fig3a", "--transient", "-2"], ["transient"]),
    (["--preset", "fig3a", "--record", "0"], ["record"]),
    (["--preset", "fig3a", "--record", "2.5"], ["record"]),
    (["--preset", "fig3a", "--method", "euler"], ["method", "euler"]),
    (["--preset", "fig3a", "--phase", "1.0"], ["phase"]),
    (["--preset", "fig3a", "--set", "model=pair"], ["model", "pair"]),
    (["--preset", "fig3a", "--trajectory", "-3"], ["--trajectory"]),
    (["--preset", "fig3a", "--bogus"], ["--bogus"]),
]


@pytest.mark.parametrize(("options", "names"), BAD_SCENE_OPTIONS)
def test_bad_scene_options_are_one_line_exit_2(capsys, options, names):
    assert_one_line_error(*run(capsys, "simulate", *options, "--json"), *names)


def test_an_unknown_sweep_parameter_says_where_the_names_are(capsys, tmp_path):
    code, out, err = run(capsys, "sweep", "--preset", "wall", "--param", "nope=0:1#3",
                         "-o", str(tmp_path / "x.h5"))
    assert_one_line_error(code, out, err, "nope", "chaospound params")
    assert not (tmp_path / "x.h5").exists()
    code, out, err = run(capsys, "sweep", "--preset", "wall", "--param", "gapp=1:2#3",
                         "-o", str(tmp_path / "x.h5"))
    assert_one_line_error(code, out, err, "gapp", "did you mean 'gap'")


def test_malformed_toml_names_the_file(capsys, bad_toml):
    assert_one_line_error(*run(capsys, "simulate", str(bad_toml)), bad_toml.name, "TOML")


def test_bad_value_in_file_names_file_and_parameter(capsys, tmp_path):
    path = tmp_path / "negative.toml"
    path.write_text("[contact]\nbeta = -5.0\n", encoding="utf-8")
    assert_one_line_error(*run(capsys, "simulate", str(path)), path.name, "beta")


def test_missing_file_names_the_file(capsys, tmp_path):
    missing = tmp_path / "absent.toml"
    assert_one_line_error(*run(capsys, "simulate", str(missing)), "absent.toml")


def test_both_preset_and_file(capsys, scene_file):
    code, out, err = run(capsys, "simulate", "--preset", "fig3a", str(scene_file))
    assert_one_line_error(code, out, err, "--preset", scene_file.name)


@pytest.mark.parametrize(
    ("argv", "names"),
    [
        (["presets", "nope"], ["nope"]),
        (["params", "bogus"], ["bogus"]),
        (["frobnicate"], ["frobnicate"]),
        ([], ["COMMAND"]),
    ],
)
def test_other_usage_errors(capsys, argv, names):
    assert_one_line_error(*run(capsys, *argv), *names)


@pytest.mark.parametrize(
    ("argv", "names"),
    [
        (["simulate", "--preset", "fig3a", "--set", "beta=-1", "--json"], ["beta"]),
        (["simulate", "--preset", "fig3a", "--set", "beta"], ["beta"]),
        (["simulate", "--preset", "nope"], ["nope"]),
        (["simulate", "--unknown-option"], ["--unknown-option"]),
    ],
)
def test_subprocess_errors_have_no_traceback(argv, names):
    done = run_subprocess(*argv)
    assert_one_line_error(done.returncode, done.stdout, done.stderr, *names)


def test_subprocess_malformed_toml(bad_toml):
    done = run_subprocess("simulate", str(bad_toml), "--json")
    assert_one_line_error(done.returncode, done.stdout, done.stderr, bad_toml.name)


def test_help_and_validation_do_not_import_the_kernels():
    probe = (
        "import sys, contextlib, io\n"
        "from chaospound.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['--help']) == 0\n"
        "    assert main(['simulate', '--help']) == 0\n"
        "with contextlib.redirect_stderr(io.StringIO()):\n"
        "    assert main(['simulate', '--preset', 'fig3a', '--set', 'beta=-1']) == 2\n"
        "print(sorted(m for m in sys.modules if m.startswith(('numba', 'chaospound.simulate'))))\n"
    )
    done = run_subprocess(code=probe)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_simulate_is_the_function_whoever_imported_its_module_first():
    """The package's export and the submodule share the name ``simulate``; a fresh
    interpreter that imports the module first still gets the function."""
    probe = (
        "import chaospound.simulate\n"
        "from chaospound.simulate import Simulation\n"
        "import chaospound\n"
        "from chaospound import simulate\n"
        "print(callable(simulate), callable(chaospound.simulate), Simulation.__name__)\n"
    )
    done = run_subprocess(code=probe)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "True True Simulation"


def test_help_returns_zero_instead_of_exiting(capsys):
    code, out, err = run(capsys, "simulate", "--help")
    assert code == 0
    assert "--preset" in out and "--set" in out and "--trajectory" in out
    assert err == ""


# =================================================== runtime failures
def test_numerical_failure_is_one_line_exit_1(capsys):
    code, out, err = run(capsys, "simulate", "--preset", "fig3a", "--set", "max_steps=10", *SHORT)
    assert_one_line_error(code, out, err, "max_steps", exit_code=1)


def test_interrupt_is_one_line_exit_130(capsys, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(importlib.import_module("chaospound.simulate"), "simulate", interrupted)
    code, out, err = run(capsys, "simulate", "--preset", "fig3a", *SHORT)
    assert_one_line_error(code, out, err, "interrupted", exit_code=130)


# ================================================================ JSON
def test_fig3a_json(capsys):
    doc = run_json(capsys, "--preset", "fig3a")
    assert doc["model"] == "towers"
    assert set(PARAMETERS) <= set(doc["scene"])
    assert doc["scene"]["transient"] == 40 and doc["scene"]["record"] == 8
    assert doc["scene"]["ecc_y_A"] == pytest.approx(10.0)  # ecc_y_ratio 0.1 of length 100, resolved
    strobe = np.array(doc["strobe"])
    assert strobe.shape == (9, 12)
    assert np.all(np.isfinite(strobe))
    assert doc["impacts"], "fig3a pounds"
    for impact in doc["impacts"]:
        assert {"time", "phase", "velocity", "corner"} <= set(impact)
        assert impact["corner"] in CORNERS
        assert 0.0 <= impact["phase"] < 1.0
        assert impact["velocity"] > 0.0
    times = [impact["time"] for impact in doc["impacts"]]
    assert times == sorted(times)
    period = doc["scene"]["period"]
    assert 40 * period <= times[0] and times[-1] < 48 * period  # onsets in the record window
    assert {"steps", "rejected", "rhs_evals", "wall_s"} <= set(doc["stats"])
    assert doc["stats"]["steps"] > 0 and doc["stats"]["rhs_evals"] > doc["stats"]["steps"]


def test_translational_preset_runs_the_pair_model(capsys):
    doc = run_json(capsys, "--preset", "fig4-translational", *SHORT)
    assert doc["model"] == "pair"
    strobe = np.array(doc["strobe"])
    assert strobe.shape == (3, 4)
    assert {impact["corner"] for impact in doc["impacts"]} <= {"face"}


def test_options_reach_the_scene_and_match_the_library(capsys):
    from chaospound.simulate import simulate

    doc = run_json(
        capsys, "--preset", "fig3a", "--set", "gap=0.5", "--set", "zeta=0.05", *SHORT,
        "--method", "dop853", "--rtol", "1e-8", "--atol", "1e-11", "--phase", "0.25",
    )  # fmt: skip
    scene = doc["scene"]
    assert (scene["gap"], scene["zeta_t_B"], scene["method"]) == (0.5, 0.05, "dop853")
    assert (scene["rtol"], scene["atol"], scene["phase"]) == (1e-8, 1e-11, 0.25)
    assert (scene["transient"], scene["record"]) == (5, 2)
    expected = load_preset("fig3a").with_params(
        gap=0.5, zeta=0.05, transient=5, record=2, method="dop853", rtol=1e-8, atol=1e-11,
        phase=0.25,
    )  # fmt: skip
    sim = simulate(expected)
    assert [i["time"] for i in doc["impacts"]] == sim.impacts.time.tolist()  # bitwise
    assert [i["velocity"] for i in doc["impacts"]] == sim.impacts.velocity.tolist()
    assert [i["corner"] for i in doc["impacts"]] == sim.impacts.labels
    assert doc["strobe"] == sim.strobe.state.tolist()


def test_run_options_win_over_set_and_paper_method_sets_its_tolerance(capsys):
    doc = run_json(capsys, "--preset", "wall", "--set", "record=7", "--record", "2")
    assert doc["scene"]["record"] == 2 and len(doc["strobe"]) == 3
    paper = run_json(capsys, "--preset", "wall", "--method", "paper", *SHORT)["scene"]
    assert (paper["method"], paper["rtol"]) == ("cash-karp", 1e-3)
    tight = run_json(capsys, "--preset", "wall", "--method", "paper", "--rtol", "1e-7", *SHORT)
    assert (tight["scene"]["method"], tight["scene"]["rtol"]) == ("cash-karp", 1e-7)


def test_trajectory_samples_the_record_window(capsys):
    doc = run_json(capsys, "--preset", "fig3a", *SHORT, "--trajectory", "8")
    time = np.array(doc["trajectory"]["time"])
    state = np.array(doc["trajectory"]["state"])
    period = doc["scene"]["period"]
    assert time.shape == (8 * 2 + 1,) and state.shape == (17, 12)
    np.testing.assert_allclose(time, period * (5 + np.arange(17) / 8), rtol=1e-12)
    # samples at whole cycles are the stroboscopic section
    np.testing.assert_allclose(state[::8], np.array(doc["strobe"]), rtol=1e-9, atol=1e-9)


# ======================================================== readable text
def test_readable_output_table_matches_json(capsys):
    doc = run_json(capsys, "--preset", "fig3a", *SHORT)
    code, out, err = run(capsys, "simulate", "--preset", "fig3a", *SHORT)
    assert code == 0 and err == ""
    assert "towers (12 states" in out
    assert "5 transient + 2 recorded" in out
    assert "dopri5" in out and "rtol 1e-05" in out
    lines = out.splitlines()
    start = next(i for i, line in enumerate(lines) if line.split()[:2] == ["#", "cycle"])
    # a units row under the header: velocity, peak penetration, force and duration
    assert lines[start + 1].split() == ["of", "T", "A_g", "omega_Ax", "A_g", "A_g", "k_Ax",
                                        "1/omega_Ax"]
    start += 1
    rows = [line.split() for line in lines[start + 1 :] if line.strip()][: len(doc["impacts"])]
    assert len(rows) == len(doc["impacts"])
    for k, (row, impact) in enumerate(zip(rows, doc["impacts"], strict=True)):
        assert int(row[0]) == k + 1
        assert row[4] == impact["corner"]
        assert float(row[3]) == pytest.approx(impact["velocity"], rel=1e-5)
    assert lines[start + 1 + len(rows)] == ""  # table ends, summary follows
    per_cycle = len(doc["impacts"]) / 2
    assert f"impacts per cycle  {per_cycle:.4g} ({len(doc['impacts'])} in 2 cycles)" in out
    assert "us per accepted step" in out
    last = [i["corner"] for i in doc["impacts"] if i["cycle"] == 6]
    assert any(line.split()[3:] == last for line in lines if line.startswith("corners, cycle 6"))


# ============================================================ presets
def test_presets_lists_every_preset_with_its_description(capsys):
    code, out, err = run(capsys, "presets")
    assert code == 0 and err == ""
    listed = [line.split()[0] for line in out.splitlines()[1:]]
    assert listed == sorted(PRESETS) == list_presets()
    assert load_preset("fig3a").description in out


@pytest.mark.parametrize("name", PRESETS)
def test_preset_toml_loads_back_to_the_same_scene(capsys, name):
    code, out, err = run(capsys, "presets", name)
    assert code == 0 and err == ""
    assert Scene.from_toml(out) == load_preset(name)


def test_edited_preset_file_runs_like_the_preset(capsys, tmp_path):
    code, out, _ = run(capsys, "presets", "fig3a")
    path = tmp_path / "my.toml"
    path.write_text(out, encoding="utf-8")
    from_file = run_json(capsys, str(path), *SHORT)
    from_preset = run_json(capsys, "--preset", "fig3a", *SHORT)
    assert from_file["impacts"] == from_preset["impacts"]
    assert from_file["scene"] == from_preset["scene"]


def test_params_lists_every_parameter(capsys):
    code, out, err = run(capsys, "params")
    assert code == 0 and err == ""
    listed = {line.split()[0] for line in out.splitlines()[1:]}
    assert set(PARAMETERS) <= listed
    code, out, _ = run(capsys, "params", "beta")
    assert code == 0 and "must be > 0" in out and len(out.splitlines()) == 2


def test_params_shows_each_default(capsys):
    """Each parameter's default beside its meaning and range, derived ones say what
    they follow."""
    code, out, err = run(capsys, "params")
    assert code == 0 and err == ""
    header, *lines = out.splitlines()
    assert header.split()[:2] == ["parameter", "default"]
    rows = {line.split()[0]: line.split(None, 1)[1] for line in lines}
    assert set(PARAMETERS) <= set(rows)
    defaults = Scene().to_dict()
    for name in ("period_ratio", "gap", "beta", "chi", "length_A", "rtol", "transient"):
        assert rows[name].split()[0] == f"{defaults[name]:g}", name
    assert rows["method"].startswith("dopri5 ") and rows["model"].startswith("auto ")
    assert rows["mass_ratio"].startswith("auto: freq_ratio**2 = 2.25 ")
    assert rows["atol"].startswith("1e-3 rtol = 1e-08 ")
    assert rows["zeta"].startswith("0.03 ")
    code, out, _ = run(capsys, "params", "gap")
    assert out.splitlines()[1].split()[:2] == ["gap", "1"] and "must be >= 0" in out


# ============================================================= --output
def test_output_writes_the_same_json(capsys, tmp_path):
    target = tmp_path / "run.json"
    code, out, err = run(
        capsys, "simulate", "--preset", "wall", *SHORT, "--json", "--output", str(target)
    )
    assert code == 0 and err == ""
    assert json.loads(target.read_text(encoding="utf-8")) == json.loads(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.json"]  # no temp file left


def test_output_refuses_to_overwrite(capsys, tmp_path):
    target = tmp_path / "run.json"
    target.write_text("keep me", encoding="utf-8")
    code, out, err = run(capsys, "simulate", "--preset", "wall", *SHORT, "--output", str(target))
    assert_one_line_error(code, out, err, "run.json", "--overwrite")
    assert target.read_text(encoding="utf-8") == "keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.json"]
    code, out, err = run(
        capsys, "simulate", "--preset", "wall", *SHORT, "--output", str(target), "--overwrite"
    )
    assert code == 0 and err == "" and "wrote" in out
    assert json.loads(target.read_text(encoding="utf-8"))["model"] == "wall"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.json"]


def test_output_into_missing_folder_is_refused_before_running(capsys, tmp_path, monkeypatch):
    def must_not_run(*args, **kwargs):
        raise AssertionError("simulate ran although the output path is unusable")

    monkeypatch.setattr(importlib.import_module("chaospound.simulate"), "simulate", must_not_run)
    target = tmp_path / "no" / "such" / "run.json"
    code, out, err = run(capsys, "simulate", "--preset", "wall", "--output", str(target))
    assert_one_line_error(code, out, err, "run.json")
    assert not (tmp_path / "no").exists()


def test_failed_write_leaves_nothing(tmp_path, monkeypatch):
    target = tmp_path / "run.json"

    def broken_replace(src, dst):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(cli.files.os, "replace", broken_replace)  # write_json_file's os
    with pytest.raises(cli.CliError, match="run.json"):
        cli.write_json_file({"x": 1.0}, str(target))
    assert list(tmp_path.iterdir()) == []


def test_non_finite_numbers_become_null(tmp_path):
    target = tmp_path / "nan.json"
    cli.write_json_file({"a": [1.0, float("nan")], "b": float("inf")}, str(target))
    assert json.loads(target.read_text(encoding="utf-8")) == {"a": [1.0, None], "b": None}


# ======================================= a newcomer's small inconsistencies (issue 18)
@pytest.mark.parametrize("value", ["0", "-2", "two"])
def test_workers_below_one_gets_one_message(capsys, tmp_path, value):
    """--workers 0 and --workers -2 are refused with the same words."""
    code, out, err = run(capsys, "sweep", "--preset", "wall", "--param", "gap=1,2", "-o",
                         str(tmp_path / "x.h5"), "--workers", value)
    assert_one_line_error(code, out, err, "--workers", "must be an integer >= 1")
    assert list(tmp_path.iterdir()) == []


def test_empty_scene_file_says_which_defaults_it_runs(capsys, tmp_path):
    path = tmp_path / "empty.toml"
    path.write_text("", encoding="utf-8")
    code, out, err = run(capsys, "simulate", str(path), *SHORT, "--json")
    assert code == 0
    [line] = err.splitlines()
    assert line.startswith("chaospound: note: ") and "empty.toml" in line
    assert "sets no parameter" in line and "default scene" in line
    for shown in ("period_ratio = 0.7", "freq_ratio = 1.5", "gap = 1", "beta = 1000",
                  "method = dopri5", "rtol = 1e-05", "transient = 40"):
        assert shown in line
    assert json.loads(out)["scene"] == {**Scene().with_params(transient=5, record=2).to_dict()}
    # a file that sets something runs without the note
    path.write_text("[structure]\ngap = 0.5\n", encoding="utf-8")
    code, out, err = run(capsys, "simulate", str(path), *SHORT, "--json")
    assert code == 0 and err == ""


@pytest.mark.parametrize(("law", "name", "value"), [
    ("hertz", "restitution", "0.5"), ("linear", "chi", "2"), ("linear", "no_pull", "true"),
    ("hunt-crossley", "damping_variant", "ye"),
])
def test_a_contact_input_the_law_does_not_read_is_noted(capsys, law, name, value):
    """--set restitution=0.5 under the elastic hertz law changes nothing (the packed
    parameters are the same): one note says so and names the laws that read it."""
    def scene_of(*assignments):
        args = cli.build_parser().parse_args(
            ["simulate", "--preset", "wall", "--set", f"contact_law={law}",
             *(item for a in assignments for item in ("--set", a))])
        return cli.scene_from_args(args)

    plain = scene_of()
    assert capsys.readouterr() == ("", "")
    scene = scene_of(f"{name}={value}")
    out, err = capsys.readouterr()
    assert out == ""
    [line] = err.splitlines()
    assert line.startswith(f"chaospound: note: {name} = {value} has no effect: ")
    assert f"the {law} contact law does not read {name}" in line
    # (every law but hertz reads its block after N_PARAMS, not Hertz's chi slot P_CHI)
    slots = [] if law == "hertz" else [P_CHI]
    np.testing.assert_array_equal(np.delete(scene.pack(), slots), np.delete(plain.pack(), slots))
    # a law that reads it: no note
    reader = {"restitution": "hertzdamp", "chi": "hertz", "no_pull": "kelvin-voigt",
              "damping_variant": "hertzdamp"}[name]
    scene_of(f"contact_law={reader}", f"{name}={value}")
    assert capsys.readouterr() == ("", "")


def test_a_sweep_over_a_contact_input_the_law_does_not_read_is_refused(capsys, tmp_path):
    out_file = tmp_path / "r.h5"
    code, out, err = run(capsys, "sweep", "--preset", "wall", "--param",
                         "restitution=0.3:0.9#4", "-o", str(out_file))
    assert_one_line_error(code, out, err, "sweep restitution=0.3:0.9#4",
                          "every point would be the same", "hertz contact law")
    assert not out_file.exists()


@pytest.mark.parametrize(("options", "expected"), [
    (["--set", "gap=2", "--param", "gap=1,2"], "--set gap=2 (swept: gap)"),
    (["--set", "zeta=0.1", "--param", "zeta_x_A=0.01,0.02"], "--set zeta=0.1 (swept: zeta_x_A)"),
    (["--set", "beta=2000", "--rtol", "1e-6", "--param", "rtol=1e-5,1e-6"],
     "--rtol 1e-6 (swept: rtol)"),
    (["--set", "gap=2", "--param", "period_ratio=0.5,0.6"], None),
])
def test_note_sweep_overrides(capsys, options, expected):
    """The helper _cmd_sweep calls: one note on stderr when --set names a swept parameter."""
    args = cli.build_parser().parse_args(["sweep", "--preset", "wall", *options, "-o", "x.h5"])
    note = cli.note_sweep_overrides(args, cli.scene_from_args(args))
    out, err = capsys.readouterr()
    assert out == ""
    if expected is None:
        assert note is None and err == ""
        return
    assert expected in note and "overrides" in note
    assert err == f"chaospound: note: {note}\n"
    assert "beta" not in note


def test_note_sweep_overrides_reads_the_scene_sweep_table(capsys):
    args = cli.build_parser().parse_args(["sweep", "--preset", "fig4", "--set",
                                          "period_ratio=0.9", "-o", "x.h5"])
    note = cli.note_sweep_overrides(args, cli.scene_from_args(args))
    assert "--set period_ratio=0.9 (swept: period_ratio)" in note


def test_plot_titles_do_not_show_the_internal_branch_name(capsys, tmp_path):
    path = tmp_path / "wall.h5"
    code, _, err = run(capsys, "sweep", "--preset", "wall", *SHORT, "--param",
                       "period_ratio=0.5:1.0#3", "-o", str(path), "--quiet")
    assert code == 0, err
    from chaospound.store import open_sweep

    fig = cli._sweep_figure(open_sweep(path), ["fresh"])
    titles = [ax.get_title() for ax in fig.axes] + [fig.get_suptitle()]
    assert not any("fresh" in title for title in titles), titles
    assert "3 of 3 points" in titles[0]


# ================================================================ units
@pytest.mark.parametrize("argv", [
    ["simulate", "--preset", "wall", *SHORT, "--json"],
    ["lyapunov", "--preset", "wall", *SHORT, "--cycles", "10", "--json"],
    ["classify", "--preset", "wall", "--transient", "5", "--max-transient", "20", "--json"],
    ["bench", "--preset", "wall", *SHORT, "--repeats", "1", "--no-cli", "--json"],
])
def test_every_json_document_carries_units(capsys, argv):
    """As the sweep file does: the units of lengths, velocities, forces, times, exponents."""
    from chaospound.store import UNITS

    code, out, err = run(capsys, *argv)
    assert code == 0, err
    units = json.loads(out)["units"]
    assert {key: units[key] for key in UNITS} == UNITS
    assert units["velocity"] == "A_g omega_Ax" and units["force"] == "A_g k_Ax"
    assert units["wall_s"].startswith("seconds")


def test_simulate_table_states_units(capsys):
    code, out, err = run(capsys, "simulate", "--preset", "wall", *SHORT)
    assert code == 0 and err == ""
    velocity = next(line for line in out.splitlines() if line.startswith("velocity"))
    assert velocity.endswith("(A_g omega_Ax)")
    header = next(i for i, line in enumerate(out.splitlines()) if line.startswith("#"))
    assert "A_g k_Ax" in out.splitlines()[header + 1]


# ============================================== status lines, compilation (issue 18)
class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def slow_work(seconds: float = 0.35):
    time.sleep(seconds)


@pytest.mark.parametrize(("stream", "quiet", "shown"), [
    (FakeTerminal(), False, True),
    (FakeTerminal(), True, False),
    (io.StringIO(), False, False),  # a file, a pipe, a log: never a status line
])
def test_status_line_only_on_a_terminal_without_quiet(stream, quiet, shown):
    with cli._Status("working", quiet=quiet, delay=0.0, stream=stream) as status:
        slow_work()
        status.set("stage two")
        slow_work(0.05)
    text = stream.getvalue()
    assert ("chaospound: working ... 0 s" in text) == shown
    if shown:
        assert text.endswith("\r\033[K")  # cleared: the results follow on a clean line
    else:
        assert text == ""


def test_status_line_waits_for_slow_work():
    stream = FakeTerminal()
    with cli._Status("quick", delay=5.0, stream=stream):
        slow_work(0.05)
    assert stream.getvalue() == ""


def test_compilation_is_announced_at_once(monkeypatch):
    """Kernels not in numba's disk cache: the notice comes before the compilation."""
    jit = importlib.import_module("chaospound.simulate")  # where kernels_cached lives

    stream = FakeTerminal()
    monkeypatch.setattr(sys, "stderr", stream)
    monkeypatch.setattr(jit, "kernels_cached", lambda *composition: False)
    cli._load_kernels(False, slow_work)
    assert "chaospound: compiling kernels, first run only, about 10-15 s ... 0 s" in \
        stream.getvalue()
    stream = FakeTerminal()
    monkeypatch.setattr(sys, "stderr", stream)
    cli._load_kernels(True, slow_work)  # --quiet
    assert stream.getvalue() == ""
    monkeypatch.setattr(jit, "kernels_cached", lambda *composition: True)
    cli._load_kernels(False, slow_work)  # cached: loads in well under the delay
    assert stream.getvalue() == ""


def test_cache_detection_sees_compiled_and_stale_kernels(tmp_path, monkeypatch):
    """is_cached: False before the first compilation, True after, False after an edit."""
    import importlib

    from chaospound.kernels.jit import is_cached
    from chaospound.simulate import kernels_cached

    source = tmp_path / "fresh_kernel_module.py"
    source.write_text("from numba import njit\n\n@njit(cache=True)\ndef twice(x):\n"
                      "    return 2.0 * x\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module("fresh_kernel_module")
    assert is_cached(module.twice) is False
    assert module.twice(2.0) == 4.0
    assert is_cached(module.twice) is True
    source.write_text(source.read_text(encoding="utf-8").replace("2.0 * x", "x + x"),
                      encoding="utf-8")  # edited: the cached code is stale
    importlib.invalidate_caches()
    module = importlib.reload(module)
    assert is_cached(module.twice) is False
    main(["simulate", "--preset", "wall", *SHORT, "--json"])  # loads (or compiles) them
    assert kernels_cached() is True


def test_classify_reports_its_stages(capsys, monkeypatch):
    stream = FakeTerminal()
    monkeypatch.setattr(cli.status, "STATUS_DELAY_S", 0.0)
    monkeypatch.setattr(sys, "stderr", stream)
    code = main(["classify", "--preset", "fig3a", "--transient", "5", "--max-transient", "40"])
    out = capsys.readouterr().out
    assert code == 0
    text = stream.getvalue()
    assert "chaospound: classifying fig3a" in text and text.endswith("\r\033[K")
    assert "wall time" in out and "s the whole command" in out
    # the stages the line shows
    from chaospound.dynamics.classify import classify

    stages = []
    classify(load_preset("fig3a"), min_transient=5, max_transient=40, progress=stages.append)
    assert stages[0] == "transient: 0 of at most 40 cycles"
    assert "transient: 5 of at most 40 cycles" in stages
    assert any(stage.startswith("record window: 64 cycles") for stage in stages)


def test_simulate_reports_kernel_and_command_time(capsys):
    code, out, err = run(capsys, "simulate", "--preset", "wall", *SHORT)
    assert code == 0 and err == ""
    [line] = [line for line in out.splitlines() if line.startswith("wall time")]
    kernel, command = line.split("s in the kernels")[0].split()[-1], line.split(";")[1].split()[0]
    assert 0 < float(kernel) < float(command)


def test_sweep_says_when_the_grid_overrides_a_set(tmp_path):
    """`--set gap=2 --param gap=1,2`: the sweep runs over the grid and says so on stderr,
    in one line, after its input was found valid."""
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root))
    path = tmp_path / "override.h5"
    proc = subprocess.run([sys.executable, "-m", "chaospound", "sweep", "--preset", "wall",
                           "--set", "transient=2", "--set", "record=2", "--set", "gap=2",
                           "--param", "gap=1,2", "-o", str(path), "--quiet"],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and "overrides --set gap=2" in lines[0], proc.stderr
    assert path.exists()


def test_a_report_says_what_set_changed_from_the_preset(capsys):
    """fig3a's description names its regime at T/T_Ax = 0.70: after --set, the report's
    scene row says what changed from the preset; run and solver options are not physics.
    The scene itself (its JSON, a store's record) keeps the preset's description."""
    code, out, _ = run(capsys, "simulate", "--preset", "fig3a", "--set", "period_ratio=0.9",
                       "--set", "gap=0.6", "--method", "dop853", *SHORT)
    first = out.splitlines()[0]
    assert code == 0 and first.endswith("; changed from the preset: period_ratio 0.7 -> 0.9, "
                                        "gap 1 -> 0.6"), first
    code, out, _ = run(capsys, "simulate", "--preset", "fig3a", "--method", "dop853", *SHORT)
    assert code == 0 and "changed" not in out.splitlines()[0]
    doc = run_json(capsys, "--preset", "fig3a", "--set", "period_ratio=0.9", *SHORT)
    assert doc["scene"]["description"] == load_preset("fig3a").description
