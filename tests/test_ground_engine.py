"""Ground motions inside the composed engine: records and stochastic motions.

A record that samples the harmonic motion's acceleration reproduces the sine
scene's run, with an error that falls at the order of the piecewise-linear
acceleration (2) as the sampling interval shrinks; the engine lands on every
sample; a stochastic motion runs bit for bit the same from the same seed.
"""

from dataclasses import replace

import numpy as np
import pytest

from chaospound import load_preset
from chaospound.dynamics.system import System
from chaospound.physics.ground import record, stochastic
from chaospound.simulate import simulate


def _sine_and_record(samples_per_period: int, cycles: int = 12):
    scene = load_preset("fig3a").with_params(rtol=1e-11, atol=1e-13, method="dop853")
    system = replace(System.from_scene(scene), scene=None)
    r = scene.excitation.period_ratio
    t = np.linspace(0.0, cycles * system.period, cycles * samples_per_period + 1)
    block = record.block_from_samples(t, -np.sin(t / r) / r**2, baseline="none",
                                      initial_x=(0.0, 1.0 / r))
    sampled = replace(system, ground="record", params=np.concatenate((system.params, block)))
    return system, sampled


def test_a_sampled_sine_converges_to_the_sine_at_second_order():
    errors = []
    reference = None
    for n in (25, 50, 100, 200):
        system, sampled = _sine_and_record(n)
        if reference is None:
            reference = simulate(system, transient=6, record=3)
        run = simulate(sampled, transient=6, record=3)
        assert len(run.impacts) == len(reference.impacts)
        errors.append(max(np.max(np.abs(run.impacts.time - reference.impacts.time)),
                          np.max(np.abs(run.strobe.state - reference.strobe.state))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 1.8) & (orders < 2.2)), (errors, orders)


def test_the_engine_lands_on_every_sample():
    """Steps end on the record's samples: the runs of two tolerances agree far better
    than the tolerance would allow across the kinks of u_g''."""
    _, sampled = _sine_and_record(7, cycles=4)
    steps = []
    for rtol in (1e-9, 1e-12):
        run = simulate(sampled.with_solver(rtol=rtol, atol=rtol * 1e-2), transient=1,
                       record=2)
        steps.append(run.stats.steps)
    # at least one step per sample interval: 7 a period over 3 periods
    assert min(steps) >= 7 * 3


def test_stochastic_motion_is_reproducible_bit_for_bit():
    scene = load_preset("wall").with_params(gap=0.3)
    system = replace(System.from_scene(scene), scene=None)
    spec = {"omega_g": 3.0, "zeta_g": 0.6, "omega_f": 0.3, "zeta_f": 0.6, "intensity": 0.02,
            "dt": 0.05, "duration": 60.0, "seed": 7, "envelope": "jennings", "t_rise": 5.0,
            "t_plateau": 20.0, "decay": 0.1}
    runs = []
    for _ in range(2):
        block = stochastic.block(spec)
        quake = replace(system, ground="stochastic",
                        params=np.concatenate((system.params, block)))
        runs.append(simulate(quake, transient=0, record=8))
    assert runs[0].final_state.tobytes() == runs[1].final_state.tobytes()
    assert runs[0].impacts.time.tobytes() == runs[1].impacts.time.tobytes()
    other = dict(spec, seed=8)
    quake = replace(system, ground="stochastic",
                    params=np.concatenate((system.params, stochastic.block(other))))
    assert simulate(quake, transient=0, record=8).final_state.tobytes() != \
        runs[0].final_state.tobytes()


def test_impact_times_of_a_record_are_absolute():
    system, sampled = _sine_and_record(100)
    run = simulate(sampled, transient=6, record=3)
    assert np.all(run.impacts.time >= 6 * system.period)
    assert np.all(run.impacts.time <= 9.5 * system.period)
    assert np.all((run.impacts.phase >= 0.0) & (run.impacts.phase < 1.0))


@pytest.mark.parametrize("law", ["hertz", "jankowski"])
def test_a_record_after_a_law_block(law):
    """The record's block follows the law's: both read their own slots."""
    scene = load_preset("fig3a").with_params(contact_law=law, restitution=0.7)
    system = replace(System.from_scene(scene), scene=None)
    r = scene.excitation.period_ratio
    t = np.linspace(0.0, 10 * system.period, 1001)
    block = record.block_from_samples(t, -np.sin(t / r) / r**2, baseline="none",
                                      initial_x=(0.0, 1.0 / r))
    sampled = replace(system, ground="record", params=np.concatenate((system.params, block)))
    a = simulate(system, transient=4, record=2)
    b = simulate(sampled, transient=4, record=2)
    assert len(a.impacts) == len(b.impacts)
    assert np.max(np.abs(a.strobe.state - b.strobe.state)) < 5e-2  # sampling error, 100 a period


# ------------------------------------------------------- scenes and the command line

