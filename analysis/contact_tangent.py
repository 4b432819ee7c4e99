"""Tangent dynamics of the laws with memory, jumps and shifts, measured: results/contact_tangent.*

For each case, the engine's propagator monodromy of one period against a
4th-order central difference of its stroboscopic map (the helpers of
tests/test_contact_tangent.py, imported from there, so the table and the tests
measure the same thing), after 30 periods from the scene's initial state; on
fig4 at T/T_Ax = 0.9, e = 0.65 (chaotic), the QR largest Lyapunov exponent
against the two-trajectory estimate; and Kelvin-Voigt's saltation on the point
models (tests/test_saltation.py, its cases and helpers): on the periodic
orbits, the propagator monodromy against the orbit solver's 5-point finite
difference and the QR exponent against ``log |mu_1| / T``, on the chaotic pair
the QR exponent against the two-trajectory estimate; and Jankowski's shifted
approach phase on the point models (tests/test_jankowski_tangent.py, the same
checks on its orbits, two of them sectioned inside an approach).
docs/contact_laws.md section 7 quotes it.

Usage::

    python analysis/contact_tangent.py            # results/contact_tangent.{md,json}, ~20 min
    python analysis/contact_tangent.py --out DIR  # elsewhere
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
#: (model, law, rtol, extra scene values); the point models with the law's
#: default e = 0.6 at their presets' T/T_Ax (wall 0.7, fig4-translational 1.0)
MONODROMY = (("tower-wall", "hertzdamp", 1e-12, {}), ("tower-wall", "hunt-crossley", 1e-12, {}),
             ("tower-wall", "kelvin-voigt", 1e-12, {}), ("fig3a", "hertzdamp", 1e-12, {}),
             ("fig3a", "kelvin-voigt", 1e-10, {}), ("wall", "kelvin-voigt", 1e-12, {}),
             ("wall", "kelvin-voigt", 1e-12, {"no_pull": True}),
             ("fig4-translational", "kelvin-voigt", 1e-12, {}),
             ("fig4-translational", "kelvin-voigt", 1e-12, {"no_pull": True}),
             ("wall", "jankowski", 1e-12, {}), ("fig4-translational", "jankowski", 1e-12, {}))
CHAOTIC = ("hertzdamp", "hunt-crossley", "kelvin-voigt")


def _cases(name: str = "test_contact_tangent"):
    """A test module of tests/ as a module (its helpers and cases)."""
    sys.path.insert(0, str(ROOT))
    spec = importlib.util.spec_from_file_location(f"{name}_cases",
                                                  ROOT / "tests" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _label(law: str, values: dict) -> str:
    return law + (" no-pull" if values.get("no_pull") else "")


def _orbit_row(scene, label: str, values: dict) -> dict:
    """One periodic orbit's checks: the propagator monodromy against the orbit solver's
    5-point finite difference (Newton on it), the QR exponent against log |mu_1| / T."""
    import math
    from dataclasses import replace

    from chaospound.dynamics.lyapunov import lyapunov_spectrum
    from chaospound.dynamics.system import System
    from chaospound.orbits import StroboscopicMap, find_orbit, finite_difference_monodromy
    from chaospound.orbits.maps import variational_monodromy

    smap = replace(StroboscopicMap.of(scene, monodromy_provider=finite_difference_monodromy),
                   jacobian_rtol=None)
    orbit = find_orbit(smap, transient=60)
    _, matrix = variational_monodromy(smap, orbit.state, 1)
    error = np.max(np.abs(matrix - orbit.monodromy)) / np.max(np.abs(orbit.monodromy))
    expected = math.log(abs(orbit.multipliers[0])) / smap.system.period
    system = System.from_scene(scene.with_params(method="dop853", rtol=1e-11, atol=1e-13))
    qr = lyapunov_spectrum(system, k=1, transient=0, tangent_transient=20, cycles=60,
                           n_blocks=6, initial_state=orbit.state)
    row = {"case": label, **values, "impacts_per_period": orbit.impacts_per_period,
           "multipliers_abs": [float(abs(z)) for z in orbit.multipliers],
           "relative_error": float(error), "log_mu_over_T": expected,
           "qr": float(qr.exponents[0]), "qr_error": float(qr.errors[0])}
    print(row, flush=True)
    return row


def _saltation() -> dict:
    """The measurements of tests/test_saltation.py (Kelvin-Voigt on the point models)."""
    from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum

    cases = _cases("test_saltation")
    orbits = [_orbit_row(cases._scene(preset, ratio, no_pull), label,
                         {"period_ratio": ratio, "no_pull": no_pull})
              for (preset, ratio, no_pull), label in zip(cases.ORBITS, cases.IDS, strict=True)]
    chaos = []
    for ratio, e, no_pull in ((1.25, 0.65, False), (1.24, 0.8, True)):
        scene = cases._scene("fig4-translational", ratio, no_pull, e).with_params(
            method="dop853", rtol=1e-10, atol=1e-12)
        qr = lyapunov_spectrum(scene, k=1, cycles=1000, transient=100)
        two = largest_exponent_two_trajectory(scene, cycles=1000, transient=100)
        chaos.append({"period_ratio": ratio, "restitution": e, "no_pull": no_pull,
                      "qr": float(qr.exponents[0]), "qr_error": float(qr.errors[0]),
                      "two": two.exponent, "two_error": two.error})
        print(chaos[-1], flush=True)
    return {"orbits": orbits, "chaotic_pair": chaos}


def _jankowski() -> dict:
    """The measurements of tests/test_jankowski_tangent.py (its shifted approach phase)."""
    from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum

    cases = _cases("test_jankowski_tangent")
    orbits = [_orbit_row(cases._scene(preset, ratio, phase), label,
                         {"period_ratio": ratio, "phase": phase})
              for (preset, ratio, phase), label in zip(cases.ORBITS, cases.IDS, strict=True)]
    scene = cases._scene("fig4-translational", 1.25).with_params(method="dop853", rtol=1e-10,
                                                                  atol=1e-12)
    qr = lyapunov_spectrum(scene, k=1, cycles=1000, transient=100)
    two = largest_exponent_two_trajectory(scene, cycles=1000, transient=100)
    chaos = {"period_ratio": 1.25, "restitution": 0.65, "qr": float(qr.exponents[0]),
             "qr_error": float(qr.errors[0]), "two": two.exponent, "two_error": two.error}
    print(chaos, flush=True)
    return {"orbits": orbits, "chaotic_pair": chaos}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "results"))
    args = parser.parse_args(argv)
    from chaospound import load_preset
    from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
    from chaospound.dynamics.system import advance, monodromy

    cases = _cases()
    rows = []
    for preset, law, rtol, values in MONODROMY:
        start = time.perf_counter()
        system = cases._system(preset, law, rtol=rtol, **values)
        state, _, _ = advance(system, system.initial_state, 30, from_time_zero=True)
        memory = system.params.copy()
        _, matrix = monodromy(system, state, 1)
        reference = cases._strobe_derivative(system, state, memory)
        error = float(np.max(np.abs(matrix - reference)) / np.max(np.abs(reference)))
        rows.append({"model": preset, "law": _label(law, values), "rtol": rtol,
                     "relative_error": error, "seconds": time.perf_counter() - start})
        print(rows[-1], flush=True)
    chaos = []
    for law in CHAOTIC:
        scene = load_preset("fig4").with_params(contact_law=law, restitution=0.65,
                                                period_ratio=0.9, method="dop853",
                                                rtol=1e-10, atol=1e-12)
        qr = lyapunov_spectrum(scene, k=1, cycles=300, transient=100)
        two = largest_exponent_two_trajectory(scene, cycles=300, transient=100)
        chaos.append({"law": law, "qr": float(qr.exponents[0]), "qr_error": float(qr.errors[0]),
                      "two": two.exponent, "two_error": two.error})
        print(chaos[-1], flush=True)
    saltation = _saltation()
    shifted = _jankowski()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "contact_tangent.json").write_text(json.dumps(
        {"monodromy": rows, "chaotic_fig4_0.9": chaos, "saltation": saltation,
         "jankowski_point": shifted}, indent=1) + "\n")
    lines = ["# Tangent dynamics of the laws with memory, jumps and shifts", "",
             "Generated by `python analysis/contact_tangent.py`.", "",
             "| model | law | rtol | monodromy vs central differences (relative) |",
             "|---|---|---|---|"]
    lines += [f"| {r['model']} | {r['law']} | {r['rtol']:g} | {r['relative_error']:.2g} |"
              for r in rows]
    lines += ["", "fig4, T/T_Ax = 0.9, e = 0.65, 100 + 300 cycles, rtol 1e-10:", "",
              "| law | QR lambda_1 | two trajectories |", "|---|---|---|"]
    lines += [f"| {c['law']} | {c['qr']:.4f} +- {c['qr_error']:.4f} | "
              f"{c['two']:.4f} +- {c['two_error']:.4f} |" for c in chaos]
    lines += ["", "Kelvin-Voigt on the point models (saltation at the force's jumps), e = 0.65, "
              "on stable period-1 orbits (tests/test_saltation.py): the propagator "
              "monodromy against the 5-point finite difference (rtol 1e-12), the QR "
              "exponent (60 cycles, rtol 1e-11) against log |mu_1| / T:", "",
              "| model | T/T_Ax | impacts | abs(mu) | monodromy vs finite differences "
              "(relative) | QR lambda_1 | log abs(mu_1) / T |", "|---|---|---|---|---|---|---|"]
    lines += [f"| {o['case']} | {o['period_ratio']:g} | {o['impacts_per_period']} | "
              + ", ".join(f"{m:.4f}" for m in o["multipliers_abs"])
              + f" | {o['relative_error']:.2g} | {o['qr']:.5f} +- {o['qr_error']:.2g} | "
              f"{o['log_mu_over_T']:.5f} |" for o in saltation["orbits"]]
    lines += ["", "Chaotic pair (fig4-translational), 100 + 1000 cycles, rtol 1e-10:", "",
              "| T/T_Ax | e | no_pull | QR lambda_1 | two trajectories |", "|---|---|---|---|---|"]
    lines += [f"| {c['period_ratio']:g} | {c['restitution']:g} | {c['no_pull']} | "
              f"{c['qr']:.4f} +- {c['qr_error']:.4f} | {c['two']:.4f} +- {c['two_error']:.4f} |"
              for c in saltation["chaotic_pair"]]
    lines += ["", "Jankowski on the point models (the approach phase's tangent vectors shifted), "
              "e = 0.65, on stable period-1 orbits sectioned at the phase given "
              "(tests/test_jankowski_tangent.py; 0.312 and 0.111 fall inside an approach), "
              "the same checks:", "",
              "| model | T/T_Ax | phase | impacts | abs(mu) | monodromy vs finite differences "
              "(relative) | QR lambda_1 | log abs(mu_1) / T |",
              "|---|---|---|---|---|---|---|---|"]
    lines += [f"| {o['case']} | {o['period_ratio']:g} | {o['phase']:g} | "
              f"{o['impacts_per_period']} | "
              + ", ".join(f"{m:.4f}" for m in o["multipliers_abs"])
              + f" | {o['relative_error']:.2g} | {o['qr']:.5f} +- {o['qr_error']:.2g} | "
              f"{o['log_mu_over_T']:.5f} |" for o in shifted["orbits"]]
    c = shifted["chaotic_pair"]
    lines += ["", f"Chaotic pair with Jankowski (fig4-translational, T/T_Ax = "
              f"{c['period_ratio']:g}, e = {c['restitution']:g}), 100 + 1000 cycles, rtol "
              f"1e-10: QR lambda_1 = {c['qr']:.4f} +- {c['qr_error']:.4f}, two trajectories "
              f"{c['two']:.4f} +- {c['two_error']:.4f}."]
    (out / "contact_tangent.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
