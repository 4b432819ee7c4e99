"""The test suite of one tree against another's, on the same tests, in one run.

    python benchmarks/bench_suite.py --old /path/to/old/tree --new . [--rounds 2]
        [--output results/bench_suite.json]

Issue 14's gate asks that the test suite take no longer than it did before the
redesign. The suite has grown since (1541 tests against 1102 at 3fe32a0), so the
comparison that means something is like for like: the new tree runs only the
tests whose node ids the old tree collects (every old test still exists under its
name), with its own pytest options (two xdist workers); the old tree runs its
whole suite with its own options (serial, and without pytest-xdist, which its
test dependencies did not include: :data:`OLD_OPTIONS`). Both start from empty
caches, as on a fresh clone: the numba cache files (``*.nbi``, ``*.nbc``) under each tree are
deleted before its run, and ``CHAOSPOUND_CACHE_DIR`` is a fresh directory.
(``NUMBA_CACHE_DIR`` stays unset: the old tree's cache tests assume ``__pycache__``.)

Each round runs both (order swapped every round, so drift and load fall on both
alike) and records wall seconds, the children's CPU seconds (user + system) and
the number of tests passed. The result is the median wall ratio new/old.
``--warm`` times instead a second run of each tree on the caches its first run
filled (docs/design/engine.md's gate, step 5).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_compile import commit

OLD_OPTIONS = ["-p", "no:xdist"]  #: the old tree's pytest: no xdist, as in its CI
#: a pytest plugin that keeps the tests named in KEEP_IDS (one node id per line)
KEEP_PLUGIN = """
import os

_KEEP = set(open(os.environ["KEEP_IDS"]).read().splitlines())


def pytest_collection_modifyitems(config, items):
    dropped = [item for item in items if item.nodeid not in _KEEP]
    items[:] = [item for item in items if item.nodeid in _KEEP]
    config.hook.pytest_deselected(items=dropped)
"""


def collect(tree: Path, options: list[str]) -> list[str]:
    """The node ids pytest collects in ``tree`` (with ``options``, serial)."""
    out = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q",
                          "-p", "no:cacheprovider", *options], cwd=tree, capture_output=True,
                         text=True, env=dict(os.environ, PYTHONPATH=str(tree)), check=True)
    return [line for line in out.stdout.splitlines() if "::" in line]


def run_suite(tree: Path, extra: list[str], env: dict[str, str], warm: bool = False) -> dict:
    """One run of pytest in ``tree`` from empty caches (``warm``: after an untimed run
    that fills them): wall and CPU seconds, tests passed."""
    for pattern in ("*.nbi", "*.nbc"):
        for cached in tree.rglob(pattern):
            cached.unlink()
    with tempfile.TemporaryDirectory() as caches:
        env = dict(env, CHAOSPOUND_CACHE_DIR=caches)
        env.pop("NUMBA_CACHE_DIR", None)
        if warm:
            _pytest(tree, extra, env)
        return _pytest(tree, extra, env)


def _pytest(tree: Path, extra: list[str], env: dict[str, str]) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           *extra], cwd=tree, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    last = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else done.stderr[-300:]
    if done.returncode != 0:
        failed = [line for line in done.stdout.splitlines() if line.startswith("FAILED")]
        raise SystemExit(f"{tree}: pytest failed: {last}\n" + "\n".join(failed))
    passed = int(last.split(" passed")[0].split()[-1])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "passed": passed}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True)
    parser.add_argument("--new", type=Path, default=Path("."))
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--warm", action="store_true",
                        help="time a second run on the caches the first filled")
    parser.add_argument("--output", type=Path)
    args = parser.parse_args(argv)
    # a background job of a shell without job control starts with SIGINT ignored, and
    # its children inherit that: both suites' Ctrl-C tests would then wait in vain
    signal.signal(signal.SIGINT, signal.default_int_handler)
    old, new = args.old.resolve(), args.new.resolve()
    old_ids = collect(old, OLD_OPTIONS)
    new_ids = set(collect(new, ["-n", "0"]))
    missing = [i for i in old_ids if i not in new_ids]
    if missing:
        raise SystemExit(f"{len(missing)} old tests are missing in the new tree, "
                         f"e.g. {missing[0]}")
    with tempfile.TemporaryDirectory() as plugin_dir:
        Path(plugin_dir, "keep_ids.py").write_text(KEEP_PLUGIN)
        ids = Path(plugin_dir, "ids.txt")
        ids.write_text("\n".join(old_ids) + "\n")
        runs = {
            old: (OLD_OPTIONS, dict(os.environ, PYTHONPATH=str(old))),
            new: (["-p", "keep_ids"], dict(os.environ, PYTHONPATH=f"{new}{os.pathsep}"
                                           f"{plugin_dir}", KEEP_IDS=str(ids))),
        }
        rounds = []
        for r in range(args.rounds):
            order = (old, new) if r % 2 == 0 else (new, old)
            got = {tree: run_suite(tree, *runs[tree], args.warm) for tree in order}
            rounds.append({"old": got[old], "new": got[new],
                           "ratio": got[new]["wall_s"] / got[old]["wall_s"]})
            print(f"round {r + 1}: old {got[old]['wall_s']:.0f} s "
                  f"({got[old]['passed']} passed), new {got[new]['wall_s']:.0f} s "
                  f"({got[new]['passed']} passed): {rounds[-1]['ratio']:.3f}", flush=True)
    ratios = [r["ratio"] for r in rounds]
    summary = {
        "command": " ".join(["python benchmarks/bench_suite.py"] + sys.argv[1:]),
        "old": commit(old) or str(old),
        "new": commit(new) or str(new),
        "tests": len(old_ids),
        "caches": "warm" if args.warm else "cold",
        "cpus": os.cpu_count(),
        "rounds": rounds,
        "median_wall_ratio": float(np.median(ratios)),
        "median_cpu_ratio": float(np.median([r["new"]["cpu_s"] / r["old"]["cpu_s"]
                                             for r in rounds])),
    }
    print(f"median wall ratio new/old {summary['median_wall_ratio']:.3f}, "
          f"CPU ratio {summary['median_cpu_ratio']:.3f}")
    if args.output:
        args.output.write_text(json.dumps(summary, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
