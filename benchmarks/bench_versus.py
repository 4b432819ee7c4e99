"""Per-step cost of one commit against another, side by side in one run.

    python benchmarks/bench_versus.py --old /path/to/old/tree --new . [--preset fig3a]
        [--rounds 21] [--output results/bench_versus.json]

Each round runs one child process per tree (order swapped every round, so drift
and load fall on both alike). A child loads the tree's package, warms the
engine, runs ``simulate(preset)`` five times and prints the best kernel time
(``stats.wall_s``, which excludes Python set-up) divided by the accepted steps.
Both trees must take the same steps (the same work): the script checks it. The
result is the median ratio new/old with its quartiles.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

CHILD = """
import sys
from chaospound import load_preset, simulate
assert __import__('chaospound').__file__.startswith(sys.argv[1]), 'wrong tree'
scene = load_preset(sys.argv[2])
simulate(scene, transient=2, record=1)
best = min((simulate(scene) for _ in range(5)), key=lambda s: s.stats.wall_s)
print(best.stats.wall_s / best.stats.steps, best.stats.steps)
"""


def child(tree: Path, preset: str) -> tuple[float, int]:
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run([sys.executable, "-c", CHILD, str(tree), preset], env=env,
                         capture_output=True, text=True, check=True, cwd=tree).stdout.split()
    return float(out[0]), int(out[1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True)
    parser.add_argument("--new", type=Path, default=Path("."))
    parser.add_argument("--preset", default="fig3a")
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--output", type=Path)
    args = parser.parse_args(argv)
    old, new = args.old.resolve(), args.new.resolve()
    child(old, args.preset)  # compile both outside the timing
    child(new, args.preset)
    ratios, per_old, per_new = [], [], []
    for r in range(args.rounds):
        order = (old, new) if r % 2 == 0 else (new, old)
        got = {tree: child(tree, args.preset) for tree in order}
        (t_old, s_old), (t_new, s_new) = got[old], got[new]
        if s_old != s_new:
            raise SystemExit(f"different work: {s_old} steps (old) against {s_new} (new)")
        per_old.append(t_old)
        per_new.append(t_new)
        ratios.append(t_new / t_old)
        print(f"round {r + 1:2d}: old {t_old * 1e9:7.1f} ns/step, new {t_new * 1e9:7.1f} "
              f"ns/step, ratio {t_new / t_old:.3f}", flush=True)
    q1, med, q3 = np.percentile(ratios, [25, 50, 75])
    result = {"preset": args.preset, "rounds": args.rounds, "steps": s_new,
              "old_ns_per_step_median": float(np.median(per_old)) * 1e9,
              "new_ns_per_step_median": float(np.median(per_new)) * 1e9,
              "ratio_median": float(med), "ratio_q1": float(q1), "ratio_q3": float(q3),
              "old": str(old), "new": str(new)}
    print(f"median ratio new/old {med:.3f} (quartiles {q1:.3f} .. {q3:.3f})")
    if args.output:
        args.output.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
