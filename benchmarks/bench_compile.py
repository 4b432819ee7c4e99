"""Cold compile of the built-in engines, one tree against another, in one run.

    python benchmarks/bench_compile.py --old /path/to/old/tree --new . [--rounds 3]
        [--output results/bench_compile.json]

Each round runs one child process per tree (order swapped every round), each on
empty caches (a fresh ``NUMBA_CACHE_DIR`` and ``CHAOSPOUND_CACHE_DIR``). A
child composes the engines of the four pounding models (Hertz, sine, DOPRI5:
what a first run of the presets compiles) and warms each up, then prints its
CPU seconds (user + system, whole process: imports, generation, compilation)
and its wall seconds. Both trees must use the engine API of
:mod:`chaospound.engine.compose` (commits since the redesign, issue 14). The
result is the median CPU time of each tree and the median ratio new/old.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

CHILD = """
import resource, sys, time
started = time.perf_counter()
import chaospound
assert chaospound.__file__.startswith(sys.argv[1]), 'wrong tree'
from chaospound.dynamics.system import warm_up
from chaospound.engine.compose import Composition, engine_for
for model in ("wall", "pair", "tower-wall", "towers"):
    warm_up(engine_for(Composition(model=model)))
usage = resource.getrusage(resource.RUSAGE_SELF)
print(usage.ru_utime + usage.ru_stime, time.perf_counter() - started)
"""


def child(tree: Path) -> tuple[float, float]:
    """(CPU s, wall s) of a cold compile in ``tree``."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_CACHE_DIR=f"{cache}/numba",
                   CHAOSPOUND_CACHE_DIR=f"{cache}/chaospound")
        out = subprocess.run([sys.executable, "-c", CHILD, str(tree)], env=env,
                             capture_output=True, text=True, check=True, cwd=tree).stdout
    cpu, wall = out.split()
    return float(cpu), float(wall)


def commit(tree: Path) -> str:
    """The tree's git commit (short), or "" outside git."""
    out = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                         capture_output=True, text=True)
    return out.stdout.strip()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True)
    parser.add_argument("--new", type=Path, default=Path("."))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--output", type=Path)
    args = parser.parse_args(argv)
    old, new = args.old.resolve(), args.new.resolve()
    ratios, cpu_old, cpu_new = [], [], []
    for r in range(args.rounds):
        order = (old, new) if r % 2 == 0 else (new, old)
        got = {tree: child(tree) for tree in order}
        (c_old, w_old), (c_new, w_new) = got[old], got[new]
        cpu_old.append(c_old)
        cpu_new.append(c_new)
        ratios.append(c_new / c_old)
        print(f"round {r + 1:2d}: old {c_old:6.2f} s CPU ({w_old:6.2f} s wall), new "
              f"{c_new:6.2f} s CPU ({w_new:6.2f} s wall), ratio {c_new / c_old:.3f}",
              flush=True)
    result = {"engines": ["wall", "pair", "tower-wall", "towers"], "rounds": args.rounds,
              "old_cpu_s_median": float(np.median(cpu_old)),
              "new_cpu_s_median": float(np.median(cpu_new)),
              "ratio_median": float(np.median(ratios)),
              "old": commit(old) or str(old), "new": commit(new) or str(new)}
    print(f"median CPU old {result['old_cpu_s_median']:.2f} s, new "
          f"{result['new_cpu_s_median']:.2f} s, ratio new/old {result['ratio_median']:.3f}")
    if args.output:
        args.output.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
