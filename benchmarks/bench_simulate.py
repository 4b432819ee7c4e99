"""Speed of one steady fig3a run against scipy's solve_ivp (RK45), on this machine.

Runs :func:`chaospound.bench.run_benchmark` on the preset fig3a (40 + 8
cycles, dopri5, rtol 1e-6): chaospound's ``simulate`` against
``solve_ivp(method="RK45")`` with a pure-Python and with a numba right-hand
side over the same span and tolerances, plus ``chaospound simulate --preset
fig3a`` end to end in a subprocess (warm numba cache). Prints the table and
writes every number to ``results/bench_simulate.json``.

Usage::

    python benchmarks/bench_simulate.py [--preset fig3a] [--repeats 10] [--output PATH]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from chaospound.bench import format_benchmark, run_benchmark
from chaospound.cli import write_json_file
from chaospound.scene import load_preset

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUTPUT = ROOT / "results" / "bench_simulate.json"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="fig3a", help="scene (default fig3a)")
    parser.add_argument("--repeats", type=int, default=10,
                        help="interleaved timing rounds (best of each run counts)")
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT), help="JSON file written")
    parser.add_argument("--rtol", type=float, default=1e-6,
                        help="rtol (default 1e-6, the issue's setting; atol = 1e-3 rtol)")
    args = parser.parse_args()

    scene = load_preset(args.preset).with_params(rtol=args.rtol)
    result = run_benchmark(scene, repeats=args.repeats)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    write_json_file(result, args.output, overwrite=True)
    print(format_benchmark(result), end="")
    print(f"\nwrote {args.output}")


if __name__ == "__main__":
    main()
