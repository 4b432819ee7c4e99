"""Work-precision study of chaospound's integrators (speed against accuracy).

For every integrator (Dormand-Prince 5(4) "dopri5", Cash-Karp 5(4) with
Press's error scaling "cash-karp", Dormand-Prince 8(5,3) "dop853") over
rtol = 1e-2 .. 1e-10 (atol = ATOL_PER_RTOL * rtol), and fixed-step "rk4"
over steps_per_cycle = 50 .. 20000, the error against a tight reference
(dop853, rtol 1e-13, atol 1e-15) is measured together with the work (time:
minimum over several repeats of the wall clock and of the CPU time, see
:func:`timed`; right-hand-side evaluations: deterministic) on four problems:

(a) impact velocities of a periodic steady state (40 + 8 cycles from rest):
    fig3a (group-periodic 3-1) and fig4 at period_ratio 1.3 (periodic 1-1);
    error = max |V - V_ref| / max |V_ref| over the impacts of the record
    window matched by order; a different impact count is a failure;
(b) the state of the chaotic scene fig4 at period_ratio 0.9 after 6 cycles
    from rest (the strobe of transient 5 + record 1); relative error in the
    length-scaled norm (rotations times the radius of gyration);
(c) the largest Lyapunov exponent of fig4 at 0.9 (k = 1, 40 cycles of
    transient, 20 of alignment, 200 averaged): |lambda - lambda_ref| against
    the combined standard error sqrt(sigma^2 + sigma_ref^2);
(d) the 200-point fig4 scan period_ratio = 0.3:2.0#200 (40 + 8 cycles from
    rest, "window" classification): fraction of points whose regime label
    (regime and n-P) differs from the reference scan, and fraction whose
    number of impacts in the record window differs.

Also: the paper's setting (Cash-Karp, rtol 1e-3, i.e. Press's 0.1 %; with and
without landing on the contact kinks), the effect of restart_at_kinks on
(a) and (b), the effect of atol, and the reference's own error (dop853 at
rtol 1e-12 against rtol 1e-13). The recommended defaults follow from a rule
stated in :func:`recommend`.

Outputs (``--output-dir``, default results/work_precision/): work_precision.json
(every number), table.md (Markdown tables), error_vs_time.png,
error_vs_rhs.png, restart.png.

Usage::

    python benchmarks/work_precision.py            # full study, ~10 min on 2 cores
    python benchmarks/work_precision.py --quick    # smoke run, < 60 s (fewer points)

Timings are minima over repeats on whatever machine runs this (the figures
use CPU time, which other processes on shared cores do not inflate as much as
the wall clock); only the rhs evaluation counts are reproducible.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from chaospound.dynamics.lyapunov import lyapunov_spectrum
from chaospound.scene import (
    DEFAULT_RTOL,
    PAPER_RTOL,
    STATE_NAMES,
    Scene,
    load_preset,
)
from chaospound.simulate import SimulationError, simulate
from chaospound.store import open_sweep
from chaospound.sweep import SweepSpec, parse_axis, run_sweep

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUTPUT = ROOT / "results" / "work_precision"

REFERENCE = {"method": "dop853", "rtol": 1e-13, "atol": 1e-15}
REFERENCE_CHECK = {"method": "dop853", "rtol": 1e-12, "atol": 1e-14}
ATOL_PER_RTOL = 1e-3  #: atol = ATOL_PER_RTOL * rtol for every adaptive run of the study
ADAPTIVE = ("dopri5", "cash-karp", "dop853")
RTOLS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
RK4_STEPS = (50, 100, 200, 400, 800, 1600, 3200, 6400, 20000)
RK4_SWEEP_MAX = 3200  #: rk4 scans beyond this cost minutes each: skipped in (d)
RESTART_RTOLS = (1e-6, 1e-8, 1e-10)  #: the restart table of the issue
ATOL_STUDY = {"methods": ("dopri5", "dop853"), "rtols": (1e-6, 1e-9),
              "ratios": (1.0, 1e-3, 1e-6)}

REGULAR = ("periodic", "group-periodic", "none")  #: regime names with a reproducible count
PERIODIC_SCENES = {"fig3a": ("fig3a", {}), "fig4_r1.3": ("fig4", {"period_ratio": 1.3})}
CHAOTIC = ("fig4", {"period_ratio": 0.9})
CHAOTIC_TRANSIENT, CHAOTIC_RECORD = 5, 1
LYAP_CYCLES, LYAP_ALIGN = 200, 20
LYAP_REF_CYCLES = 2000  #: the reference exponent averages 10x longer: sigma_ref ~ sigma / 3
SCAN_AXIS = "period_ratio=0.3:2.0#200"

#: acceptance rule of the recommended defaults (see recommend())
MAX_LABEL_MISMATCH = 0.01  #: (d) regime labels agree on >= 99 % of the scan
MAX_COUNT_MISMATCH = 0.01  #: (d) impact counts agree on >= 99 % of the scan
MAX_VELOCITY_ERROR = 1e-4  #: (a) relative impact-velocity error on both periodic scenes
LYAP_SIGMAS = 3.0  #: (c) |lambda - lambda_ref| within 3 combined standard errors

METHOD_STYLE = {
    "dopri5": ("tab:blue", "o"),
    "cash-karp": ("tab:orange", "s"),
    "dop853": ("tab:green", "^"),
    "rk4": ("tab:purple", "D"),
}


# ===================================================================== settings
@dataclass(frozen=True)
class Setting:
    """One solver configuration of the study."""

    method: str
    rtol: float | None = None  # adaptive methods
    atol: float | None = None
    steps_per_cycle: int | None = None  # rk4
    restart: bool = True
    tag: str = ""  # "paper", "paper-through", "reference", ...

    @property
    def key(self) -> str:
        if self.method == "rk4":
            base = f"rk4/spc={self.steps_per_cycle}"
        else:
            base = f"{self.method}/rtol={self.rtol:.0e}/atol={self.atol:.0e}"
        return base + ("" if self.restart else "/through")

    @property
    def label(self) -> str:
        if self.method == "rk4":
            text = f"rk4 {self.steps_per_cycle}/cycle"
        else:
            text = f"{self.method} {self.rtol:.0e}"
        return text + ("" if self.restart else " (through kinks)")

    def apply(self, scene: Scene) -> Scene:
        flat: dict[str, object] = {"method": self.method, "restart_at_kinks": self.restart}
        if self.method == "rk4":
            flat["steps_per_cycle"] = self.steps_per_cycle
        else:
            flat["rtol"] = self.rtol
            flat["atol"] = self.atol
        return scene.with_params(**flat)


def adaptive(method: str, rtol: float, restart: bool = True, atol: float | None = None,
             tag: str = "") -> Setting:
    return Setting(method, rtol=rtol, atol=ATOL_PER_RTOL * rtol if atol is None else atol,
                   restart=restart, tag=tag)


def rk4(steps: int) -> Setting:
    return Setting("rk4", steps_per_cycle=steps)


# ====================================================================== timing
def n_repeats(first_wall: float, quick: bool) -> int:
    """Repeats for a timing: more for short runs (noise), fewer for long ones (budget)."""
    if quick:
        return 3 if first_wall < 0.05 else 2 if first_wall < 0.3 else 1
    if first_wall < 0.05:
        return 15
    if first_wall < 0.3:
        return 7
    if first_wall < 3.0:
        return 3
    if first_wall < 20.0:
        return 1 if quick else 2
    return 1


def timed(fn, quick: bool):
    """(result of the first call, {wall_s, cpu_s, repeats}).

    wall_s and cpu_s are minima over the repeats of the wall-clock and of the
    process CPU time. Every run here is single-threaded, so cpu_s is the wall
    time the run takes on an idle core; it does not count the time spent
    waiting while other processes hold the (shared) cores.
    """
    wall = cpu = math.inf
    result = None
    repeats = 1
    i = 0
    while i < repeats:
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall = min(wall, time.perf_counter() - w0)
        cpu = min(cpu, time.process_time() - c0)
        if i == 0:
            result = out
            repeats = n_repeats(wall, quick)
        i += 1
    return result, {"wall_s": wall, "cpu_s": cpu, "repeats": repeats}


# ===================================================================== problems
class Problems:
    """The four problems, their reference solutions and the error of a setting."""

    def __init__(self, quick: bool, workdir: str) -> None:
        self.quick = quick
        self.workdir = workdir
        self.periodic = {name: load_preset(p).with_params(**kw)
                         for name, (p, kw) in PERIODIC_SCENES.items()}
        self.chaotic = load_preset(CHAOTIC[0]).with_params(**CHAOTIC[1])
        self.scan_base = load_preset("fig4")
        self.scan_axis = SCAN_AXIS if not quick else "period_ratio=0.3:2.0#30"
        self.lyap_cycles = LYAP_CYCLES if not quick else 60
        self.lyap_ref_cycles = LYAP_REF_CYCLES if not quick else 300
        d = self.chaotic.to_dict()
        names = STATE_NAMES[self.chaotic.model_id()]
        self.weights = np.array([d["gyration_A"] if n.endswith("th_A") else
                                 d["gyration_B"] if n.endswith("th_B") else 1.0
                                 for n in names])
        self.ref: dict = {}
        self._sweep_counter = 0

    # ---------------------------------------------------------------- runs
    def run_periodic(self, name: str, setting: Setting) -> dict:
        scene = setting.apply(self.periodic[name])
        try:
            sim, timing = timed(lambda: simulate(scene), self.quick)
        except SimulationError as exc:
            return {"failed": True, "reason": str(exc)[:200]}
        return {"failed": False, "velocity": sim.impacts.velocity.copy(),
                "corner": sim.impacts.corner.copy(), **timing,
                "rhs_evals": sim.stats.rhs_evals, "steps": sim.stats.steps,
                "rejected": sim.stats.rejected}

    def run_chaotic(self, setting: Setting) -> dict:
        scene = setting.apply(self.chaotic)
        run = lambda: simulate(scene, transient=CHAOTIC_TRANSIENT, record=CHAOTIC_RECORD)  # noqa: E731
        try:
            sim, timing = timed(run, self.quick)
        except SimulationError as exc:
            return {"failed": True, "reason": str(exc)[:200]}
        return {"failed": False, "state": sim.strobe.state[-1].copy(), **timing,
                "rhs_evals": sim.stats.rhs_evals, "steps": sim.stats.steps}

    def run_lyapunov(self, setting: Setting, cycles: int | None = None) -> dict:
        scene = setting.apply(self.chaotic)
        cycles = self.lyap_cycles if cycles is None else cycles
        run = lambda: lyapunov_spectrum(scene, k=1, cycles=cycles,  # noqa: E731
                                        tangent_transient=LYAP_ALIGN)
        try:
            spec, timing = timed(run, self.quick)
        except SimulationError as exc:
            return {"failed": True, "reason": str(exc)[:200]}
        return {"failed": False, "exponent": spec.max_exponent, "sigma": spec.max_error,
                "cycles": cycles,
                **timing, "rhs_evals": spec.rhs_evals,
                "steps": spec.steps}

    def run_scan(self, setting: Setting) -> dict:
        scene = setting.apply(self.scan_base)
        spec = SweepSpec(axes=(parse_axis(self.scan_axis, scene),), classify="window")
        self._sweep_counter += 1
        path = os.path.join(self.workdir, f"scan{self._sweep_counter}.h5")
        run = lambda: run_sweep(scene, spec, path, workers=1, progress=False,  # noqa: E731
                                overwrite=True)
        _, timing = timed(run, self.quick)
        f = open_sweep(path)
        labels = []
        for regime, n, p in zip(f.regimes(), f.array("impacts_per_period"),
                                f.array("period_cycles"), strict=True):
            labels.append(f"{regime} {n}-{p}" if regime in ("periodic", "group-periodic")
                          else regime)
        status = f.status()
        out = {"failed": False, "labels": labels,
               "impact_count": f.array("impact_count").astype(int).tolist(),
               "velocities": [v.tolist() for v in f.impact_velocities()],
               "point_failures": int(sum(s != "done" for s in status)),
               **timing,
               "rhs_evals": int(f.array("rhs_evals").sum()),
               "steps": int(f.array("steps").sum()),
               "period_ratio": f.grid["period_ratio"].tolist()}
        os.remove(path)
        return out

    # ------------------------------------------------------------- reference
    def compute_reference(self, setting: Setting) -> None:
        self.ref = {"periodic": {n: self.run_periodic(n, setting) for n in self.periodic},
                    "chaotic": self.run_chaotic(setting),
                    "lyapunov": self.run_lyapunov(setting, self.lyap_ref_cycles),
                    "scan": self.run_scan(setting)}
        for part in ("chaotic", "lyapunov", "scan"):
            if self.ref[part]["failed"]:
                raise RuntimeError(f"reference failed on {part}: {self.ref[part]['reason']}")
        for name, r in self.ref["periodic"].items():
            if r["failed"]:
                raise RuntimeError(f"reference failed on {name}: {r['reason']}")

    # ---------------------------------------------------------------- errors
    def evaluate(self, setting: Setting, parts=("a", "b", "c", "d")) -> dict:
        out: dict = {"setting": asdict(setting), "key": setting.key, "label": setting.label}
        if "a" in parts:
            out["a"] = {n: self.periodic_error(n, self.run_periodic(n, setting))
                        for n in self.periodic}
        if "b" in parts:
            out["b"] = self.chaotic_error(self.run_chaotic(setting))
        if "c" in parts:
            out["c"] = self.lyapunov_error(self.run_lyapunov(setting))
        if "d" in parts:
            out["d"] = self.scan_error(self.run_scan(setting))
        return out

    def periodic_error(self, name: str, run: dict) -> dict:
        ref = self.ref["periodic"][name]
        res = {k: v for k, v in run.items() if k not in ("velocity", "corner")}
        if run["failed"]:
            res["error"] = None
            return res
        v, v_ref = run["velocity"], ref["velocity"]
        res["impacts"] = int(v.size)
        res["impacts_ref"] = int(v_ref.size)
        if v.size != v_ref.size:
            res.update(failed=True, reason=f"{v.size} impacts, reference {v_ref.size}",
                       error=None)
            return res
        abs_err = float(np.max(np.abs(v - v_ref))) if v.size else 0.0
        res["error_abs"] = abs_err
        res["error"] = abs_err / float(np.max(np.abs(v_ref)))
        res["corners_agree"] = bool(np.array_equal(run["corner"], ref["corner"]))
        return res

    def chaotic_error(self, run: dict) -> dict:
        res = {k: v for k, v in run.items() if k != "state"}
        if run["failed"]:
            res["error"] = None
            return res
        w = self.weights
        y, y_ref = run["state"] * w, self.ref["chaotic"]["state"] * w
        res["error"] = float(np.linalg.norm(y - y_ref) / np.linalg.norm(y_ref))
        return res

    def lyapunov_error(self, run: dict) -> dict:
        res = dict(run)
        if run["failed"]:
            res["error"] = None
            return res
        ref = self.ref["lyapunov"]
        res["error"] = abs(run["exponent"] - ref["exponent"])
        res["sigma_combined"] = math.hypot(run["sigma"], ref["sigma"])
        res["z"] = res["error"] / res["sigma_combined"]
        return res

    def scan_error(self, run: dict) -> dict:
        ref = self.ref["scan"]
        labels, labels_ref = run["labels"], ref["labels"]
        n = len(labels_ref)
        diff = [i for i in range(n) if labels[i] != labels_ref[i]]
        counts = [i for i in range(n) if run["impact_count"][i] != ref["impact_count"][i]]
        # points whose reference response is regular (periodic, group-periodic or no impact):
        # there the impact count is a property of the attractor; on aperiodic ("unresolved",
        # chaotic) points any perturbation changes it, whatever the tolerance
        regular = [i for i in range(n) if labels_ref[i].split(" ")[0] in REGULAR]
        counts_regular = [i for i in counts if i in regular]
        # impact velocities where both runs are periodic with the same impacts
        v_err = []
        for i in range(n):
            if (i in counts or labels_ref[i].split(" ")[0] not in ("periodic", "group-periodic")
                    or labels[i] != labels_ref[i] or not ref["velocities"][i]):
                continue
            v, vr = np.array(run["velocities"][i]), np.array(ref["velocities"][i])
            v_err.append(float(np.max(np.abs(v - vr)) / np.max(np.abs(vr))))
        return {
            "failed": False,
            "points": n,
            "label_mismatch": len(diff) / n,
            "count_mismatch": len(counts_regular) / len(regular) if regular else 0.0,
            "regular_points": len(regular),
            "count_mismatch_all": len(counts) / n,
            "error": len(diff) / n,
            "differing_points": [{"index": i, "period_ratio": ref["period_ratio"][i],
                                  "label": labels[i], "label_ref": labels_ref[i],
                                  "impacts": run["impact_count"][i],
                                  "impacts_ref": ref["impact_count"][i]}
                                 for i in sorted(set(diff) | set(counts))],
            "periodic_velocity_error_max": max(v_err) if v_err else None,
            "periodic_points_compared": len(v_err),
            "point_failures": run["point_failures"],
            "wall_s": run["wall_s"], "cpu_s": run["cpu_s"], "repeats": run["repeats"],
            "rhs_evals": run["rhs_evals"], "steps": run["steps"],
        }


# ==================================================================== the study
def study_settings(quick: bool) -> tuple[list[Setting], list[Setting]]:
    rtols = (1e-3, 1e-6, 1e-9) if quick else RTOLS
    steps = (100, 400, 800) if quick else RK4_STEPS
    main = [adaptive(m, r) for m in ADAPTIVE for r in rtols]
    main += [rk4(s) for s in steps]
    extra = [adaptive("cash-karp", PAPER_RTOL, restart=False, tag="paper-through"),
             Setting(**{**REFERENCE_CHECK, "tag": "reference-check"})]
    return main, extra


def run_study(quick: bool, log) -> dict:
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="work_precision_") as workdir:
        problems = Problems(quick, workdir)
        log("warm-up (numba cache) ...")
        for s in [adaptive(m, 1e-3) for m in ADAPTIVE] + [rk4(100)]:
            simulate(s.apply(problems.periodic["fig3a"]), transient=1, record=1)
        lyapunov_spectrum(problems.chaotic, k=1, cycles=10, tangent_transient=2, transient=1)

        reference = Setting(**REFERENCE, tag="reference")
        log(f"reference {reference.label} ...")
        problems.compute_reference(reference)
        ref_summary = {
            "setting": asdict(reference),
            "periodic": {n: {k: v for k, v in r.items() if k not in ("velocity", "corner")}
                         | {"velocity": r["velocity"].tolist()}
                         for n, r in problems.ref["periodic"].items()},
            "chaotic": {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                        for k, v in problems.ref["chaotic"].items()},
            "lyapunov": problems.ref["lyapunov"],
            "scan": {k: problems.ref["scan"][k] for k in
                     ("labels", "impact_count", "point_failures", "wall_s", "cpu_s", "rhs_evals",
                      "steps", "period_ratio")},
        }

        main, extra = study_settings(quick)
        results = []
        for s in main + extra:
            parts = ("a", "b", "c", "d")
            if s.method == "rk4" and s.steps_per_cycle > RK4_SWEEP_MAX:
                parts = ("a", "b", "c")
            t0 = time.perf_counter()
            r = problems.evaluate(s, parts)
            r["tag"] = s.tag or ("paper" if s.method == "cash-karp" and s.rtol == PAPER_RTOL
                                 and s.restart else "")
            results.append(r)
            log(f"{s.label:32s} {_brief(r)}  [{time.perf_counter() - t0:.1f} s]")

        log("restart at kinks: on vs off ...")
        restart = []
        rtols = (1e-6,) if quick else RTOLS
        for m in ADAPTIVE:
            for rt in rtols:
                row = {"method": m, "rtol": rt}
                for flag in (True, False):
                    r = problems.evaluate(adaptive(m, rt, restart=flag), ("a", "b"))
                    row["on" if flag else "off"] = {"a": r["a"], "b": r["b"]}
                restart.append(row)
                log(f"  {m} {rt:.0e}: " + ", ".join(
                    f"{k} fig3a {_fmt(row[k]['a']['fig3a'].get('error'))}" for k in ("on", "off")))

        log("atol ...")
        atol_rows = []
        for m in ATOL_STUDY["methods"]:
            for rt in () if quick else ATOL_STUDY["rtols"]:
                for ratio in ATOL_STUDY["ratios"]:
                    r = problems.evaluate(adaptive(m, rt, atol=ratio * rt), ("a", "b"))
                    atol_rows.append({"method": m, "rtol": rt, "atol": ratio * rt,
                                      "atol_per_rtol": ratio, "a": r["a"], "b": r["b"]})

    doc = {
        "description": __doc__.split("\n\n")[0],
        "quick": quick,
        "machine": {"cpu_count": os.cpu_count(), "platform": platform.platform(),
                    "python": sys.version.split()[0]},
        "definitions": {
            "reference": REFERENCE, "atol_per_rtol": ATOL_PER_RTOL,
            "a": "max |V - V_ref| / max |V_ref| over the record window's impacts "
                 "(40 + 8 cycles from rest), matched by order; different count = failure",
            "b": f"relative error of the state after {CHAOTIC_TRANSIENT + CHAOTIC_RECORD} cycles "
                 "from rest, rotations scaled by the radius of gyration",
            "c": f"|lambda - lambda_ref| (k=1, {problems.lyap_cycles} cycles after 40 + "
                 f"{LYAP_ALIGN}; the reference averages {problems.lyap_ref_cycles} cycles); "
                 "sigma_combined = hypot(sigma, sigma_ref), z = error / sigma_combined",
            "d": f"fraction of the scan {problems.scan_axis} (40 + 8 cycles, window "
                 "classification) whose label (regime n-P) or impact count differs",
            "wall_s": "wall-clock time, minimum over repeats (see 'repeats'); 2 shared cores: "
                      "includes waiting for the cores when other processes run",
            "cpu_s": "process CPU time, minimum over the same repeats: the wall time on an "
                     "idle core (single-threaded runs); the time axis of the figures",
            "load_average": os.getloadavg(),
            "rhs_evals": "deterministic; (c) counts the tangent run only, (d) the whole scan",
        },
        "scenes": {"a": {n: f"{p} {kw}" for n, (p, kw) in PERIODIC_SCENES.items()},
                   "b": f"{CHAOTIC[0]} {CHAOTIC[1]}", "c": f"{CHAOTIC[0]} {CHAOTIC[1]}",
                   "d": f"fig4 {problems.scan_axis}"},
        "reference": ref_summary,
        "results": results,
        "restart": restart,
        "atol": atol_rows,
        "current_defaults": {"method": "dopri5", "rtol": DEFAULT_RTOL,
                             "atol": ATOL_PER_RTOL * DEFAULT_RTOL},
        "compute_s": None,
    }
    doc["lyapunov_statistics"] = lyapunov_statistics(doc)
    doc["recommendation"] = recommend(doc)
    doc["compute_s"] = time.perf_counter() - t_start
    return doc


# ============================================================== recommendation
def lyapunov_statistics(doc: dict) -> dict:
    """Scatter of the exponent over the settings that pass (a) and (d): is sigma honest?

    Where the tolerance no longer matters, the exponents of the different settings
    are independent-looking samples of the same average (their trajectories part
    within a few dozen cycles): their spread should match the block error bar.
    """
    rows = [r for r in doc["results"] if not r["c"]["failed"] and passes(r)["a"]
            and r["tag"] != "reference-check"]
    lam = np.array([r["c"]["exponent"] for r in rows])
    sig = np.array([r["c"]["sigma"] for r in rows])
    if lam.size < 2:
        return {"runs": int(lam.size)}
    return {"runs": int(lam.size), "mean": float(lam.mean()), "std": float(lam.std(ddof=1)),
            "median_sigma": float(np.median(sig)),
            "reference": doc["reference"]["lyapunov"]["exponent"],
            "reference_sigma": doc["reference"]["lyapunov"]["sigma"],
            "settings": [r["label"] for r in rows]}


def passes(r: dict) -> dict:
    """The acceptance rule, criterion by criterion (None: not measured)."""
    a_ok = all(x.get("error") is not None and not x["failed"] and x["error"] <= MAX_VELOCITY_ERROR
               for x in r["a"].values())
    c = r["c"]
    c_ok = (not c["failed"]) and c["error"] <= LYAP_SIGMAS * c["sigma_combined"]
    d = r.get("d")
    d_ok = None if d is None else (d["label_mismatch"] <= MAX_LABEL_MISMATCH
                                   and d["count_mismatch"] <= MAX_COUNT_MISMATCH
                                   and d["point_failures"] == 0)
    return {"a": a_ok, "c": c_ok, "d": d_ok,
            "all": bool(a_ok and c_ok and d_ok)}


def recommend(doc: dict) -> dict:
    """Loosest setting per method that passes, and whose tighter settings all pass.

    Rule: (a) relative impact-velocity error <= 1e-4 on both periodic scenes;
    (c) the exponent within 3 combined standard errors of the reference's;
    (d) regime labels and impact counts agree with the reference scan on
    >= 99 % of the points, no failed point. Per method, the loosest rtol (or
    fewest rk4 steps) that passes *and after which every tighter setting of
    the study passes (a) and (d) too* (no lucky isolated passes). (c) is a
    3-sigma test of a noisy estimate, repeated on every setting: a tighter
    setting that misses it by chance (z of 3 to 4 happens among ~40 settings)
    does not veto looser ones. The default is the passing setting with the
    smallest scan time (CPU time of the scan, the wall time on an idle core;
    ties, within 15 %, go to fewer rhs evaluations).
    """
    per_method = {}
    for m in (*ADAPTIVE, "rk4"):
        rows = [r for r in doc["results"] if r["setting"]["method"] == m and not r["tag"]
                or (r["setting"]["method"] == m and r["tag"] == "paper")]
        rows = [r for r in rows if r["setting"]["restart"] and "d" in r]
        # loosest first
        rows.sort(key=lambda r: -(r["setting"]["rtol"] or 0.0) if m != "rk4"
                  else r["setting"]["steps_per_cycle"])
        verdicts = [passes(r) for r in rows]
        ok = [v["all"] for v in verdicts]
        deterministic = [bool(v["a"] and v["d"]) for v in verdicts]
        chosen = None
        for i in range(len(rows)):
            if ok[i] and all(deterministic[i:]):
                chosen = rows[i]
                break
        per_method[m] = None if chosen is None else {
            "key": chosen["key"], "label": chosen["label"], "setting": chosen["setting"],
            "scan_cpu_s": chosen["d"]["cpu_s"], "scan_wall_s": chosen["d"]["wall_s"],
            "scan_rhs_evals": chosen["d"]["rhs_evals"],
            "a_error": max(x["error"] for x in chosen["a"].values()),
            "b_error": chosen["b"]["error"], "c_z": chosen["c"]["z"],
            "d_label_mismatch": chosen["d"]["label_mismatch"],
            "d_count_mismatch": chosen["d"]["count_mismatch"],
        }
    candidates = [v for v in per_method.values() if v is not None]
    best = None
    if candidates:
        fastest = min(c["scan_cpu_s"] for c in candidates)
        close = [c for c in candidates if c["scan_cpu_s"] <= 1.15 * fastest]
        best = min(close, key=lambda c: c["scan_rhs_evals"])
    return {"rule": recommend.__doc__.split("\n\n", 1)[1].strip(),
            "per_method": per_method, "default": best}


# ======================================================================= output
def _fmt(x, digits=1) -> str:
    if x is None:
        return "fail"
    if x == 0:
        return "0"
    return f"{x:.{digits}e}"


def _brief(r: dict) -> str:
    a = " ".join(_fmt(x.get("error")) for x in r["a"].values())
    b = _fmt(r["b"].get("error"))
    c = "fail" if r["c"]["failed"] else f"{r['c']['error']:.3f}(z={r['c']['z']:.1f})"
    d = "-" if "d" not in r else (f"{100 * r['d']['label_mismatch']:.1f}%/"
                                  f"{100 * r['d']['count_mismatch']:.1f}%")
    return f"a {a} | b {b} | c {c} | d {d}"


def _lyap_sentence(st: dict) -> str:
    if st.get("runs", 0) < 2:
        return ""
    return (f"Over the {st['runs']} settings that pass (a), the exponents scatter by "
            f"{st['std']:.4f} (mean {st['mean']:.4f}) against a median error bar of "
            f"{st['median_sigma']:.4f}: the block error bar is honest, and differences below "
            "it say nothing about the tolerance.")


def _compress(labels: list[str]) -> str:
    """'cash-karp 1e-02', 'cash-karp 1e-03', ... -> 'cash-karp 1e-02 .. 1e-10 (9)'."""
    groups: dict[str, list[str]] = {}
    for lab in labels:
        head, _, tail = lab.partition(" ")
        groups.setdefault(head, []).append(tail)
    parts = []
    for head, tails in groups.items():
        parts.append(f"{head} {tails[0]}" if len(tails) == 1
                     else f"{head} {tails[0]} .. {tails[-1]} ({len(tails)})")
    return "\n".join(parts)


def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.1f}"


def _wall(x: dict | None, key="cpu_s") -> str:
    """A time in milliseconds."""
    if x is None or x.get(key) is None:
        return "-"
    return f"{x[key] * 1e3:.1f}"


def make_tables(doc: dict) -> str:
    ref = doc["reference"]
    lines = ["# Work-precision tables", "",
             f"Generated by `benchmarks/work_precision.py{' --quick' if doc['quick'] else ''}`; "
             f"reference: dop853 rtol 1e-13 atol 1e-15; adaptive runs use atol = "
             f"{ATOL_PER_RTOL:g} rtol (Cash-Karp: Press's scaling with atol as its floor).",
             "Errors: (a) max relative impact-velocity error, fig3a / fig4 r=1.3; (b) relative "
             "state error after 6 cycles, fig4 r=0.9; (c) |lambda - lambda_ref| per unit time "
             "and z = that / combined standard error; (d) % of the scan points whose regime "
             "label differs / impact count differs among the points the reference finds regular "
             "(periodic, group-periodic, no impact) / among all points (aperiodic points change "
             "their count under any perturbation); (d) V periodic: max relative impact-velocity "
             "error over the periodic points of the scan with the reference's label. "
             "`fail`: run failed or impact count differs.",
             f"Reference: lambda_ref = {ref['lyapunov']['exponent']:.4f} +- "
             f"{ref['lyapunov']['sigma']:.4f} per unit time ({ref['lyapunov']['cycles']} cycles). "
             + _lyap_sentence(doc.get("lyapunov_statistics", {})), "",
             "## Errors and cost", "",
             "| setting | (a) fig3a | (a) fig4 1.3 | (b) | (c) abs err (z) | (d) labels % | "
             "(d) counts % regular | (d) counts % all | (d) V periodic | time (a) fig3a ms | "
             "rhs (a) fig3a | time (d) scan s | wall (d) scan s | rhs (d) scan |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in doc["results"]:
        tag = {"paper": " **(paper)**", "paper-through": " **(paper, through kinks)**",
               "reference-check": " (reference check)"}.get(r["tag"], "")
        a = r["a"]
        c = r["c"]
        cs = "fail" if c["failed"] else f"{c['error']:.3f} ({c['z']:.1f})"
        d = r.get("d")
        scan_wall = "- | -" if d is None else f"{d['cpu_s']:.2f} | {d['wall_s']:.2f}"
        scan_rhs = "-" if d is None else d["rhs_evals"]
        lines.append(
            f"| {r['label']}{tag} | {_fmt(a['fig3a'].get('error'))} | "
            f"{_fmt(a['fig4_r1.3'].get('error'))} | {_fmt(r['b'].get('error'))} | {cs} | "
            f"{_pct(d and d['label_mismatch'])} | {_pct(d and d['count_mismatch'])} | "
            f"{_pct(d and d['count_mismatch_all'])} | "
            f"{'-' if d is None else _fmt(d['periodic_velocity_error_max'])} | "
            f"{_wall(a['fig3a'], 'cpu_s')} | {a['fig3a'].get('rhs_evals', '-')} | "
            f"{scan_wall} | {scan_rhs} |")
    lines += ["", "## Cost of the other problems", "",
              "| setting | time (a) fig4 1.3 ms | rhs | time (b) ms | rhs | time (c) s | "
              "rhs (tangent run) |", "|---|---|---|---|---|---|---|"]
    for r in doc["results"]:
        a2, b, c = r["a"]["fig4_r1.3"], r["b"], r["c"]
        c_wall = "-" if c["failed"] else f"{c['cpu_s']:.3f}"
        lines.append(f"| {r['label']} | {_wall(a2)} | {a2.get('rhs_evals', '-')} | {_wall(b)} | "
                     f"{b.get('rhs_evals', '-')} | "
                     f"{c_wall} | "
                     f"{c.get('rhs_evals', '-')} |")
    lines += ["", "## Restart at the contact kinks (on: steps end on every end-penetration "
              "zero crossing; off: step through)", "",
              "| method | rtol | (a) fig3a on | off | (a) fig4 1.3 on | off | (b) on | off | "
              "steps fig3a on | off | rhs fig3a on | off |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in doc["restart"]:
        on, off = row["on"], row["off"]
        lines.append(
            f"| {row['method']} | {row['rtol']:.0e} | {_fmt(on['a']['fig3a'].get('error'))} | "
            f"{_fmt(off['a']['fig3a'].get('error'))} | {_fmt(on['a']['fig4_r1.3'].get('error'))} | "
            f"{_fmt(off['a']['fig4_r1.3'].get('error'))} | {_fmt(on['b'].get('error'))} | "
            f"{_fmt(off['b'].get('error'))} | {on['a']['fig3a'].get('steps', '-')} | "
            f"{off['a']['fig3a'].get('steps', '-')} | {on['a']['fig3a'].get('rhs_evals', '-')} | "
            f"{off['a']['fig3a'].get('rhs_evals', '-')} |")
    lines += ["", "## atol (restart on)", "",
              "| method | rtol | atol | (a) fig3a | (a) fig4 1.3 | (b) | rhs fig3a | rhs (b) |",
              "|---|---|---|---|---|---|---|---|"]
    for row in doc["atol"]:
        lines.append(
            f"| {row['method']} | {row['rtol']:.0e} | {row['atol']:.0e} | "
            f"{_fmt(row['a']['fig3a'].get('error'))} | "
            f"{_fmt(row['a']['fig4_r1.3'].get('error'))} | "
            f"{_fmt(row['b'].get('error'))} | {row['a']['fig3a'].get('rhs_evals', '-')} | "
            f"{row['b'].get('rhs_evals', '-')} |")
    rec = doc["recommendation"]
    lines += ["", "## Recommendation", "", rec["rule"], "",
              "| method | loosest passing setting | scan time s | scan rhs | (a) max | (b) | "
              "(c) z | (d) labels % | (d) counts % |", "|---|---|---|---|---|---|---|---|---|"]
    for m, v in rec["per_method"].items():
        if v is None:
            lines.append(f"| {m} | none passes | | | | | | | |")
            continue
        lines.append(f"| {m} | {v['label']} | {v['scan_cpu_s']:.2f} | {v['scan_rhs_evals']} | "
                     f"{_fmt(v['a_error'])} | {_fmt(v['b_error'])} | {v['c_z']:.1f} | "
                     f"{_pct(v['d_label_mismatch'])} | {_pct(v['d_count_mismatch'])} |")
    best = rec["default"]
    lines += ["", f"Default by the rule: **{best['label'] if best else 'none'}**"
              + ("" if best is None else f" (atol {best['setting']['atol']:.0e})"), ""]
    cur = doc["current_defaults"]
    if best is not None:
        same = (cur["method"] == best["setting"]["method"]
                and math.isclose(cur["rtol"], best["setting"]["rtol"])
                and math.isclose(cur["atol"], best["setting"]["atol"]))
        lines += [f"Code defaults when this ran (chaospound.scene): {cur['method']}, rtol "
                  f"{cur['rtol']:.0e}, atol {cur['atol']:.0e}: "
                  f"{'the same' if same else 'DIFFERENT from the rule'}.", ""]
    return "\n".join(lines)


def make_figures(doc: dict, outdir: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    def counts(r):
        return None if r.get("d") is None else {**r["d"], "error": r["d"]["count_mismatch"]}

    panels = [
        ("(a) impact velocity, fig3a (3-1)", lambda r: r["a"]["fig3a"],
         "rel. error max|V-V_ref|/max|V_ref|"),
        ("(a) impact velocity, fig4 r=1.3 (1-1)", lambda r: r["a"]["fig4_r1.3"], "rel. error"),
        ("(b) state after 6 cycles, fig4 r=0.9", lambda r: r["b"], "rel. error"),
        ("(c) largest Lyapunov exponent, fig4 r=0.9", lambda r: r["c"], "|lambda - lambda_ref|"),
        ("(d) fig4 scan: regime labels differing", lambda r: r.get("d"), "fraction of points"),
        ("(d) fig4 scan: impact counts differing (regular pts)", counts, "fraction of points"),
    ]
    files = []
    main = [r for r in doc["results"] if not r["tag"] or r["tag"] == "paper"]
    special = [r for r in doc["results"] if r["tag"] in ("paper", "paper-through")]
    rec = doc["recommendation"]["default"]
    n_scan = doc["reference"]["scan"]["labels"].__len__()
    for xkey, xlabel, fname in (("cpu_s", "CPU time per run (s)", "error_vs_time.png"),
                                ("rhs_evals", "right-hand-side evaluations", "error_vs_rhs.png")):
        fig, axes = plt.subplots(2, 3, figsize=(16, 9.5))
        for ax, (title, get, ylabel) in zip(axes.ravel(), panels, strict=True):
            finite = [get(r)["error"] for r in doc["results"] if get(r) is not None
                      and not get(r).get("failed") and get(r).get("error")]
            top = 10 ** (math.ceil(math.log10(max(finite))) + 1) if finite else 1.0
            is_frac = title.startswith("(d)")
            floor = 0.25 / n_scan if is_frac else None
            no_x: list[str] = []
            if is_frac:
                top = 2.0
            for m in (*ADAPTIVE, "rk4"):
                color, marker = METHOD_STYLE[m]
                rows = [r for r in main if r["setting"]["method"] == m and get(r) is not None]
                xs, ys, fx, zx, zy = [], [], [], [], []
                for r in rows:
                    g = get(r)
                    x = g.get(xkey)
                    if g.get("failed") or g.get("error") is None:
                        # failure: at the top when the run finished (e.g. another impact
                        # count), else listed in the panel's note
                        if x is not None:
                            fx.append(x)
                        else:
                            no_x.append(r["label"])
                        continue
                    if g["error"] == 0 and is_frac:
                        zx.append(x)
                        zy.append(floor)
                        xs.append(x)
                        ys.append(floor)
                        continue
                    xs.append(x)
                    ys.append(g["error"])
                ax.loglog(xs, ys, marker=marker, color=color, label=m, ms=5, lw=1.3)
                if fx:
                    ax.scatter(fx, [top] * len(fx), marker="x", color=color, s=50, zorder=5)
                if zx:
                    ax.scatter(zx, zy, marker=marker, facecolors="white", edgecolors=color,
                               s=40, zorder=6)
                for r in rows:  # annotate tolerances on the adaptive lines, sparsely
                    g = get(r)
                    if (g.get("failed") or g.get("error") is None or g.get(xkey) is None
                            or g["error"] == 0):
                        continue
                    s = r["setting"]
                    txt = (f"{s['rtol']:.0e}".replace("e-0", "e-") if m != "rk4"
                           else str(s["steps_per_cycle"]))
                    if m == "rk4" or (s["rtol"] in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)):
                        y = g["error"] if g["error"] > 0 else floor
                        ax.annotate(txt, (g[xkey], y), fontsize=6.5, color=color,
                                    xytext=(3, 3), textcoords="offset points")
            for r in special:
                g = get(r)
                if g is None:
                    continue
                x = g.get(xkey)
                failed = g.get("failed") or g.get("error") is None
                y = top if failed else (g["error"] if g["error"] > 0 else floor)
                if x is None:
                    if r["tag"] == "paper-through":
                        no_x.append("paper (through kinks)")
                    continue
                if r["tag"] == "paper":
                    ax.scatter([x], [y], marker="*", s=260, facecolors="gold", edgecolors="k",
                               zorder=7, label="paper: Cash-Karp 1e-3")
                else:
                    ax.scatter([x], [y], marker="*", s=260, facecolors="none", edgecolors="k",
                               zorder=7, label="paper, through kinks")
            if rec is not None:
                rr = next(r for r in doc["results"] if r["key"] == rec["key"])
                g = get(rr)
                if g is not None and not g.get("failed") and g.get(xkey) is not None:
                    y = g["error"] if g["error"] > 0 else floor
                    ax.scatter([g[xkey]], [y], marker="o", s=230, facecolors="none",
                               edgecolors="red", lw=2, zorder=8, label="recommended default")
            if title.startswith("(c)"):
                sigmas = [r["c"]["sigma"] for r in doc["results"] if not r["c"]["failed"]]
                comb = math.hypot(float(np.median(sigmas)), doc["reference"]["lyapunov"]["sigma"])
                ax.axhline(comb, color="grey", ls="--", lw=1)
                ax.axhline(LYAP_SIGMAS * comb, color="grey", ls=":", lw=1)
                ax.text(0.02, comb, " 1 combined sigma (median)",
                        transform=ax.get_yaxis_transform(), fontsize=7, va="bottom", color="grey")
                ax.text(0.02, LYAP_SIGMAS * comb, " 3 sigma", transform=ax.get_yaxis_transform(),
                        fontsize=7, va="bottom", color="grey")
            if title.startswith("(a)"):
                ax.axhline(MAX_VELOCITY_ERROR, color="grey", ls=":", lw=1)
            if is_frac:
                ax.axhline(MAX_LABEL_MISMATCH, color="grey", ls=":", lw=1)
                ax.axhline(floor, color="lightgrey", ls="-", lw=0.8)
                ax.text(0.02, floor * 0.97, " 0 points differ (open markers)",
                        transform=ax.get_yaxis_transform(), fontsize=7, va="top", color="grey")
                ax.set_ylim(floor / 2, top * 1.5)
            ax.axhline(top, color="lightgrey", lw=0.8)
            ax.text(0.02, top, " failed / impact count differs (x)",
                    transform=ax.get_yaxis_transform(), fontsize=7, va="bottom", color="grey")
            if no_x:
                ax.text(0.98, 0.02, "run failed (no result):\n" + _compress(no_x),
                        transform=ax.transAxes, fontsize=7, ha="right", va="bottom",
                        color="firebrick")
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_title(title, fontsize=10)
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            ax.grid(True, which="major", alpha=0.3)
        handles, labels = axes[0, 0].get_legend_handles_labels()
        seen = dict(zip(labels, handles, strict=True))
        fig.legend(seen.values(), seen.keys(), loc="upper center", ncol=7, fontsize=9,
                   frameon=False, bbox_to_anchor=(0.5, 0.965))
        if xkey == "cpu_s":
            fig.text(0.5, 0.005, "time per run: the minimum over repeats of the CPU time "
                     "(= the wall time on an idle core)", ha="center", fontsize=8, color="grey")
        fig.suptitle(f"chaospound work-precision (reference dop853 1e-13; atol = "
                     f"{ATOL_PER_RTOL:g} rtol){' [quick]' if doc['quick'] else ''}",
                     y=0.995, fontsize=11)
        fig.tight_layout(rect=(0, 0, 1, 0.93))
        fig.savefig(outdir / fname, dpi=110)
        plt.close(fig)
        files.append(fname)

    # restart on/off
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    for ax, (title, get) in zip(axes, (("(a) fig3a impact velocity", lambda x: x["a"]["fig3a"]),
                                       ("(a) fig4 r=1.3 impact velocity",
                                        lambda x: x["a"]["fig4_r1.3"]),
                                       ("(b) state after 6 cycles", lambda x: x["b"])),
                                strict=True):
        for m in ADAPTIVE:
            color, marker = METHOD_STYLE[m]
            rows = [r for r in doc["restart"] if r["method"] == m]
            for flag, ls, mf in (("on", "-", color), ("off", "--", "white")):
                xs = [r["rtol"] for r in rows if get(r[flag]).get("error") is not None]
                ys = [get(r[flag])["error"] for r in rows if get(r[flag]).get("error") is not None]
                ax.loglog(xs, ys, ls=ls, marker=marker, color=color, mfc=mf,
                          label=f"{m} restart {flag}")
        xs = np.array([min(RTOLS), max(RTOLS)])
        ax.loglog(xs, xs, color="grey", lw=0.8, ls=":", label="error = rtol")
        ax.loglog(xs, 10 * xs, color="grey", lw=0.8, ls="-.", label="error = 10 rtol")
        ax.invert_xaxis()
        ax.set_xlabel("rtol")
        ax.set_ylabel("relative error")
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    fig.suptitle("Landing steps on the contact kinks (restart on, solid) vs stepping through "
                 "(off, dashed, open markers)", fontsize=11)
    fig.tight_layout()
    fig.savefig(outdir / "restart.png", dpi=110)
    plt.close(fig)
    files.append("restart.png")
    return files


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="3 tolerances per method, a 30-point scan, 60 Lyapunov cycles, "
                             "no atol study (< 60 s)")
    parser.add_argument("--from-json", metavar="FILE", default=None,
                        help="rebuild table.md and the figures from a study's "
                             "work_precision.json (re-applying the rule), without running")
    parser.add_argument("--output-dir", default=None,
                        help=f"where to write (default {DEFAULT_OUTPUT}, or its 'quick' "
                             "subfolder with --quick)")
    args = parser.parse_args(argv)
    outdir = Path(args.output_dir) if args.output_dir else (
        DEFAULT_OUTPUT / "quick" if args.quick else DEFAULT_OUTPUT)
    outdir.mkdir(parents=True, exist_ok=True)

    def log(msg: str) -> None:
        print(msg, flush=True)

    if args.from_json:
        doc = json.loads(Path(args.from_json).read_text())
        doc["recommendation"] = recommend(doc)
    else:
        doc = run_study(args.quick, log)
    (outdir / "work_precision.json").write_text(json.dumps(_jsonable(doc), indent=1) + "\n")
    (outdir / "table.md").write_text(make_tables(doc))
    files = make_figures(doc, outdir)
    log(f"\n{make_tables(doc)}")
    log(f"wrote {outdir}/work_precision.json, table.md, {', '.join(files)} "
        f"(compute {doc['compute_s']:.0f} s)")


if __name__ == "__main__":
    main()
