"""Cost of the Lyapunov spectrum against the plain trajectory, measured in one run.

The issue's target: the full 12-exponent spectrum (variational equations with
the analytic Jacobian, QR every period) costs at most 15x the plain
trajectory over the same cycles. Both runs start from the same section state
of the scene (after its transient) and integrate the same number of cycles
with the scene's solver; best of ``--repeats``.

    python benchmarks/bench_lyapunov.py [--preset fig3a] [--cycles 200] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from chaospound.dynamics.lyapunov import lyapunov_spectrum
from chaospound.dynamics.system import System, advance
from chaospound.scene import load_preset
from chaospound.simulate import warm_up

ROOT = Path(__file__).resolve().parents[1]


def best_of(repeats: int, fn) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return min(times), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="fig3a")
    parser.add_argument("--cycles", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--output", default=str(ROOT / "results" / "bench_lyapunov.json"))
    args = parser.parse_args()

    system = System.from_scene(load_preset(args.preset))
    warm_up()
    start, _, _ = advance(system, system.initial_state, system.transient, from_time_zero=True)
    n, tangent_transient = system.dim, 20
    total = tangent_transient + args.cycles
    # compile both paths once
    advance(system, start, 1)
    lyapunov_spectrum(system, cycles=10, tangent_transient=0, transient=0, initial_state=start)

    plain_s, (_, _, plain_stats) = best_of(args.repeats, lambda: advance(system, start, total))
    runs = {}
    for k in (1, n):
        wall, spec = best_of(args.repeats, lambda k=k: lyapunov_spectrum(
            system, k=k, cycles=args.cycles, tangent_transient=tangent_transient,
            transient=0, initial_state=start))
        runs[str(k)] = {"wall_s": wall, "ratio": wall / plain_s, "steps": spec.steps,
                        "max_exponent": float(spec.exponents[0]),
                        "max_error": float(spec.errors[0])}
    result = {
        "preset": args.preset, "model": system.model_name, "states": n,
        "cycles": total, "rtol": system.rtol, "plain_wall_s": plain_s,
        "plain_steps": int(plain_stats[0]), "spectra": runs,
        "target_full_ratio": [runs[str(n)]["ratio"], 15.0],
    }
    Path(args.output).write_text(json.dumps(result, indent=2) + "\n")
    print(f"{args.preset} ({system.model_name}, {n} states), {total} cycles at rtol "
          f"{system.rtol:g} from the same section state (best of {args.repeats})")
    print(f"  plain trajectory: {plain_s * 1e3:.1f} ms, {int(plain_stats[0])} steps")
    for k, run in runs.items():
        print(f"  {k:>2} exponent(s): {run['wall_s'] * 1e3:.1f} ms, {run['ratio']:.2f}x the "
              f"plain run, {run['steps']} steps")
    print(f"  target: the full spectrum <= 15x -> {runs[str(n)]['ratio']:.2f}x; "
          f"wrote {args.output}")


if __name__ == "__main__":
    main()
