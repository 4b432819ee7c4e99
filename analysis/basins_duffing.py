"""Basins of the twin-well Duffing oscillator, checked against scipy (docs/basins.md).

x'' + 0.25 x' - x + x^3 = 0.1 cos t (chaospound.duffing with linear -1, cubic 1):
a period-1 attractor in each well, with interleaved spiral basins. The scan
covers x, x' in [-2, 2]^2 (the initial state at t = 0, 40 + 8 periods per
point); 1000 random initial states are then integrated by scipy's DOP853 at
rtol 1e-10 over the same 48 periods and sorted onto the nearest attractor,
and compared with the map's label of their nearest cell, counting apart the
states within one cell of a basin boundary.

    PYTHONPATH=. python analysis/basins_duffing.py [--points 201] [--workers 2]

writes results/basins/duffing_basins.png and results/basins/duffing_basins.json.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from chaospound.basins import basins
from chaospound.dynamics.system import duffing
from chaospound.plot import save
from chaospound.plot_basins import plot_basins

DAMPING, FORCE, OMEGA = 0.25, 0.1, 1.0
ROOT = Path(__file__).resolve().parents[1]


def rhs(t, y):
    return [y[1], FORCE * math.cos(OMEGA * t) - DAMPING * y[1] + y[0] - y[0] ** 3]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=201, help="grid points per axis")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--checks", type=int, default=1000, help="random states for scipy")
    args = parser.parse_args()
    system = dataclasses.replace(
        duffing(damping=DAMPING, linear=-1.0, cubic=1.0, amplitude=FORCE, frequency=OMEGA),
        transient=40, record=8)
    n = args.points
    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        summary, result = basins(system, (f"x=-2:2#{n}", f"dx=-2:2#{n}"),
                                 Path(folder) / "duffing.h5", workers=args.workers,
                                 progress=False)
        wall = time.perf_counter() - started
    print(summary.format())
    print(result.format())
    out = ROOT / "results" / "basins"
    out.mkdir(parents=True, exist_ok=True)
    save(plot_basins(result, state_names=("x", "dx")), out / "duffing_basins.png")

    x, dx = result.grid["x"], result.grid["dx"]
    rng = np.random.default_rng(2016)
    period = 2.0 * math.pi / OMEGA
    agree = disagree = near = 0
    for y0 in rng.uniform(-2.0, 2.0, size=(args.checks, 2)):
        i, j = int(np.argmin(np.abs(x - y0[0]))), int(np.argmin(np.abs(dx - y0[1])))
        block = result.labels[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2]
        sol = solve_ivp(rhs, (0.0, 48 * period), y0, method="DOP853", rtol=1e-10, atol=1e-12)
        end = sol.y[:, -1]
        label = int(np.argmin([np.max(np.abs(end - a.sections[0]))
                               for a in result.attractors]))
        if np.any(block != block.flat[0]):
            near += 1
            continue
        if label == result.labels[i, j]:
            agree += 1
        else:
            disagree += 1
    print(f"scipy check of {args.checks} random states: {agree} agree, {disagree} disagree, "
          f"{near} within a cell of a boundary (not compared)")
    document = {
        "command": f"PYTHONPATH=. python analysis/basins_duffing.py --points {n} "
                   f"--workers {args.workers} --checks {args.checks}",
        "system": "x'' + 0.25 x' - x + x^3 = 0.1 cos t, 40 + 8 periods",
        "grid": f"x=-2:2#{n}, dx=-2:2#{n}",
        "points_per_second": summary.points_per_second,
        "wall_s": wall,
        "attractors": [{"label": a.label, "section": a.sections[0].tolist(),
                        "share": a.share} for a in result.attractors],
        "basin_entropy": result.entropy,
        "boundary_basin_entropy": result.boundary_entropy,
        "box": result.box,
        "scipy_check": {"states": args.checks, "agree": agree, "disagree": disagree,
                        "near_boundary": near},
    }
    (out / "duffing_basins.json").write_text(json.dumps(document, indent=2) + "\n")


if __name__ == "__main__":
    main()
