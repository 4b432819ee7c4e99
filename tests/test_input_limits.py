"""User input at the edge: grids, --set values and scene files that are wrong, huge,
deep or absurd give one line on stderr and exit 2, fast, and write nothing.

The real-process checks run ``python -m chaospound`` (the worktree first on
PYTHONPATH); they fail before any kernel is compiled, so each takes about a second.
The timeouts are generous bounds against hanging, not speed assertions.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from chaospound.grid import (
    MAX_NUMBER_LENGTH,
    MAX_POINTS,
    Axis,
    _first_invalid,
    check_axes,
    grid_values,
    make_axis,
    parse_axis,
)
from chaospound.messages import shorten
from chaospound.scene import Scene, SceneError, load_preset

ROOT = Path(__file__).resolve().parents[1]
WALL = load_preset("wall")
FIG3A = load_preset("fig3a")
PAIR = Scene().with_params(model="pair")  # exact only while e_y = 0 and offset_y = 0
TIMEOUT = 20  #: seconds: "does not hang", far above the ~1 s these take


def subprocess_env() -> dict:
    return dict(os.environ,
                PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))


def chaospound(*argv: str, timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "chaospound", *map(str, argv)],
                          capture_output=True, text=True, env=subprocess_env(),
                          timeout=timeout, cwd=ROOT)


def one_line_error(proc: subprocess.CompletedProcess, *words: str) -> str:
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert proc.stdout == ""
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr[-2000:]
    assert lines[0].startswith("chaospound: error: ")
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


# ------------------------------------------------------------ real processes


def test_a_bad_middle_list_value_writes_nothing(tmp_path):
    """Every value of a list is checked, not only the first and the last."""
    out = tmp_path / "out"
    out.mkdir()
    proc = chaospound("sweep", "--preset", "wall", "--param", "period_ratio=0.5,-1,0.6",
                      "-o", out / "x.h5", "--quiet")
    one_line_error(proc, "period_ratio", "-1.0", "must be > 0")
    assert list(out.iterdir()) == []


@pytest.mark.parametrize("grid", [
    "1:1e309:1",  # stop overflows to inf
    "1:2:1e-320",  # a subnormal step: (stop - start) / step overflows
    "0:1e308:1e-308",
    "1e308:-1e308:-1e308",  # stop - start overflows
    "-1e308:1e308#3",  # linspace overflows
    "1:2#99999999999999999999",
    "1:2#" + "9" * 5000,  # more digits than int() converts
    "1:2:nan",
    "inf:2:1",
    "0.5,1e400",
    "1:2:0",
    "1:2#0",
    "1:2:3:4",
    "1:2#3#4",
    "1#2:3",
])
def test_absurd_grids_are_one_line(tmp_path, grid):
    proc = chaospound("sweep", "--preset", "wall", "--param", f"period_ratio={grid}",
                      "-o", tmp_path / "x.h5", "--quiet")
    line = one_line_error(proc, "period_ratio")
    assert len(line) < 300
    assert list(tmp_path.iterdir()) == []


def deep_files(folder: Path) -> dict[str, Path]:
    depth = 5000
    texts = {
        "arrays": "a = " + "[" * depth + "]" * depth + "\n",
        "inline-tables": "a = " + "{b = " * depth + "1" + "}" * depth + "\n",
        "mixed": "[excitation]\nperiod_ratio = " + "[{a = " * depth + "1" + "}]" * depth + "\n",
        "table-headers": "[" + ".".join(["t"] * depth) + "]\n",
        "unclosed": "a = " + "[" * depth + "\n",
    }
    files = {}
    for name, text in texts.items():
        files[name] = folder / f"{name}.toml"
        files[name].write_text(text)
    return files


def test_deep_toml_is_one_line_naming_the_file(tmp_path):
    for name, path in deep_files(tmp_path).items():
        proc = chaospound("simulate", path)
        line = one_line_error(proc, str(path))
        assert len(line) < 400, (name, line)


def test_garbage_and_huge_toml_are_one_line(tmp_path):
    files = {
        "binary": bytes(range(256)) * 64,
        "nul": b"\x00\x01abc = 1\n",
        "huge-int": b"[structure]\ngap = 0x" + b"f" * 100_000 + b"\n",
        "long-int": b"[structure]\ngap = 1" + b"0" * 5000 + b"\n",
        "long-key": b"[structure]\n" + b"k" * 100_000 + b" = 1\n",
        "twice": (b"k" * 100_000 + b" = 1\n") * 2,
        "long-string": b'[structure]\ngap = "' + b"1" * 100_000 + b'x"\n',
        "long-name": b'name = "' + b"n" * 100_000 + b'"\n[structure]\ngap = -1\n',
        "long-grid": b'[sweep]\nperiod_ratio = "' + b"1" * 100_000 + b'"\n',
    }
    for name, data in files.items():
        path = tmp_path / f"{name}.toml"
        path.write_bytes(data)
        command = "sweep" if name == "long-grid" else "simulate"
        extra = ["-o", tmp_path / "x.h5"] if command == "sweep" else []
        proc = chaospound(command, path, *extra)
        line = one_line_error(proc, str(path))
        assert len(line) < 400, (name, line)
    assert not (tmp_path / "x.h5").exists()


def test_a_100k_digit_grid_value_is_refused_at_once(tmp_path):
    """The old grid regex backtracked quadratically: minutes for 100 000 digits."""
    digits = "1" * 100_000
    for grid in (digits, f"0.5:{digits}:0.1", f"0.5:{digits}#3", f"0.5,{digits}x",
                 ":" * 100_000, "1" + ",1" * 60_000 + "x", "1." + "1" * 100_000 + "e"):
        proc = chaospound("sweep", "--preset", "wall", "--param", f"period_ratio={grid}",
                          "-o", tmp_path / "x.h5")
        line = one_line_error(proc, "period_ratio")
        assert len(line) < 300, line
    assert list(tmp_path.iterdir()) == []


def test_a_100k_set_value_is_quoted_short():
    value = "1" * 100_000 + "x"
    for argv in (["--set", f"gap={value}"], ["--set", f"{value}=1"], ["--set", value],
                 ["--set", f"method={value}"], ["--rtol", value]):
        proc = chaospound("simulate", "--preset", "wall", *argv)
        line = one_line_error(proc)
        assert "(100001 characters)" in line, line
        assert "1" * 81 not in line
        assert len(line) < 1000, line  # an unknown name lists the known ones


def test_long_arguments_to_argparse_are_quoted_short(tmp_path):
    value = "7" * 100_000
    for argv in (["--workers", value + "x"], ["--continuation", value], ["--lyapunov", "x" + value],
                 [f"--bogus{value}"]):
        proc = chaospound("sweep", "--preset", "wall", "--param", "gap=1,2", *argv,
                          "-o", tmp_path / "x.h5")
        line = one_line_error(proc)
        assert "7" * 81 not in line and len(line) < 300, line


# --------------------------------------------------------------- in process


def test_every_grid_form_still_parses():
    assert list(parse_axis("gap = 1, 2.5,4", WALL).values) == [1.0, 2.5, 4.0]
    assert list(parse_axis("gap=1,,2,", WALL).values) == [1.0, 2.0]  # empty items skipped
    assert len(parse_axis("period_ratio=0.3:2.0:0.005", WALL)) == 341
    axis = parse_axis("period_ratio=0.3:2.0#1000", WALL)
    assert np.array_equal(axis.values, np.linspace(0.3, 2.0, 1000))
    assert list(parse_axis("gap=3:1:-1").values) == [3.0, 2.0, 1.0]
    assert list(parse_axis("gap=1:1:0.5").values) == [1.0]
    assert list(parse_axis("gap=+1e0:.5e1#2").values) == [1.0, 5.0]
    # 1e308 - (-1e308) overflows, the count does not
    assert len(grid_values("offset_y", "-1e308:1e308:1e308")) == 3
    assert list(grid_values("offset_y", "1e308:-1e308:-1e308")) == [1e308, 0.0, -1e308]
    assert len(make_axis("period_ratio", "1:2#" + "0" * 1000 + "3")) == 3
    assert len(make_axis("gap", f"0:{MAX_POINTS - 1}:1")) == MAX_POINTS


@pytest.mark.parametrize(("grid", "words"), [
    ("1:2:1e-320", ["too many points", str(MAX_POINTS)]),
    ("0:1:1e-300", ["about 1e+300 points"]),
    ("1:2#99999999999999999999", ["99999999999999999999 points"]),
    (f"0:{MAX_POINTS}:1", [f"{MAX_POINTS + 1} points"]),
    ("1:1e309:1", ["non-finite value '1e309'"]),
    ("-1e308:1e308#3", ["non-finite values"]),
    ("1:" + "2" * (MAX_NUMBER_LENGTH + 1) + ":1", [f"{MAX_NUMBER_LENGTH + 1} characters"]),
    ("1,2;3", ["not a grid"]),
    ("", ["empty range"]),
    # the same point twice would be one label stored in two rows
    ("0.7,0.7", ["value 0.7 is repeated"]),
    ("0.7:0.7#3", ["value 0.7 is repeated"]),
])
def test_grid_errors(grid, words):
    with pytest.raises(ValueError) as info:
        make_axis("gap", grid)
    message = str(info.value)
    assert "\n" not in message and len(message) < 300
    for word in words:
        assert word in message, message


def test_a_sweep_of_a_choice_or_a_flag_says_it_is_not_numeric():
    for text, words in (("contact_law=hertz,linear", ["not a numeric parameter", "hertzdamp",
                                                      "--set contact_law="]),
                        ("no_pull=0,1", ["not a numeric parameter", "true or false"])):
        with pytest.raises(ValueError) as info:
            parse_axis(text)
        message = str(info.value)
        assert "\n" not in message and all(word in message for word in words), message


def test_every_value_is_checked_against_the_scene():
    with pytest.raises(ValueError, match=r"sweep period_ratio=0.5,-1,0.6: period_ratio = -1.0"):
        parse_axis("period_ratio=0.5,-1,0.6", WALL)
    with pytest.raises(ValueError, match=r"transient = 2.5: must be an integer"):
        parse_axis("transient=0,1,2.5,3", WALL)
    # a range of more values than are checked one by one: its first fraction is found
    with pytest.raises(ValueError, match=r"transient = 0.5: must be an integer"):
        parse_axis("transient=0:5000:0.5", WALL)
    with pytest.raises(ValueError,
                       match=r"ecc_y_A=0,1,0.5: at ecc_y_A = 1.0: model = 'pair': not exact"):
        parse_axis("ecc_y_A=0,1,0.5", PAIR)
    parse_axis("transient=0:5000:1", WALL)


def test_two_axes_are_checked_together():
    """length_A and offset_y are only valid together where the towers overlap."""
    axes = [parse_axis("length_A=10:200#5"), parse_axis("offset_y=-150:150#4")]
    with pytest.raises(ValueError, match=r"no overlap at rest"):
        check_axes(Scene(), axes)
    check_axes(Scene(), [parse_axis("length_A=100:200#5"), parse_axis("offset_y=-90:90#4")])
    with pytest.raises(ValueError, match="both given"):
        check_axes(Scene(), [parse_axis("width_A=10,20"), parse_axis("width_ratio_A=0.5,0.6")])
    # many values: the corners
    big = [parse_axis("length_A=10:200#2000"), parse_axis("offset_y=-150:150#2000")]
    with pytest.raises(ValueError, match=r"no overlap at rest"):
        check_axes(Scene(), big)


NUMERIC = [
    "period_ratio", "freq_ratio", "mass_ratio", "gap", "offset_y", "beta", "chi",
    "length_A", "length", "width_A", "width_ratio_B", "ecc_x_A", "ecc_y_A", "ecc_y_ratio_A",
    "ecc_y_B", "gyration_A", "zeta_x_A", "zeta", "rtol", "atol", "steps_per_cycle",
    "max_steps", "transient", "record", "phase", "method", "restart_at_kinks", "ground",
]
EDGES = [-1e308, -200.0, -100.0, -50.0, -1.0, -0.5, -1e-300, 0.0, 5e-324, 1e-320, 1e-300,
         0.25, 0.5, 0.99, 1.0, 1.5, 3.0, 4.0, 50.0, 99.9, 100.0, 150.0, 200.0, 1e308]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(NUMERIC),
       scene=st.sampled_from([WALL, FIG3A, PAIR, Scene().with_params(offset_y=60.0)]),
       values=st.lists(st.one_of(st.sampled_from(EDGES),
                                 st.floats(-300, 300, allow_nan=False)), min_size=1,
                       max_size=12))
def test_the_quick_check_agrees_with_checking_every_value(name, scene, values):
    """check_axis's argument: the extremes plus the first fraction decide for a grid."""
    values = np.array(values)
    every = _first_invalid(scene, name, values, exhaustive=len(values))
    quick = _first_invalid(scene, name, values, exhaustive=0)
    assert (every is None) == (quick is None), (name, values, every, quick)


