"""Cost of one call of each contact law's line kernels (issue 15).

Times ``line_force`` (what the right-hand side calls at every stage in
contact) and ``line_gradient`` (the Jacobian, tangent runs) of every law in
:data:`chaospound.engine.compose.LAWS`, called from a jitted loop over 2^16
precomputed contact states, in two regimes: a corner contact (one end
penetrating, the case of torsional impacts) and a face contact (both ends
penetrating, skewed or nearly parallel). The rates are drawn of both signs, so
jankowski's approach/restitution split and kelvin-voigt's no-pull clip are
exercised. Each figure is the median over ``--repeats`` timed passes, in ns
per call; the Hertz law is the reference.

Usage::

    PYTHONPATH=. python benchmarks/bench_contact_laws.py [--repeats 7]
        [--output results/bench_contact_laws.json]
"""

from __future__ import annotations

import argparse
import importlib
import json
import platform
import time
from pathlib import Path

import numpy as np
from numba import njit

from chaospound.engine.compose import LAWS
from chaospound.physics.contact import hertz, hertzdamp, hunt_crossley, jankowski, kelvin_voigt
from chaospound.physics.contact import linear as linear_law

ROOT = Path(__file__).resolve().parent.parent
N = 1 << 16
HALF = 50.0
M_EFF = 1.0 / 3.25

BLOCKS = {
    "hertz": (hertz, lambda: hertz.block(beta=1000.0)),
    "linear": (linear_law, lambda: linear_law.block(k=100.0)),
    "kelvin-voigt": (kelvin_voigt, lambda: kelvin_voigt.block(0.65, k=100.0, m_eff=M_EFF)),
    "kelvin-voigt no-pull": (kelvin_voigt, lambda: kelvin_voigt.block(
        0.65, k=100.0, m_eff=M_EFF, no_pull=True)),
    "hertzdamp": (hertzdamp, lambda: hertzdamp.block(0.65, beta=1000.0)),
    "hunt-crossley": (hunt_crossley, lambda: hunt_crossley.block(0.65, beta=1000.0)),
    "jankowski": (jankowski, lambda: jankowski.block(0.65, beta=1000.0, m_eff=M_EFF)),
}


def _loops(module):
    force = module.line_force
    gradient = module.line_gradient

    @njit
    def force_loop(p, dc, sl, rc, rs):
        acc = 0.0
        for i in range(dc.size):
            f, m, _, _ = force(p, 0, dc[i], sl[i], rc[i], rs[i], HALF)
            acc += f + m
        return acc

    @njit
    def gradient_loop(p, dc, sl, rc, rs):
        acc = 0.0
        for i in range(dc.size):
            d_lo = dc[i] - sl[i] * HALF
            d_hi = dc[i] + sl[i] * HALF
            g = gradient(p, 0, d_lo, d_hi, rc[i] - rs[i] * HALF, rc[i] + rs[i] * HALF, HALF)
            acc += g[0] + g[1] + g[2] + g[3]
        return acc

    return force_loop, gradient_loop


def _states(regime: str, rng: np.random.Generator):
    mean = 10.0 ** rng.uniform(-3, -1, N)
    if regime == "corner":
        d_hi = mean
        d_lo = -mean * 10.0 ** rng.uniform(-2, 1, N)
    else:
        eps = rng.uniform(-0.6, 0.6, N)
        d_lo, d_hi = mean * (1 - eps), mean * (1 + eps)
    swap = rng.random(N) < 0.5
    d_lo, d_hi = np.where(swap, d_hi, d_lo), np.where(swap, d_lo, d_hi)
    r_lo = rng.normal(size=N)
    r_hi = rng.normal(size=N)
    return ((d_lo + d_hi) / 2, (d_hi - d_lo) / (2 * HALF), (r_lo + r_hi) / 2,
            (r_hi - r_lo) / (2 * HALF))


def _time(loop, p, states, repeats: int) -> float:
    loop(p, *states)  # compile
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        loop(p, *states)
        times.append(time.perf_counter() - start)
    return float(np.median(times)) / N * 1e9


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--output", type=Path, default=ROOT / "results" / "bench_contact_laws.json")
    args = parser.parse_args(argv)
    for name, path in LAWS.items():  # every registered law is timed
        assert importlib.import_module(path).NAME in (name,)
    rng = np.random.default_rng(15)
    states = {regime: _states(regime, rng) for regime in ("corner", "face")}
    rows = {}
    for name, (module, make) in BLOCKS.items():
        values = make()
        p = np.array(list(values.values()))
        module.on_onset(p, 0, 0.8)
        force_loop, gradient_loop = _loops(module)
        rows[name] = {f"{kind} {regime}": _time(loop, p, states[regime], args.repeats)
                      for regime in ("corner", "face")
                      for kind, loop in (("force", force_loop), ("gradient", gradient_loop))}
    columns = list(next(iter(rows.values())))
    print(f"ns per call (median of {args.repeats} passes over {N} states)")
    print(f"{'law':22s}" + "".join(f"{c:>17s}" for c in columns))
    for name, row in rows.items():
        print(f"{name:22s}" + "".join(f"{row[c]:17.1f}" for c in columns))
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps({
        "ns_per_call": rows, "states": N, "repeats": args.repeats,
        "machine": f"{platform.machine()}, Python {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d")}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
