"""Throughput and memory of the crash-safe store against the 0.1 in-place HDF5 store.

The fig4 scan (1000 points over T/T_Ax in [0.3, 2.0], 40 + 8 cycles, rtol
1e-6) is swept by this checkout and by an older commit (a git worktree made
here), alternating old and new run by run in fresh processes, so that the
machine's drifting load hits both alike. Each run reports the wall time of
``run_sweep`` (pool start, compute, commits and, for the new store, the final
consolidation) and the peak resident set of the sweeping process.

    python benchmarks/bench_store.py [--old-ref da32171] [--rounds 5] [--workers 2]

Writes results/bench_store.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUN = r"""
import json, resource, sys, time
from chaospound.scene import load_preset
from chaospound.sweep import SweepSpec, parse_axis, run_sweep
scene = load_preset("fig4").with_params(rtol=1e-6)
spec = SweepSpec(axes=(parse_axis("period_ratio=0.3:2.0#%(points)d", scene),), classify="paper")
start = time.perf_counter()
run_sweep(scene, spec, sys.argv[1], workers=%(workers)d, progress=False)
wall = time.perf_counter() - start
print(json.dumps({"wall_s": wall,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def run(root: Path, path: Path, points: int, workers: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(root))
    code = RUN % {"points": points, "workers": workers}
    proc = subprocess.run([sys.executable, "-c", code, str(path)], env=env, cwd=root,
                          capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--old-ref", default="da32171", help="the commit to compare against")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--points", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--output", default=str(ROOT / "results" / "bench_store.json"))
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "old"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(old),
                        args.old_ref], check=True)
        try:
            sides = {"old": old, "new": ROOT}
            runs: dict[str, list[dict]] = {"old": [], "new": []}
            for side, root in sides.items():  # warm-up: compile or load the kernels
                run(root, Path(tmp) / f"warm-{side}.h5", 20, args.workers)
            for r in range(args.rounds):
                for side in (("old", "new") if r % 2 == 0 else ("new", "old")):
                    path = Path(tmp) / f"{side}-{r}.h5"
                    runs[side].append(run(sides[side], path, args.points, args.workers))
                    print(f"round {r} {side}: {runs[side][-1]['wall_s']:.2f} s", flush=True)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(old)], check=False)
    ratios = [n["wall_s"] / o["wall_s"] for o, n in zip(runs["old"], runs["new"], strict=True)]
    result = {
        "scene": "fig4", "points": args.points, "workers": args.workers, "rtol": 1e-6,
        "old_ref": args.old_ref, "rounds": args.rounds, "runs": runs,
        "points_per_s": {side: args.points / statistics.median(r["wall_s"] for r in rs)
                         for side, rs in runs.items()},
        "wall_ratio_new_over_old": {"median": statistics.median(ratios), "min": min(ratios),
                                    "max": max(ratios)},
        "peak_rss_mb": {side: max(r["peak_rss_mb"] for r in rs) for side, rs in runs.items()},
        "target": "new points/s within 5 % of old (wall ratio <= 1.05)",
    }
    Path(args.output).write_text(json.dumps(result, indent=2) + "\n")
    pps = result["points_per_s"]
    ratio = result["wall_ratio_new_over_old"]
    print(f"fig4 scan, {args.points} points, {args.workers} workers, {args.rounds} rounds "
          f"interleaved: old {pps['old']:.0f} points/s, new {pps['new']:.0f} points/s; "
          f"wall new/old median {ratio['median']:.3f} (min {ratio['min']:.3f}, "
          f"max {ratio['max']:.3f}); peak RSS old {result['peak_rss_mb']['old']:.0f} MB, "
          f"new {result['peak_rss_mb']['new']:.0f} MB")
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
