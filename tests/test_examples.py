"""The example files the README's tour and the docs run: docs/examples/.

- synthetic.AT2 is exactly what its script writes (nothing downloaded, nothing
  edited by hand), and reads back as its header says: 2001 samples at 0.01 s, in g,
  a peak of 0.35 g, at rest at the end (baseline-corrected: the velocity
  integrated from the accelerations returns to zero);
- my_oscillator.py holds the system of docs/custom_systems.md: its parameters,
  and its documented response, periodic 1-1 (one impact a cycle).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from chaospound import classify
from chaospound.physics.ground.records_io import read_at2
from chaospound.userfile import load_system

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"


def _script(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_shipped_record_is_what_its_script_writes(tmp_path):
    written = _script("make_synthetic_record").main(tmp_path / "again.AT2")
    assert written.read_bytes() == (EXAMPLES / "synthetic.AT2").read_bytes()


def test_the_shipped_record_reads_as_its_header_says():
    dt, a, units = read_at2(EXAMPLES / "synthetic.AT2")
    assert (dt, a.size, units) == (0.01, 2001, "g")
    assert abs(np.max(np.abs(a)) - 0.35) < 0.01  # 0.35 g before the baseline correction
    velocity = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * dt)])  # g s
    assert abs(velocity[-1]) < 1e-6 * np.max(np.abs(velocity))


def test_the_example_oscillator_is_the_documented_one():
    system = load_system(f"{EXAMPLES / 'my_oscillator.py'}:system")
    assert dict(system.parameter_values) == {"c": 0.06, "gap": 1.0, "beta": 1000.0, "r": 0.7}
    assert system.state_names == ("x", "dx") and system.has_gap
    assert classify(system).label == "periodic 1-1"  # as docs/custom_systems.md says


def test_a_record_run_says_what_part_of_the_motion_it_spans(capsys):
    """The README's record command covers the 20 s record; the preset's default 40 + 8
    cycles of T = 0.35 s stop at 16.8 s, and the report says so and how to cover it."""
    from chaospound.cli import main

    base = ["simulate", "--preset", "fig3a", "--set", "ground=record", "--set",
            f"ground_file={EXAMPLES / 'synthetic.AT2'}", "--set", "length_unit=0.01",
            "--set", "tower_period=0.5"]
    assert main(base) == 0
    out = capsys.readouterr().out
    assert f"record {EXAMPLES / 'synthetic.AT2'}" in out and "contact        hertz" in out
    assert "motion ends at t = 251.327 (20 s); the run spans t = 0 to 211.115 (16.8 s): " \
           "its last part is not run (--set record=18 covers it)" in out
    assert main([*base, "--set", "transient=0", "--set", "record=58"]) == 0
    out = capsys.readouterr().out
    assert "the run spans t = 0 to 255.097 (20.3 s)\n" in out
