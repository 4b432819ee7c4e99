"""Sweep throughput: the fig4 scan with 1 and 2 local workers, measured in one run.

The issue's target: the fig4 scan at 1000 points over T/T_Ax in [0.3, 2.0]
(40 + 8 cycles, rtol 1e-6) at >= 200 points per second with 2 workers and a
speed-up from 1 to 2 workers >= 1.8x. Both runs write a real HDF5 store (the
files are compared: they must be identical apart from timing fields).

    python benchmarks/bench_sweep.py [--points 1000] [--repeats 2]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from chaospound.scene import load_preset
from chaospound.simulate import warm_up
from chaospound.store import open_sweep
from chaospound.sweep import SweepSpec, parse_axis, run_sweep

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=2, help="best of N per worker count")
    parser.add_argument("--output", default=str(ROOT / "results" / "bench_sweep.json"))
    args = parser.parse_args()

    scene = load_preset("fig4").with_params(rtol=1e-6)
    spec = SweepSpec(axes=(parse_axis(f"period_ratio=0.3:2.0#{args.points}", scene),),
                     classify="paper")
    warm_up()
    result = {"scene": "fig4", "points": args.points, "rtol": 1e-6, "cycles": "40 + 8",
              "cpus": os.cpu_count(), "runs": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for workers in (1, 2):
            best = np.inf
            for r in range(args.repeats):
                path = Path(tmp) / f"w{workers}-{r}.h5"
                start = time.perf_counter()
                run_sweep(scene, spec, path, workers=workers, progress=False)
                best = min(best, time.perf_counter() - start)
            result["runs"][str(workers)] = {"wall_s": best, "points_per_s": args.points / best}
        a, b = open_sweep(Path(tmp) / "w1-0.h5"), open_sweep(Path(tmp) / "w2-0.h5")
        result["identical_regimes"] = bool(np.array_equal(a.array("regime"),
                                                          b.array("regime")))
    one, two = result["runs"]["1"], result["runs"]["2"]
    result["speedup"] = one["wall_s"] / two["wall_s"]
    result["targets"] = {"points_per_s_2_workers": [two["points_per_s"], 200.0],
                         "speedup_1_to_2": [result["speedup"], 1.8]}
    Path(args.output).write_text(json.dumps(result, indent=2) + "\n")
    print(f"fig4 scan, {args.points} points, 40 + 8 cycles, rtol 1e-6 (best of {args.repeats})")
    for w in ("1", "2"):
        run = result["runs"][w]
        print(f"  {w} worker(s): {run['wall_s']:.2f} s, {run['points_per_s']:.0f} points/s")
    print(f"  speed-up 1 -> 2 workers: {result['speedup']:.2f}x (target >= 1.8x); "
          f"2 workers: {two['points_per_s']:.0f} points/s (target >= 200)")
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
