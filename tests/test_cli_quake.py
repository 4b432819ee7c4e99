"""``chaospound quake`` and ``simulate --units si`` on the command line.

The tests write their own accelerogram; the command's peaks are those of the
library on the same scene, ``--units si`` converts them with the hand formulas,
an ensemble without perturbation has no spread, and bad input is one line on
stderr with exit status 2.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from chaospound.cli import main
from chaospound.quake import quake
from chaospound.scene import load_preset

SCENE = ["--preset", "wall", "--set", "length_unit=0.01", "--set", "tower_period=0.5",
         "--set", "gap=2"]


@pytest.fixture(scope="module")
def record_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli_quake") / "pulse.txt"
    t = np.arange(0.0, 4.0 + 1e-9, 0.01)
    a = 0.5 * np.sin(2.0 * np.pi * t / 0.35) * np.exp(-(((t - 1.5) / 1.0) ** 2))
    np.savetxt(path, np.column_stack([t, a]))
    return str(path)


def _run(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_quake_json_matches_the_library(capsys, record_file):
    code, out, err = _run(capsys, "quake", *SCENE, "--record", record_file, "--json",
                          "--ensemble", "2", "--quiet")
    assert code == 0, err
    document = json.loads(out)
    scene = load_preset("wall").with_params(length_unit=0.01, tower_period=0.5, gap=2.0)
    run = quake(scene, record=record_file, runs=2)
    assert document["impacts"] == run.impacts > 0
    assert document["peak_force"] == run.peak_force
    assert document["corners"] == [vars(c) for c in run.corners]
    assert document["lyapunov"]["exponent"] == run.lyapunov.exponent
    assert document["ensemble"]["spread"] == 0.0


def test_quake_units_si(capsys, record_file):
    code, out, err = _run(capsys, "quake", *SCENE, "--set", "tower_mass=2e5", "--record",
                          record_file, "--units", "si", "--json", "--no-lyapunov", "--quiet")
    assert code == 0, err
    document = json.loads(out)
    omega = 2.0 * math.pi / 0.5
    si = document["si"]
    assert si["peak_force"] == pytest.approx(document["peak_force"] * 0.01 * 2e5 * omega**2
                                             / 1e3, rel=1e-14)
    corner, corner_si = document["corners"][0], si["corners"][0]
    assert corner_si["peak_velocity"] == pytest.approx(corner["peak_velocity"] * 0.01 * omega,
                                                       rel=1e-14)
    assert corner_si["peak_penetration"] == pytest.approx(corner["peak_penetration"] * 10.0,
                                                          rel=1e-14)
    code, out, err = _run(capsys, "quake", *SCENE, "--set", "tower_mass=2e5", "--record",
                          record_file, "--units", "si", "--no-lyapunov", "--quiet")
    assert code == 0 and "kN" in out and "force unit" in out


def test_quake_plot(capsys, record_file, tmp_path):
    figure = tmp_path / "quake.png"
    code, out, err = _run(capsys, "quake", *SCENE, "--record", record_file, "--no-lyapunov",
                          "--plot", str(figure), "--quiet")
    assert code == 0, err
    assert figure.stat().st_size > 10_000


@pytest.mark.parametrize("content, words", [
    ("0.0 0.1\n0.01 abc\n", "bad.txt"),
    ("", "bad.txt"),
    ("0.0 0.1\n0.0 0.2\n", "bad.txt"),
])
def test_bad_record_file_is_one_line_exit_2(capsys, tmp_path, content, words):
    bad = tmp_path / "bad.txt"
    bad.write_text(content)
    code, out, err = _run(capsys, "quake", *SCENE, "--record", str(bad), "--quiet")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and words in err


@pytest.mark.parametrize("argv, words", [
    (["--record", "/nonexistent/x.AT2"], "not found"),
    ([], "needs a record"),
    (["--record", "{record}", "--perturb", "1e-6"], "need --ensemble"),
    (["--record", "{record}", "--ensemble", "2", "--realisations"], "not stochastic"),
    (["--record", "{record}", "--units", "si"], "tower_mass"),
    (["--record", "{record}", "--scale-spread", "1.5", "--ensemble", "2"], "--scale-spread"),
    (["--record", "{record}", "--set", "ground_pga=-1"], "ground_pga"),
])
def test_bad_options_are_one_line_exit_2(capsys, record_file, argv, words):
    argv = [a.replace("{record}", record_file) for a in argv]
    code, out, err = _run(capsys, "quake", *SCENE, *argv, "--quiet")
    assert code == 2 and out == "", err
    assert err.count("\n") == 1 and words in err


def test_simulate_units_si(capsys):
    code, out, err = _run(capsys, "simulate", "--preset", "fig3a", "--set", "length_unit=0.01",
                          "--set", "tower_period=0.5", "--set", "tower_mass=1e6", "--set",
                          "transient=5", "--set", "record=2", "--units", "si", "--json")
    assert code == 0, err
    document = json.loads(out)
    omega = 2.0 * math.pi / 0.5
    forces = [i["peak_force"] for i in document["impacts"]]
    np.testing.assert_allclose(document["si"]["impacts"]["peak_force"],
                               np.array(forces) * 0.01 * 1e6 * omega**2 / 1e3, rtol=1e-14)
    code, out, err = _run(capsys, "simulate", "--preset", "fig3a", "--units", "si")
    assert code == 2 and "tower_mass" in err
