"""A 50 s accelerogram sampled at 0.01 s on the 12-state towers model (issue 15).

The record is synthetic, made by this script (nothing is downloaded): one
realisation of the Kanai-Tajimi / Clough-Penzien process of
:mod:`chaospound.physics.ground.stochastic` (omega_g = 5 pi rad/s, zeta_g = 0.6,
omega_f = 0.5 pi rad/s, zeta_f = 0.6, Jennings envelope 2 / 12 / 0.2 s^-1,
seed 15), scaled to a PGA of 0.35 g, baseline-corrected to end at rest
(:func:`chaospound.physics.ground.record.baseline_rest`, so the engine's own
correction is a no-op) and written as a two-column text file (time [s],
acceleration [m/s^2]) in a temporary folder. The scene is the preset ``fig3a``
(two eccentric towers, 12 states) with ``ground = "record"`` on that file,
``length_unit = 0.05`` m, ``tower_period = 1`` s and ``period_ratio = 1`` (so a
section "cycle" is 1 s and ``record = 50`` covers the 50 s), run with the laws
``hertz`` and ``hertzdamp`` (e = 0.65) at the preset's dopri5, rtol 1e-5.

Two times per run: the engine's (``Simulation.stats.wall_s``: the compiled
integration of the 50 s) and ``simulate(scene)`` end to end, which also reads
the text file and integrates the record into its block (pure Python, done on
every call: it dominates).

Timing: warm engines (the first run of each law compiles or loads them and
is not timed), then ``--rounds`` rounds, each running every law once in turn
(interleaved, so the load of the shared machine falls on both alike); the
best and the median per law, and the hertzdamp / hertz ratio per round.

Usage::

    PYTHONPATH=. python benchmarks/bench_record.py [--rounds 21]
        [--output results/bench_record.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from chaospound.physics.ground import record, stochastic
from chaospound.scene import load_preset
from chaospound.simulate import simulate

ROOT = Path(__file__).resolve().parent.parent
G = 9.80665  #: m/s^2
DURATION = 50.0  #: s
DT = 0.01  #: s
PGA = 0.35  #: g
SPEC_SI = {"omega_g": 5.0 * np.pi, "zeta_g": 0.6, "omega_f": 0.5 * np.pi, "zeta_f": 0.6,
           "intensity": 1.0, "dt": DT, "duration": DURATION, "seed": 15,
           "envelope": "jennings", "t_rise": 2.0, "t_plateau": 12.0, "decay": 0.2}
LAWS = ("hertz", "hertzdamp")


def synthetic_record(folder: Path, pga_g: float = PGA) -> tuple[Path, np.ndarray, np.ndarray]:
    """Write the benchmark's accelerogram into ``folder``.

    Returns
    -------
    path, t, a : Path, ndarray, ndarray
        The text file (time [s], acceleration [m/s^2]) and its samples, the
        values exactly as written (``repr`` round-trips a float64).
    """
    # the spec is in SI; model_parameters with A_g = 1 m and omega = 1 rad/s is the identity
    t, a, _ = stochastic.generate(stochastic.model_parameters(SPEC_SI, 1.0, 1.0))
    a = record.baseline_rest(t, a * (pga_g * G / np.max(np.abs(a))))
    path = Path(folder) / "synthetic_50s.txt"
    with path.open("w") as out:
        out.write("# synthetic accelerogram (benchmarks/bench_record.py): time [s], a [m/s^2]\n")
        for tk, ak in zip(t, a, strict=True):
            out.write(f"{float(tk)!r} {float(ak)!r}\n")
    back = np.loadtxt(path)
    return path, back[:, 0], back[:, 1]


def scene_for(path: Path, law: str):
    """The fig3a towers on the record, under ``law``."""
    return load_preset("fig3a").with_params(
        ground="record", ground_file=str(path), ground_units="m/s^2", length_unit=0.05,
        tower_period=1.0, period_ratio=1.0, contact_law=law, restitution=0.65,
        transient=0, record=int(round(DURATION)))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--output", type=Path, default=ROOT / "results" / "bench_record.json")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        path, t, a = synthetic_record(Path(folder))
        scenes = {law: scene_for(path, law) for law in LAWS}
        first = {}
        for law, scene in scenes.items():  # compile or load the engines; not timed
            start = time.perf_counter()
            first[law] = simulate(scene)
            first[law] = (first[law], time.perf_counter() - start)
        times = {law: [] for law in LAWS}
        engine = {law: [] for law in LAWS}
        runs = {}
        for _ in range(args.rounds):
            for law, scene in scenes.items():
                start = time.perf_counter()
                runs[law] = simulate(scene)
                times[law].append(time.perf_counter() - start)
                engine[law].append(runs[law].stats.wall_s)
    rows = {}
    for law in LAWS:
        run = runs[law]
        same = run.final_state.tobytes() == first[law][0].final_state.tobytes()
        rows[law] = {
            "model": run.model, "states": len(run.state_names),
            "end_to_end_best_s": min(times[law]),
            "end_to_end_median_s": float(np.median(times[law])),
            "end_to_end_max_s": max(times[law]), "first_run_s": first[law][1],
            "engine_best_s": min(engine[law]), "engine_median_s": float(np.median(engine[law])),
            "engine_max_s": max(engine[law]),
            "steps": run.stats.steps, "rejected": run.stats.rejected,
            "rhs_evals": run.stats.rhs_evals, "events": run.stats.events,
            "impacts": len(run.impacts),
            "peak_impact_force_model": float(np.max(run.impacts.peak_force, initial=0.0)),
            "engine_us_per_step_best": min(engine[law]) / run.stats.steps * 1e6,
            "repeatable_bitwise": bool(same),
        }
    ratio = np.array(engine["hertzdamp"]) / np.array(engine["hertz"])
    print(f"50 s record at 0.01 s ({t.size} samples, PGA {PGA} g), fig3a towers, "
          f"dopri5 rtol 1e-5, {args.rounds} interleaved rounds")
    for law, row in rows.items():
        print(f"{law:10s} {row['model']} ({row['states']} states): engine best "
              f"{row['engine_best_s'] * 1e3:6.2f} ms, "
              f"median {row['engine_median_s'] * 1e3:6.2f} ms "
              f"({row['engine_us_per_step_best']:.2f} us/step); simulate() end to end best "
              f"{row['end_to_end_best_s'] * 1e3:6.1f} ms, median "
              f"{row['end_to_end_median_s'] * 1e3:6.1f} ms; {row['steps']} steps "
              f"({row['rejected']} rejected), {row['impacts']} impacts")
    print(f"engine time hertzdamp / hertz per round: median {np.median(ratio):.3f} "
          f"(min {ratio.min():.3f}, max {ratio.max():.3f})")
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps({
        "record": {"duration_s": DURATION, "dt_s": DT, "samples": int(t.size), "pga_g": PGA,
                   "stochastic_spec_si": SPEC_SI, "scaled_and_baseline_corrected": True},
        "scene": "fig3a, ground=record, length_unit=0.05 m, tower_period=1 s, period_ratio=1, "
                 "restitution=0.65, transient=0, record=50",
        "rounds": args.rounds, "laws": rows,
        "ratio_hertzdamp_over_hertz": {"median": float(np.median(ratio)),
                                       "min": float(ratio.min()), "max": float(ratio.max())},
        "machine": f"{platform.machine()}, Python {platform.python_version()}, 2 shared cores",
        "date": time.strftime("%Y-%m-%d"),
        "command": "PYTHONPATH=. python benchmarks/bench_record.py"}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
