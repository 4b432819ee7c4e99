"""Cost of one ground-motion evaluation, per module, inside a compiled loop.

What the engine pays per Runge-Kutta stage for ``u_g, u_g'``: ``at(t)`` at
increasing times (sine: two library calls; record: an O(1) interval guess and a
cubic), the carried-state path ``at_anchor(shifted(c, h))`` that DOPRI5 uses,
and building the block (reading plus exact integration) of a 50 s record at
0.005 s (10 001 samples).

    python benchmarks/bench_ground.py [--output results/bench_ground.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from numba import njit

from chaospound.physics.ground import none, record, sine, stochastic

N_CALLS = 2_000_000


def timed_loop(module):
    at, anchor, shifted, at_anchor = module.at, module.anchor, module.shifted, module.at_anchor

    @njit
    def direct(p, base, t0, h, n):
        total = 0.0
        for k in range(n):
            u, v = at(t0 + k * h, p, base)
            total += u + v
        return total

    @njit
    def carried(p, base, t0, h, n):
        total = 0.0
        c0, c1 = anchor(t0, p, base)
        for k in range(n):
            d0, d1 = shifted(c0, c1, (k % 7) * h, p, base)
            u, v = at_anchor(d0, d1, p, base)
            total += u + v
            if k % 7 == 6:
                c0, c1 = shifted(c0, c1, 7 * h, p, base)
        return total

    return direct, carried


def best_ns(function, args, repeats: int = 5) -> float:
    function(*args[:-1], 10)  # compile
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        function(*args)
        best = min(best, time.perf_counter() - start)
    return best / args[-1] * 1e9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=None)
    options = parser.parse_args()
    dt = 0.005 * 2.0 * np.pi  # 0.005 s with omega_Ax = 2 pi rad/s
    times = np.arange(10_001) * dt
    accel = np.random.default_rng(0).normal(size=times.size)
    start = time.perf_counter()
    record_block = record.block_from_samples(times, accel)
    build_s = time.perf_counter() - start
    stochastic_spec = {"omega_g": 2.5, "zeta_g": 0.6, "omega_f": 0.25, "zeta_f": 0.6,
                       "intensity": 1.0, "dt": dt, "duration": times[-1], "seed": 1,
                       "envelope": "jennings", "t_rise": 10.0, "t_plateau": 100.0,
                       "decay": 0.05}
    stochastic.block({**stochastic_spec, "duration": 10 * dt})  # load the recursion kernel
    start = time.perf_counter()
    stochastic.block(stochastic_spec)
    stochastic_s = time.perf_counter() - start
    jitter = np.cumsum(np.random.default_rng(1).uniform(0.5, 1.5, times.size)) * dt
    cases = {
        "sine": (sine, sine.block({"period_ratio": 0.8})),
        "none": (none, none.block({})),
        "record (uniform)": (record, record_block),
        "record (non-uniform)": (record, record.block_from_samples(jitter, accel)),
    }
    h = 0.7 * dt / 7.0  # steps a little shorter than the samples, as with landing on kinks
    results = {}
    for name, (module, block) in cases.items():
        direct, carried = timed_loop(module)
        args = (block, 0, 0.0, h, N_CALLS)
        results[name] = {"at_ns": best_ns(direct, args), "carried_ns": best_ns(carried, args)}
        print(f"{name:22s} at: {results[name]['at_ns']:6.2f} ns/call   "
              f"at_anchor(shifted): {results[name]['carried_ns']:6.2f} ns/call")
    results["record_block_10001_samples_s"] = build_s
    results["stochastic_block_10001_samples_s"] = stochastic_s
    print(f"record block (10 001 samples, baseline + exact integration): {build_s * 1e3:.1f} ms")
    print(f"stochastic block (10 001 samples, Jennings envelope): {stochastic_s * 1e3:.1f} ms")
    if options.output is not None:
        options.output.write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
