"""chaospound against OpenSeesPy: one tower against a wall, Hertzdamp contact, a 50 s record.

An optional benchmark (issue 15): it needs ``openseespy``, which is not a
dependency of chaospound; without it the script says so and exits 0.

The problem, in SI: a single-degree-of-freedom tower (m = 1e6 kg, T = 0.5 s,
zeta = 0.03) at a gap a = 20 mm from a rigid wall that moves with the ground,
Hertzdamp contact with Kh = 2.75e10 N/m^1.5 (Muthukumar & DesRoches' bridge
value, 25 000 kip/in^1.5), n = 1.5, e = 0.65, under the synthetic 50 s record of
:mod:`bench_record` (0.01 s samples, PGA 0.35 g). In the relative displacement
x (tower minus ground)::

    m x'' + c x' + K x + F = -m a_g(t),   F = Kh d^n (1 + xiNorm d' / v0),  d = x - a > 0

with v0 the approach velocity d' at the impact's onset and xiNorm =
3 (1 - e^2) / 4 (Lankarani-Nikravesh, chaospound's default variant of
``hertzdamp``; OpenSees takes xiNorm as given, so both get the same number).

Three solutions of this ODE:

* **reference**: scipy's DOP853 at rtol 1e-12 (atol 1e-15 m, 1e-13 m/s), restarted at
  every sample (the kinks of a_g) and at every contact onset and release
  (events), v0 the velocity at the located onset, peak force located on the
  dense output. Independent of both codes.
* **chaospound**: the scene ``wall`` (2 states) with ``ground = "record"`` on
  the same file, converted to the dimensionless model (docs/model.md section 2):
  A_g = 1 cm, omega_Ax = 2 pi / T, gap = a / A_g, beta = Kh A_g^(n-1) / K;
  dopri5 at rtol 1e-3 .. 1e-10 (atol = 1e-3 rtol, in A_g).
* **OpenSeesPy**: a zeroLength element with ``uniaxialMaterial Elastic K c``
  (tower) and one with ``uniaxialMaterial Hertzdamp Kh xiNorm -a n`` (wall),
  ``UniformExcitation`` of a ``Path`` time series (linear between samples, as
  chaospound's record), Newmark average acceleration, Newton, NormDispIncr 1e-12,
  dt = 0.01 / 2^k; the displacement is recorded at every step, the contact
  force too.

Accuracy, against the reference: the peak |x| over the 0.01 s sample times,
the peak contact force over the record, and the largest error of x at the
sample times relative to the peak |x|. Work: wall time per run, best of
``--rounds`` interleaved rounds (every run of both codes once per round).
chaospound's time is ``simulate()`` end to end (which reads the text file and
integrates the record into its block in Python at every call: about 45 ms,
nearly all of it) and the engine's alone; OpenSees' time is building the model (the 5001 values
passed as a list) plus ``analyze`` plus flushing the recorders, without
reading their files back.

Differences between the two Hertzdamp implementations (OpenSees
SRC/material/uniaxial/Hertzdamp.cpp, read for this benchmark):

* same force law, ``(Kh + xi d') d^n`` with ``xi = xiNorm Kh / v0``;
* v0: OpenSees sets xi at the first converged step that ends in contact, from
  that step's end velocity (the trial strain rate, recomputed at every Newton
  iteration until the step commits); chaospound (and the reference) use the
  velocity at the located onset. The difference is O(dt) and is part of
  OpenSees' error here;
* OpenSees' tangent leaves out the damping term's dependence on d' (no damping
  tangent), which slows Newton but does not change the converged answer.

Usage::

    PYTHONPATH=. python benchmarks/bench_opensees.py [--rounds 3]
        [--output results/bench_opensees.json]
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_record import synthetic_record  # noqa: E402

from chaospound.physics.contact.hertzdamp import damping_numerator  # noqa: E402
from chaospound.physics.ground import record  # noqa: E402
from chaospound.scene import load_preset  # noqa: E402
from chaospound.simulate import simulate  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
MASS = 1.0e6  #: kg
PERIOD = 0.5  #: s
ZETA = 0.03
OMEGA = 2.0 * math.pi / PERIOD
STIFFNESS = MASS * OMEGA**2  #: N/m
DAMPING = 2.0 * ZETA * MASS * OMEGA  #: N s/m
KH = 2.75e10  #: N/m^1.5
EXPONENT = 1.5
GAP = 0.02  #: m
RESTITUTION = 0.65
XI_NORM = damping_numerator(RESTITUTION, 1.0)  #: 3 (1 - e^2) / 4
A_G = 0.01  #: m, chaospound's length unit
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
DTS = tuple(0.01 / 2**k for k in range(7))
TARGETS = (1e-2, 1e-3, 1e-4, 1e-5)


# ---------------------------------------------------------------- reference


def reference(t: np.ndarray, a: np.ndarray, rtol: float = 1e-12) -> dict:
    """DOP853 on the SI equations, restarted at samples and contact switches."""
    state = {"v0": 1.0}

    def force(x, v):
        d = x - GAP
        if d <= 0.0:
            return 0.0
        return KH * d**EXPONENT * (1.0 + XI_NORM * v / state["v0"])

    def rhs_in(k, contact):
        slope = (a[k + 1] - a[k]) / (t[k + 1] - t[k])

        def rhs(s, y):
            ag = a[k] + slope * (s - t[k])
            f = force(y[0], y[1]) if contact else 0.0
            return (y[1], -(DAMPING * y[1] + STIFFNESS * y[0] + f) / MASS - ag)
        return rhs

    def onset(s, y):
        return y[0] - GAP
    onset.terminal = True
    onset.direction = 1.0

    def release(s, y):
        return y[0] - GAP
    release.terminal = True
    release.direction = -1.0

    y = np.array([0.0, 0.0])
    contact = False
    xs = np.empty(t.size)
    xs[0] = 0.0
    peak_force = 0.0
    impacts = 0
    steps = 0
    for k in range(t.size - 1):
        s0 = t[k]
        while True:
            sol = solve_ivp(rhs_in(k, contact), (s0, t[k + 1]), y, method="DOP853", rtol=rtol,
                            atol=(1e-15, 1e-13), events=release if contact else onset,
                            dense_output=contact)
            steps += sol.t.size - 1
            if contact:
                grid = np.linspace(sol.t[0], sol.t[-1], 65)
                values = [force(*sol.sol(s)) for s in grid]
                i = int(np.argmax(values))
                best = values[i]
                if 0 < i < 64:
                    found = minimize_scalar(lambda s, sol=sol: -force(*sol.sol(s)),
                                            bounds=(grid[i - 1], grid[i + 1]), method="bounded",
                                            options={"xatol": 1e-14})
                    best = max(best, -found.fun)
                peak_force = max(peak_force, best)
            if sol.status == 1:  # an event: switch and restart from it
                s0 = sol.t_events[0][0]
                y = sol.y_events[0][0].copy()
                y[0] = GAP  # exactly on the surface
                contact = not contact
                if contact:
                    impacts += 1
                    state["v0"] = y[1]
                continue
            y = sol.y[:, -1].copy()
            break
        xs[k + 1] = y[0]
    return {"x": xs, "peak_force": peak_force, "impacts": impacts, "steps": steps}


# ---------------------------------------------------------------- chaospound


def chaospound_scene(path: Path, rtol: float):
    """The ``wall`` preset converted from the SI problem."""
    return load_preset("wall").with_params(
        ground="record", ground_file=str(path), ground_units="m/s^2", length_unit=A_G,
        tower_period=PERIOD, period_ratio=1.0 / PERIOD, zeta_x=ZETA, gap=GAP / A_G,
        beta=KH * A_G ** (EXPONENT - 1.0) / STIFFNESS, chi=EXPONENT, contact_law="hertzdamp",
        restitution=RESTITUTION, damping_variant="lankarani-nikravesh", transient=0,
        record=50, rtol=rtol, atol=1e-3 * rtol)


def run_chaospound(path: Path, t: np.ndarray, u_ground: np.ndarray, rtol: float) -> dict:
    scene = chaospound_scene(path, rtol)
    start = time.perf_counter()
    run = simulate(scene, samples_per_cycle=100)
    wall = time.perf_counter() - start
    if run.model != "wall":
        raise RuntimeError(f"expected the 2-state wall model, got {run.model}")
    times = run.trajectory.time / OMEGA
    if times.size != t.size or np.max(np.abs(times - t)) > 1e-9:
        raise RuntimeError("the trajectory's samples are not the record's sample times")
    x = run.trajectory.state[:, 0] * A_G - u_ground
    return {"x": x, "peak_force": float(np.max(run.impacts.peak_force, initial=0.0))
            * A_G * STIFFNESS, "impacts": len(run.impacts), "steps": run.stats.steps,
            "wall_s": wall, "engine_s": run.stats.wall_s}


# ---------------------------------------------------------------- OpenSees


def run_opensees(ops, t: np.ndarray, a: np.ndarray, dt: float, folder: Path) -> dict:
    disp_file = folder / "disp.out"
    force_file = folder / "force.out"
    steps = int(round(t[-1] / dt))
    start = time.perf_counter()
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(1, 0.0)
    ops.node(2, 0.0)
    ops.node(3, 0.0)
    ops.fix(1, 1)
    ops.fix(3, 1)
    ops.mass(2, MASS)
    ops.uniaxialMaterial("Elastic", 1, STIFFNESS, DAMPING)
    ops.uniaxialMaterial("Hertzdamp", 2, KH, XI_NORM, -GAP, EXPONENT)
    ops.element("zeroLength", 1, 1, 2, "-mat", 1, "-dir", 1)
    ops.element("zeroLength", 2, 2, 3, "-mat", 2, "-dir", 1)
    ops.timeSeries("Path", 1, "-dt", float(t[1] - t[0]), "-values", *map(float, a))
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.recorder("Node", "-file", str(disp_file), "-time", "-node", 2, "-dof", 1, "disp")
    ops.recorder("Element", "-file", str(force_file), "-time", "-ele", 2, "force")
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.test("NormDispIncr", 1e-12, 100)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    status = ops.analyze(steps, dt)
    ops.wipe()  # closes the recorders
    wall = time.perf_counter() - start
    if status != 0:
        return {"failed": True, "wall_s": wall}
    disp = np.loadtxt(disp_file)
    force = np.loadtxt(force_file)
    every = int(round((t[1] - t[0]) / dt))
    x = np.concatenate(([0.0], disp[every - 1::every, 1]))
    contact = force[:, 1] != 0.0  # the force on node 2 (towards -x while in contact)
    onsets = int(np.sum(contact[1:] & ~contact[:-1]) + contact[0])
    return {"x": x[: t.size], "peak_force": float(np.max(np.abs(force[:, 1]))),
            "impacts": onsets, "steps": steps, "wall_s": wall, "failed": False}


# ---------------------------------------------------------------- report


def write_markdown(path: Path, ref: dict, ref_self: dict, rows_cp: dict, rows_os: dict,
                   matched: dict, rounds: int) -> None:
    """results/bench_opensees.md: the problem, the work-precision pairs, the matched runs."""
    lines = [
        "# chaospound against OpenSeesPy: one tower against a wall, Hertzdamp, a 50 s record",
        "",
        "Written by `PYTHONPATH=. python benchmarks/bench_opensees.py` (needs `pip install "
        "openseespy`, not a chaospound dependency; the script's docstring has the details).",
        "",
        f"Problem (SI): m = {MASS:.0e} kg, T = {PERIOD} s, zeta = {ZETA}, gap {GAP * 1e3:.0f} mm "
        f"to a rigid wall moving with the ground, Hertzdamp Kh = {KH:.3g} N/m^1.5, n = "
        f"{EXPONENT}, e = {RESTITUTION} (xiNorm = 3 (1 - e^2) / 4 = {XI_NORM:.5f}, "
        "Lankarani-Nikravesh, chaospound's default `hertzdamp` variant, given to OpenSees "
        "as is); the synthetic record of `benchmarks/bench_record.py` (50 s at 0.01 s, "
        "PGA 0.35 g). chaospound: preset `wall` (2 states), A_g = 1 cm, dopri5, atol = "
        "1e-3 rtol. OpenSees: two zeroLength elements (Elastic K c; Hertzdamp Kh xiNorm "
        "-gap n), UniformExcitation of a Path series, Newmark average acceleration, Newton, "
        "NormDispIncr 1e-12.",
        "",
        f"Reference: scipy DOP853 at rtol 1e-12, restarted at every sample and contact "
        f"switch: {ref['impacts']} impacts, peak |x| {np.max(np.abs(ref['x'])) * 1e3:.4f} mm, "
        f"peak force {ref['peak_force'] / 1e6:.4f} MN; against the same at rtol 1e-11: "
        f"{ref_self['peak_displacement']:.1e} (peak x), {ref_self['peak_force']:.1e} "
        f"(peak force), {ref_self['trajectory']:.1e} (x(t)).",
        "",
        "Errors relative to the reference: peak |x| over the 0.01 s samples, peak contact "
        "force, and max |x - x_ref| over the samples divided by the peak |x|. Times: best of "
        f"{rounds} interleaved rounds on a shared 2-core machine (absolute times move with "
        "the load; compare within the table). chaospound's time is `simulate()` end to end, "
        "which reads the text record and integrates it in Python at every call (nearly all "
        "of the time at these tolerances); 'engine' is the compiled integration alone. "
        "OpenSees' time is building the model, "
        "`analyze` and flushing its recorders (every step).",
        "",
        "| run | time [ms] | engine [ms] | steps | impacts | err peak x | err peak F | err x(t) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for rtol, row in rows_cp.items():
        err = row["error"]
        lines.append(f"| chaospound rtol {rtol:.0e} | {row['best_s'] * 1e3:.1f} | "
                     f"{row['engine_best_s'] * 1e3:.2f} | {row['steps']} | {row['impacts']} | "
                     f"{err['peak_displacement']:.1e} | {err['peak_force']:.1e} | "
                     f"{err['trajectory']:.1e} |")
    for dt, row in rows_os.items():
        if row.get("failed"):
            lines.append(f"| OpenSees dt {dt:.3g} s | {row['best_s'] * 1e3:.1f} | | | | "
                         "failed | | |")
            continue
        err = row["error"]
        lines.append(f"| OpenSees dt {dt:.3g} s | {row['best_s'] * 1e3:.1f} | | {row['steps']} | "
                     f"{row['impacts']} | {err['peak_displacement']:.1e} | "
                     f"{err['peak_force']:.1e} | {err['trajectory']:.1e} |")
    lines += ["", "At matched accuracy (for each code the loosest rtol or the longest dt whose "
              "error is at most the target):", "",
              "| error in | target | chaospound | OpenSees | OpenSees / chaospound "
              "(end to end) | (engine) |", "|---|---|---|---|---|---|"]
    for metric, by_target in matched.items():
        for target, entry in by_target.items():
            cp = (f"rtol {entry['chaospound_rtol']:.0e}, {entry['chaospound_s'] * 1e3:.1f} ms"
                  if entry["chaospound_rtol"] else "not reached")
            os_ = (f"dt {entry['opensees_dt']:.3g} s, {entry['opensees_s'] * 1e3:.0f} ms"
                   if entry["opensees_dt"] else "not reached")
            ratio = (f"{entry['opensees_over_chaospound']:.1f}x" if "opensees_over_chaospound"
                     in entry else "")
            engine = (f"{entry['opensees_over_chaospound_engine']:.0f}x"
                      if "opensees_over_chaospound_engine" in entry else "")
            lines.append(f"| {metric.replace('_', ' ')} | {target} | {cp} | {os_} | {ratio} | "
                         f"{engine} |")
    lines += [
        "",
        "The two Hertzdamp implementations (OpenSees `SRC/material/uniaxial/Hertzdamp.cpp`):",
        "the same force, `(Kh + xi d') d^n` with `xi = xiNorm Kh / v0`; OpenSees takes v0",
        "from the end velocity of the first converged step in contact, chaospound from the",
        "located onset (an O(dt) difference, part of OpenSees' error above); OpenSees'",
        "tangent has no damping term, which costs Newton iterations, not accuracy.",
        "OpenSees' manual recommends Ye's xiNorm = 8 (1 - e) / (5 e); chaospound's",
        "`damping_variant = \"ye\"` is the same formula (this benchmark uses the",
        "Lankarani-Nikravesh value on both sides).",
        "",
    ]
    path.write_text("\n".join(lines))


# ---------------------------------------------------------------- driver


def errors(run: dict, ref: dict) -> dict:
    peak = np.max(np.abs(ref["x"]))
    return {"peak_displacement": abs(np.max(np.abs(run["x"])) - peak) / peak,
            "peak_force": abs(run["peak_force"] - ref["peak_force"]) / ref["peak_force"],
            "trajectory": float(np.max(np.abs(run["x"] - ref["x"]))) / peak}


def cheapest(rows: list[dict], metric: str, target: float) -> dict | None:
    """The loosest run (rows in order of rising work) whose error is at most ``target``.

    Chosen by the nominal work (rtol, dt), not by the measured time, which the
    shared machine's load makes noisy.
    """
    for row in rows:
        if not row.get("failed") and row["error"][metric] <= target:
            return row
    return None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--output", type=Path, default=ROOT / "results" / "bench_opensees.json")
    args = parser.parse_args(argv)
    try:
        import openseespy.opensees as ops
    except Exception as error:  # ImportError, or openseespy's RuntimeError (missing libblas)
        print(f"bench_opensees: skipped, openseespy is not importable ({error}); "
              "pip install openseespy to run it", file=sys.stderr)
        return 0
    ops.logFile(str(Path(tempfile.gettempdir()) / "bench_opensees.log"), "-noEcho")
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        path, t, a = synthetic_record(folder)
        u_ground, _ = record.integrate(t, a)
        start = time.perf_counter()
        ref = reference(t, a)
        ref_s = time.perf_counter() - start
        check = reference(t, a, rtol=1e-11)
        ref_self = errors(check, ref)
        peak_x = np.max(np.abs(ref["x"]))
        print(f"reference: {ref['impacts']} impacts, peak |x| {peak_x * 1e3:.4f} mm, "
              f"peak force {ref['peak_force'] / 1e3:.2f} kN ({ref_s:.1f} s); rtol 1e-11 against "
              f"1e-12: {ref_self}")
        run_chaospound(path, t, u_ground, 1e-5)  # compile or load the engine
        rows_cp = {rtol: {"rtol": rtol, "times": [], "engine": []} for rtol in RTOLS}
        rows_os = {dt: {"dt": dt, "times": []} for dt in DTS}
        for round_ in range(args.rounds):
            for rtol, row in rows_cp.items():
                out = run_chaospound(path, t, u_ground, rtol)
                row["times"].append(out["wall_s"])
                row["engine"].append(out["engine_s"])
                row.update({"steps": out["steps"], "impacts": out["impacts"],
                            "error": errors(out, ref)})
            for dt, row in rows_os.items():
                out = run_opensees(ops, t, a, dt, folder)
                row["times"].append(out["wall_s"])
                row["failed"] = out["failed"]
                if not out["failed"]:
                    row.update({"steps": out["steps"], "impacts": out["impacts"],
                                "error": errors(out, ref)})
            print(f"round {round_ + 1}/{args.rounds} done", flush=True)
    for row in [*rows_cp.values(), *rows_os.values()]:
        row["best_s"] = min(row["times"])
        row["median_s"] = float(np.median(row["times"]))
    for row in rows_cp.values():
        row["engine_best_s"] = min(row["engine"])
    print(f"{'run':22s} {'best s':>9s} {'median s':>9s} {'steps':>8s} {'impacts':>7s} "
          f"{'err peak x':>10s} {'err peak F':>10s} {'err x(t)':>10s}")
    for label, row in [*((f"chaospound rtol {r:.0e}", v) for r, v in rows_cp.items()),
                       *((f"OpenSees dt {d:.3g}", v) for d, v in rows_os.items())]:
        if row.get("failed"):
            print(f"{label:22s} {row['best_s']:9.4f} failed to converge")
            continue
        err = row["error"]
        print(f"{label:22s} {row['best_s']:9.4f} {row['median_s']:9.4f} {row['steps']:8d} "
              f"{row['impacts']:7d} {err['peak_displacement']:10.2e} {err['peak_force']:10.2e} "
              f"{err['trajectory']:10.2e}")
    matched = {}
    for metric in ("peak_displacement", "peak_force", "trajectory"):
        matched[metric] = {}
        for target in TARGETS:
            cp = cheapest(list(rows_cp.values()), metric, target)
            os_ = cheapest(list(rows_os.values()), metric, target)
            entry = {"chaospound_rtol": cp and cp["rtol"], "chaospound_s": cp and cp["best_s"],
                     "chaospound_engine_s": cp and cp["engine_best_s"],
                     "opensees_dt": os_ and os_["dt"], "opensees_s": os_ and os_["best_s"]}
            if cp and os_:
                entry["opensees_over_chaospound"] = os_["best_s"] / cp["best_s"]
                entry["opensees_over_chaospound_engine"] = os_["best_s"] / cp["engine_best_s"]
            matched[metric][f"{target:.0e}"] = entry
            if cp and os_:
                print(f"{metric:18s} error <= {target:.0e}: chaospound rtol {cp['rtol']:.0e} "
                      f"{cp['best_s'] * 1e3:.1f} ms (engine {cp['engine_best_s'] * 1e3:.2f} ms), "
                      f"OpenSees dt {os_['dt']:.3g} {os_['best_s'] * 1e3:.1f} ms: "
                      f"OpenSees / chaospound {entry['opensees_over_chaospound']:.1f}x "
                      f"(engine {entry['opensees_over_chaospound_engine']:.0f}x)")
            else:
                cp_text = f"rtol {cp['rtol']:.0e}" if cp else "not reached"
                os_text = f"dt {os_['dt']:.3g}" if os_ else "not reached"
                print(f"{metric:18s} error <= {target:.0e}: chaospound {cp_text}, "
                      f"OpenSees {os_text}")
    args.output.parent.mkdir(parents=True, exist_ok=True)
    write_markdown(args.output.with_suffix(".md"), ref, ref_self, rows_cp, rows_os, matched,
                   args.rounds)
    args.output.write_text(json.dumps({
        "problem": {"mass_kg": MASS, "period_s": PERIOD, "zeta": ZETA, "Kh_N_per_m1.5": KH,
                    "n": EXPONENT, "gap_m": GAP, "restitution": RESTITUTION,
                    "xi_norm": XI_NORM, "record": "bench_record.synthetic_record: 50 s at 0.01 s, "
                    "PGA 0.35 g", "chaospound_length_unit_m": A_G},
        "reference": {"method": "scipy DOP853 rtol 1e-12, restarted at samples and contact "
                      "switches", "impacts": ref["impacts"],
                      "peak_displacement_m": float(np.max(np.abs(ref["x"]))),
                      "peak_force_N": ref["peak_force"], "self_check_rtol_1e-11": ref_self},
        "chaospound": [{k: v for k, v in row.items() if k not in ("times", "engine")}
                       | {"times_s": row["times"]} for row in rows_cp.values()],
        "opensees": [{k: v for k, v in row.items() if k != "times"} | {"times_s": row["times"]}
                     for row in rows_os.values()],
        "matched_accuracy": matched, "rounds": args.rounds,
        "opensees_version": ops.version() if hasattr(ops, "version") else "unknown",
        "machine": f"{platform.machine()}, Python {platform.python_version()}, 2 shared cores",
        "date": time.strftime("%Y-%m-%d"),
        "command": "PYTHONPATH=. python benchmarks/bench_opensees.py"}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
