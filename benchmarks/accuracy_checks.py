"""The accuracy numbers quoted in the README, measured on the committed integrator.

The tests assert bounds (energy drift <= 1e-6, reductions within 1e-8, ...);
this script measures the values themselves on the same scenes, so that the
README's numbers come from one reproducible run:

* energy drift without damping or ground motion (12-state fig3a scene, 200
  cycles, rtol 1e-10), and the number of impacts it covers;
* the pair model against the 12-state model on the symmetric scene
  (T/T_Ax = 0.5, 0.7, 1.0, 1.3; rtol 1e-11): largest impact-velocity difference;
* fig3b against the mirror image of fig3a (rtol 1e-10): largest difference;
* the four integrators against a DOP853 reference at rtol 1e-13 on fig3a
  (10 + 4 cycles): largest impact-time and velocity differences;
* landing steps on the contact kinks against stepping through them (pair
  scene, rtol 1e-9): impact-velocity errors against the reference.

    python benchmarks/accuracy_checks.py [--output results/accuracy_checks.json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from chaospound.dynamics.system import System
from chaospound.scene import load_preset
from chaospound.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]
MIRROR = np.array([1, 1, -1, -1, -1, -1] * 2, dtype=float)
PAIR_IN_TOWERS = [0, 1, 6, 7]
PERIOD_RATIOS = (0.5, 0.7, 1.0, 1.3)
INTEGRATORS = {
    "dopri5": {"method": "dopri5", "rtol": 1e-10, "atol": 1e-13},
    "dop853": {"method": "dop853", "rtol": 1e-12, "atol": 1e-14},
    "cash-karp": {"method": "cash-karp", "rtol": 1e-10},
    "rk4": {"method": "rk4", "steps_per_cycle": 20000},
}


def energy_drift() -> dict:
    """Relative energy drift of the undamped, unforced 12-state fig3a scene."""
    initial = [0, 2, 0.5, 0.1, 0.01, -0.005, 0, -2, -0.3, 0.2, -0.01, 0.003]
    scene = load_preset("fig3a").with_params(zeta=0, ground="none", rtol=1e-10, atol=1e-12,
                                             initial_state=initial)
    sim = simulate(scene, transient=0, record=200, samples_per_cycle=40)
    system = System.from_scene(scene)
    energy, p = system.engine().module.model_energy, system.params
    e0 = energy(system.initial_state, p)
    energies = [energy(y, p) for y in sim.trajectory.state]
    return {"model": sim.model, "impacts": len(sim.impacts),
            "relative_drift": float(np.max(np.abs(np.array(energies) - e0)) / e0)}


def pair_against_towers() -> dict:
    worst = 0.0
    for r in PERIOD_RATIOS:
        scene = load_preset("fig4-translational").with_params(period_ratio=r, rtol=1e-11,
                                                               atol=1e-13)
        pair = simulate(scene, transient=20, record=4)
        towers = simulate(scene.with_params(model="towers"), transient=20, record=4)
        worst = max(worst, float(np.max(np.abs(pair.impacts.velocity
                                               - towers.impacts.velocity))))
        worst = max(worst, float(np.max(np.abs(pair.strobe.state
                                               - towers.strobe.state[:, PAIR_IN_TOWERS]))))
    return {"max_abs_difference": worst}


def mirror() -> dict:
    tight = {"rtol": 1e-10, "atol": 1e-13}
    a = simulate(load_preset("fig3a").with_params(**tight))
    b = simulate(load_preset("fig3b").with_params(**tight))
    return {
        "impacts": len(a.impacts),
        "max_abs_difference": float(max(np.max(np.abs(b.impacts.state * MIRROR - a.impacts.state)),
                                        np.max(np.abs(b.strobe.state * MIRROR - a.strobe.state)))),
        "labels_swapped": [{"A+": "A-", "A-": "A+", "B+": "B-", "B-": "B+"}.get(c, c)
                           for c in a.impacts.labels] == b.impacts.labels,
    }


def integrators() -> dict:
    ref = simulate(load_preset("fig3a").with_params(method="dop853", rtol=1e-13, atol=1e-15),
                   transient=10, record=4)
    out = {}
    for name, settings in INTEGRATORS.items():
        sim = simulate(load_preset("fig3a").with_params(**settings), transient=10, record=4)
        out[name] = {
            "same_labels": sim.impacts.labels == ref.impacts.labels,
            "max_time_difference": float(np.max(np.abs(sim.impacts.time - ref.impacts.time))),
            "max_velocity_difference": float(np.max(np.abs(sim.impacts.velocity
                                                           - ref.impacts.velocity))),
        }
    return out


def landing() -> dict:
    out = {"landed": [], "stepped_through": []}
    for r in PERIOD_RATIOS:
        scene = load_preset("fig4-translational").with_params(period_ratio=r)
        ref = simulate(scene.with_params(method="dop853", rtol=1e-13, atol=1e-15),
                       transient=20, record=8)
        for restart, key in ((True, "landed"), (False, "stepped_through")):
            sim = simulate(scene.with_params(rtol=1e-9, atol=1e-12, restart_at_kinks=restart),
                           transient=20, record=8)
            out[key].append(float(np.max(np.abs(sim.impacts.velocity - ref.impacts.velocity))))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", default=str(ROOT / "results" / "accuracy_checks.json"))
    args = parser.parse_args()
    result = {
        "energy": energy_drift(),
        "pair_vs_towers": pair_against_towers(),
        "mirror_fig3b_fig3a": mirror(),
        "integrators_vs_dop853": integrators(),
        "landing_rtol_1e-9": landing(),
    }
    Path(args.output).write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
