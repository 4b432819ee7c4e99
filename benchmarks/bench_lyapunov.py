"""Cost of the Lyapunov spectrum against the plain trajectory, measured in one run.

The gate of issue 14: the full 12-exponent spectrum (variational equations
with the analytic Jacobian, QR every period) costs at most 8x the plain
trajectory over the same cycles. Both runs start from the same section state
of the scene (after its transient) and integrate the same number of cycles
with the scene's solver, through the one engine entry
(:func:`chaospound.dynamics.system.evolve`); the runs of the three kinds are
interleaved, round after round, and each kind's best of ``--repeats`` rounds
is kept, in wall time and in the thread's CPU time (on a shared machine the
wall time of the longer run is the more likely to include time spent waiting
for a core, which the CPU time excludes).

    python benchmarks/bench_lyapunov.py [--preset fig3a] [--cycles 200] [--repeats 7]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from chaospound.dynamics.lyapunov import lyapunov_spectrum
from chaospound.dynamics.system import System, evolve
from chaospound.scene import load_preset
from chaospound.simulate import warm_up

ROOT = Path(__file__).resolve().parents[1]


def timed(fn) -> tuple[float, float, object]:
    """(wall time, this thread's CPU time, result) of one call."""
    start, cpu = time.perf_counter(), time.thread_time()
    out = fn()
    return time.perf_counter() - start, time.thread_time() - cpu, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="fig3a")
    parser.add_argument("--cycles", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--output", default=str(ROOT / "results" / "bench_lyapunov.json"))
    args = parser.parse_args()

    system = System.from_scene(load_preset(args.preset))
    warm_up()
    start = evolve(system, cycles=system.transient).state
    n, tangent_transient = system.dim, 20
    total = tangent_transient + args.cycles
    # compile both paths once
    evolve(system, start)
    lyapunov_spectrum(system, cycles=10, tangent_transient=0, transient=0, initial_state=start)

    kinds = {"plain": lambda: evolve(system, start, cycles=total)}
    for k in (1, n):
        kinds[str(k)] = lambda k=k: lyapunov_spectrum(
            system, k=k, cycles=args.cycles, tangent_transient=tangent_transient,
            transient=0, initial_state=start)
    best = {kind: [float("inf"), float("inf"), None] for kind in kinds}
    for _ in range(args.repeats):
        for kind, fn in kinds.items():
            wall, cpu, out = timed(fn)
            best[kind][2] = out
            best[kind][0] = min(best[kind][0], wall)
            best[kind][1] = min(best[kind][1], cpu)
    plain_s, plain_cpu, plain_run = best["plain"]
    plain_stats = plain_run.stats
    runs = {}
    for k in (1, n):
        wall, cpu, spec = best[str(k)]
        runs[str(k)] = {"wall_s": wall, "ratio": wall / plain_s, "cpu_s": cpu,
                        "cpu_ratio": cpu / plain_cpu, "steps": spec.steps,
                        "max_exponent": float(spec.exponents[0]),
                        "max_error": float(spec.errors[0])}
    result = {
        "preset": args.preset, "model": system.model_name, "states": n,
        "cycles": total, "rtol": system.rtol, "plain_wall_s": plain_s,
        "plain_cpu_s": plain_cpu,
        "plain_steps": int(plain_stats[0]), "spectra": runs,
        "target_full_ratio": [runs[str(n)]["ratio"], 8.0],
        "target_full_cpu_ratio": [runs[str(n)]["cpu_ratio"], 8.0],
        "command": f"python benchmarks/bench_lyapunov.py --preset {args.preset} "
                   f"--cycles {args.cycles} --repeats {args.repeats}",
    }
    Path(args.output).write_text(json.dumps(result, indent=2) + "\n")
    print(f"{args.preset} ({system.model_name}, {n} states), {total} cycles at rtol "
          f"{system.rtol:g} from the same section state (best of {args.repeats})")
    print(f"  plain trajectory: {plain_s * 1e3:.1f} ms wall, {plain_cpu * 1e3:.1f} ms CPU, "
          f"{int(plain_stats[0])} steps")
    for k, run in runs.items():
        print(f"  {k:>2} exponent(s): {run['wall_s'] * 1e3:.1f} ms wall ({run['ratio']:.2f}x the "
              f"plain run), {run['cpu_s'] * 1e3:.1f} ms CPU ({run['cpu_ratio']:.2f}x), "
              f"{run['steps']} steps")
    print(f"  target: the full spectrum <= 8x -> {runs[str(n)]['ratio']:.2f}x wall, "
          f"{runs[str(n)]['cpu_ratio']:.2f}x CPU; wrote {args.output}")


if __name__ == "__main__":
    main()
