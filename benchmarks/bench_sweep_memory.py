"""Memory of a long sweep: 1e4 and 1e5 points streamed to HDF5, peak resident sets.

The issue's target: memory stays bounded while a 1e5-point sweep streams to
disk. Each sweep runs in a fresh Python process (the "wall" preset with 1 + 2
cycles per point, so that the 1e5 points take about a minute on 2 workers);
the peak resident set of that process and of its largest worker are read
from ``getrusage``. Results kept in memory would cost over 2 kB a point
(200 MB at 1e5 points).

    python benchmarks/bench_sweep_memory.py [--points 10000 100000] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, resource, sys, time
from chaospound.scene import load_preset
from chaospound.store import open_sweep
from chaospound.sweep import SweepSpec, parse_axis, run_sweep
points, workers, path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
scene = load_preset("wall").with_params(transient=1, record=2)
spec = SweepSpec(axes=(parse_axis(f"period_ratio=0.3:2.0#{points}", scene),), classify="paper")
start = time.perf_counter()
run_sweep(scene, spec, path, workers=workers, progress=False)
wall = time.perf_counter() - start
# peaks of the sweep itself, read before the check below loads the file
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
worker_peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
store = open_sweep(path)
print(json.dumps({
    "points": points, "workers": workers, "wall_s": wall,
    "done": int((store.array("status") == 1).sum()),
    "impacts": int(store.array("impact_count").sum()),
    "peak_rss_mb": peak, "peak_worker_rss_mb": worker_peak,
}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, nargs="+", default=[10_000, 100_000])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--output", default=str(ROOT / "results" / "bench_sweep_memory.json"))
    args = parser.parse_args()
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for points in args.points:
            path = Path(tmp) / f"{points}.h5"
            start = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", CHILD, str(points), str(args.workers),
                                  str(path)], capture_output=True, text=True, check=True)
            run = json.loads(out.stdout.strip().splitlines()[-1])
            run["file_mb"] = path.stat().st_size / 2**20
            run["process_s"] = time.perf_counter() - start
            runs.append(run)
            print(f"{points:>7} points: {run['wall_s']:.1f} s, {run['done']} done, "
                  f"{run['impacts']} impacts, file {run['file_mb']:.1f} MB, peak RSS "
                  f"{run['peak_rss_mb']:.0f} MB (largest worker "
                  f"{run['peak_worker_rss_mb']:.0f} MB)")
    growth = runs[-1]["peak_rss_mb"] - runs[0]["peak_rss_mb"]
    result = {"scene": "wall, 1 + 2 cycles per point", "runs": runs,
              "peak_rss_growth_mb": growth}
    Path(args.output).write_text(json.dumps(result, indent=2) + "\n")
    print(f"peak RSS grows by {growth:.1f} MB from {runs[0]['points']} to {runs[-1]['points']} "
          f"points; wrote {args.output}")


if __name__ == "__main__":
    main()