def _write_records(folder):
    """The same accelerogram as a PEER .AT2 (in g) and as a two-column text file."""
    t = np.arange(0.0, 20.0 + 1e-9, 0.01)
    a = 0.3 * np.sin(2.0 * np.pi * 2.0 * t) * np.exp(-0.15 * t)
    text = folder / "quake.txt"
    np.savetxt(text, np.column_stack([t, a]), fmt="%.10e")
    values = [f"{x: .10E}" for x in a]
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD", "SYNTHETIC", "UNITS OF G",
             f"NPTS=  {len(a)}, DT=   .0100 SEC"]
    lines += ["  ".join(values[i:i + 5]) for i in range(0, len(values), 5)]
    at2 = folder / "quake.AT2"
    at2.write_text("\n".join(lines) + "\n")
    return at2, text


def test_a_record_scene_runs_and_both_file_formats_agree(tmp_path):
    at2, text = _write_records(tmp_path)
    def scene(path, **more):
        return load_preset("fig3a").with_params(ground="record", ground_file=str(path),
                                                length_unit=0.01, tower_period=0.5,
                                                transient=0, record=5, **more)
    base = scene(at2)
    a = simulate(base)
    b = simulate(scene(text, ground_units="g"))
    assert len(a.impacts) > 0
    np.testing.assert_allclose(a.final_state, b.final_state, rtol=0, atol=1e-9)
    # twice the scale: another response
    c = simulate(base.with_params(ground_file=str(at2), ground_scale=2.0))
    assert np.max(np.abs(c.final_state - a.final_state)) > 1e-3


def test_a_record_scene_round_trips_through_toml(tmp_path):
    from chaospound.scene import Scene

    at2, _ = _write_records(tmp_path)
    scene = load_preset("fig3a").with_params(ground="record", ground_file=str(at2),
                                             length_unit=0.01, tower_period=0.5)
    again = Scene.from_toml(scene.to_toml())
    assert again == scene
    assert "ground_file" not in load_preset("fig3a").to_toml()  # sine scenes unchanged


def test_record_runs_and_refusals_on_the_command_line(tmp_path, capsys):
    from chaospound.cli import main

    at2, _ = _write_records(tmp_path)
    record = ["--set", "ground=record", "--set", f"ground_file={at2}", "--set",
              "length_unit=0.01", "--set", "tower_period=0.5"]
    assert main(["simulate", "--preset", "fig3a", "--transient", "0", "--record", "3",
                 "--quiet", *record]) == 0
    capsys.readouterr()
    assert main(["classify", "--preset", "fig3a", "--quiet", *record]) == 2
    assert "periodic forcing" in capsys.readouterr().err
    bad = tmp_path / "bad.AT2"
    bad.write_text("header\nheader\nheader\nNPTS=  10, DT= .01 SEC\n 1.0 2.0 x\n")
    assert main(["simulate", "--preset", "fig3a", "--quiet", "--set", "ground=record",
                 "--set", f"ground_file={bad}", "--set", "length_unit=0.01", "--set",
                 "tower_period=0.5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.AT2" in err[0]
    assert main(["simulate", "--preset", "fig3a", "--quiet", "--set", "ground=record"]) == 2



def test_trajectory_samples_that_fall_on_the_record_samples_are_all_stored(tmp_path):
    """Dense samples on a grid that coincides with the record's sample times (where
    the steps land) are each stored once: none skipped where a step ended a
    rounding error short of one (tau / dt then rounds up to the sample's index),
    none repeated, all finite. A 50 s stochastic record at 0.01 s, 100 samples a
    1 s cycle; before the fix 1-2 samples went missing in three of these four runs."""
    spec = {"omega_g": 5.0 * np.pi, "zeta_g": 0.6, "omega_f": 0.5 * np.pi, "zeta_f": 0.6,
            "intensity": 1.0, "dt": 0.01, "duration": 50.0, "seed": 15,
            "envelope": "jennings", "t_rise": 2.0, "t_plateau": 12.0, "decay": 0.2}
    t, a, _ = stochastic.generate(spec)  # SI numbers: the spec is read as is
    a = record.baseline_rest(t, a * (0.35 * 9.80665 / np.max(np.abs(a))))
    path = tmp_path / "quake.txt"
    path.write_text("".join(f"{float(tk)!r} {float(ak)!r}\n" for tk, ak in zip(t, a, strict=True)))
    scene = load_preset("wall").with_params(
        ground="record", ground_file=str(path), ground_units="m/s^2", length_unit=0.01,
        tower_period=0.5, period_ratio=2.0, gap=2.0, beta=17.41, contact_law="hertzdamp",
        transient=0, record=50)
    for law, rtol in (("hertz", 1e-5), ("hertz", 1e-10), ("hertzdamp", 1e-5),
                      ("hertzdamp", 1e-10)):
        run = simulate(scene.with_params(contact_law=law, rtol=rtol, atol=rtol * 1e-3),
                       samples_per_cycle=100)
        times = run.trajectory.time / (2.0 * np.pi / 0.5)
        assert times.size == t.size
        assert np.all(np.isfinite(run.trajectory.state)), (law, rtol)
        np.testing.assert_allclose(times, t, rtol=0.0, atol=1e-12, err_msg=f"{law} {rtol}")