PIECES = ["1", "-1", "0", "-0", "0.5", ".5", "1e308", "-1e308", "1e309", "1e-320", "5e-324",
          "nan", "inf", "1_0", "99999999999999999999", "١", " ", ":", ":", "#", "#", ",",
          ",", "e", ".", "+", "=", "\n", "\x00"]


@settings(max_examples=400, deadline=None)
@given(st.one_of(st.text(max_size=40), st.lists(st.sampled_from(PIECES), max_size=12).map(
    "".join)))
def test_any_grid_text_gives_an_axis_or_a_value_error(text):
    for scene in (None, WALL):
        try:
            axis = make_axis("gap", text, scene)
        except ValueError as exc:
            message = str(exc)
            assert "\n" not in message.strip() or "\n" in text, message
            assert len(message) < 400
        else:
            assert isinstance(axis, Axis) and 1 <= len(axis) <= MAX_POINTS
            assert np.all(np.isfinite(axis.values))
        with pytest.raises(ValueError):
            parse_axis(text.replace("=", ""), scene)  # no NAME=


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=30))
def test_any_set_value_gives_a_scene_or_a_scene_error(value):
    for name in ("gap", "transient", "method", "mass_ratio", "restart_at_kinks"):
        try:
            WALL.with_assignments([f"{name}={value}"])
        except SceneError as exc:
            assert len(str(exc)) < 400


def test_shorten():
    assert shorten("gap") == "gap"
    assert shorten("gap", quote=True) == "'gap'"
    long = "1" * 100_000
    assert shorten(long) == "1" * 77 + "... (100000 characters)"
    assert shorten(long, quote=True) == "'" + "1" * 77 + "...' (100000 characters)"
    assert len(shorten(long, 10)) < 40
    assert shorten("x" * 80) == "x" * 80
    assert math.isclose(len(shorten("x" * 81)), 80 + len(" (81 characters)"))
