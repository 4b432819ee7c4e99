"""Converged classification (the sweep default) against the careful classifier and
the other sweep modes.

Two parts:

``speed``: points/s of ``--classify converged``, ``full`` and ``paper`` on the
same slice of the fig4 scan (``--slice``, default T/T_Ax 0.6:1.3, the resonance
band, ``--points`` points), one worker, the modes interleaved in ``--rounds``
rounds so that the machine's load hits them alike; the ratios are the result.
``--workers2`` also times the converged slice with 2 workers against 1
(interleaved). Writes results/bench_classify.json, or ``--output``. The whole
1000-point scan of the README tour is ``--slice 0.3:2.0 --points 1000``
(results/bench_classify_scan.json).

``baseline``: the default sweep of this tree against ``--classify full`` of an older
tree (``--old``, a worktree; issue 17's baseline is da32171, the code of the day the
issue was written), both as ``chaospound sweep`` processes with one worker on the same
slice, interleaved in ``--rounds`` rounds, timed whole-process (start-up included)
after one untimed 2-point run of each that fills its kernel caches. Writes
results/bench_classify_baseline.json, or ``--output``.

``agreement``: a random sample of points from the fig4 scan (1000 points over
T/T_Ax 0.3-2.0), the fig4-translational scan (same grid) and a (T/T_Ax, gap)
map of fig4 (T/T_Ax 0.3-2.0 x gap 0.5-2.0, 200 x 200); each point is
classified as the default sweep does (from the scene's initial state,
:func:`chaospound.point.run_task`) and by the careful
adaptive classifier (:func:`chaospound.dynamics.classify.classify`,
``--careful-transient`` cycles of transient at most (default 6000: three times the
classifier's own default, so that transients of 2000-3000 cycles end inside it),
``--careful-exponent`` exponent cycles (default 400, four times that near the
3-sigma line); a point it leaves unresolved is classified again with
``--careful-escalate`` times the transient (default 4: 24000 cycles), since its
transients of thousands of cycles are what the reference must outlast). Writes
results/classify_agreement.json and .md (or ``--output`` and its .md), with the share
of agreement over all points and over the points the careful classifier names (an
"unresolved" reference has no label to agree with; it counts as a disagreement in
the first share).

``birkhoff``: the digits of the weighted Birkhoff average
(:func:`chaospound.dynamics.classify.birkhoff_digits`) on the attractors of the
fig4 scan's default sweep (1000 points, one worker): for each chaotic,
quasi-periodic and unresolved point, 1000 sections from its stored final state at
the classification's tolerances, the observable of rule 6 (the scaled sections on
their first principal direction). Writes results/classify_birkhoff.json.

``changes``: where two stores of the same scan (``--old``, ``--new``: say the default
sweep before and after a change of the classification) name a point differently,
which one the careful classifier (as in ``agreement``) supports: for each pair
(old regime, new regime), ``--per-change`` points drawn at random (``--seed``) are
classified carefully. Writes results/classify_changes.json and .md, or ``--output``
(its .md beside).

``budget``: where the default sweep of the 1000-point fig4 scan spends its time, regime
by regime (each point's own wall time, one worker), and the floor of its chaos watch:
``CHAOS_WATCH`` cycles of sections from each chaotic point's final state at
``--floor-rtol`` (1e-4, ten times looser than the watch's), against issue 17's 15x
budget (the old tree's ``--classify full`` wall time of
results/bench_classify_baseline.json over 15). Writes results/classify_budget.json.

``bound``: how far 15x is even where the classification gives up its watch and the
engine wastes nothing: the default sweep of the fig4 scan with and without the chaos
watch (interleaved), both read against the careful labels stored in the four agreement
files, and the right-hand side evaluations a step-size controller that never rejects a
step (and a free event location) could save. Writes results/classify_bound.json.

``approach``: whether the trajectories that step 3 of the converged classification
confirmed a stable orbit from go to it: for every such point of the fig4 scan, the
trajectory run on for ``--cycles`` cycles from the section Newton's method started
from, its distance to the orbit read along the way. Writes
results/classify_approach.json.

``table``: the careful classifier (:func:`~chaospound.dynamics.classify.classify`, its
defaults) at the T/T_Ax of docs/classification.md's "Measured" table, fig4 and
fig4-translational; prints the table's rows.

Run: PYTHONPATH=. python benchmarks/bench_classify.py speed --points 50 --rounds 3
     PYTHONPATH=. python benchmarks/bench_classify.py speed --slice 0.3:2.0 --points 1000 \
         --rounds 2 --output results/bench_classify_scan.json
     PYTHONPATH=. python benchmarks/bench_classify.py baseline --old <worktree> \
         --slice 0.3:2.0 --points 1000 --rounds 2
     PYTHONPATH=. python benchmarks/bench_classify.py agreement --per-set 67
     PYTHONPATH=. python benchmarks/bench_classify.py birkhoff
     PYTHONPATH=. python benchmarks/bench_classify.py table
     PYTHONPATH=. python benchmarks/bench_classify.py budget
     PYTHONPATH=. python benchmarks/bench_classify.py bound
     PYTHONPATH=. python benchmarks/bench_classify.py approach
     PYTHONPATH=. python benchmarks/bench_classify.py changes --preset fig4 \
         --old before.h5 --new after.h5 --per-change 16
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from chaospound.dynamics.classify import classify
from chaospound.point import run_task
from chaospound.scene import load_preset
from chaospound.sweep import SweepSpec, parse_axis, run_sweep

RESULTS = Path(__file__).resolve().parent.parent / "results"
MODES = ("converged", "full", "paper")


def speed(points: int, rounds: int, workers2: bool, interval: str = "0.6:1.3") -> dict:
    scene = load_preset("fig4")
    axis = parse_axis(f"period_ratio={interval}#{points}")
    times: dict[str, list[float]] = {m: [] for m in MODES}
    if workers2:
        times["converged-2-workers"] = []
    labels: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        # warm the kernels (compiled once per cache) so no mode pays for compilation
        run_sweep(scene, SweepSpec(axes=(parse_axis("period_ratio=0.7:0.8#2"),)),
                  os.path.join(tmp, "warm.h5"), progress=False)
        for r in range(rounds):
            for mode in times:
                spec = SweepSpec(axes=(axis,), classify=mode.split("-")[0])
                workers = 2 if mode.endswith("workers") else 1
                t0 = time.perf_counter()
                summary = run_sweep(scene, spec, os.path.join(tmp, f"{mode}-{r}.h5"),
                                    workers=workers, progress=False)
                times[mode].append(time.perf_counter() - t0)
                labels[mode] = summary.regimes
                print(f"round {r}: {mode}: {points / times[mode][-1]:.2f} points/s "
                      f"{summary.regimes}", flush=True)
    rate = {m: [points / t for t in ts] for m, ts in times.items()}
    ratio_full = [c / f for c, f in zip(rate["converged"], rate["full"], strict=True)]
    ratio_paper = [c / p for c, p in zip(rate["converged"], rate["paper"], strict=True)]
    out = {
        "command": " ".join(["python benchmarks/bench_classify.py"] + sys.argv[1:]),
        "slice": f"fig4 period_ratio={interval}#{points}",
        "rounds": rounds,
        "points_per_s": rate,
        "median_points_per_s": {m: float(np.median(v)) for m, v in rate.items()},
        "converged_over_full": ratio_full,
        "converged_over_paper": ratio_paper,
        "median_converged_over_full": float(np.median(ratio_full)),
        "regimes_last_round": labels,
    }
    if workers2:
        r2 = [a / b for a, b in zip(rate["converged-2-workers"], rate["converged"],
                                    strict=True)]
        out["two_workers_over_one"] = r2
        out["median_two_workers_over_one"] = float(np.median(r2))
    return out


def _sweep_process(tree: Path, spec: list[str], output: str) -> tuple[float, str]:
    """Run ``chaospound sweep`` of ``tree`` (one worker) in a process: (wall s, its summary)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    command = [sys.executable, "-m", "chaospound", "sweep", "--preset", "fig4", *spec,
               "-o", output, "--workers", "1", "--quiet"]
    t0 = time.perf_counter()
    done = subprocess.run(command, cwd=tree, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} (in {tree}) failed:\n{done.stderr[-2000:]}")
    summary = [line for line in done.stdout.splitlines() if line.startswith("regimes")]
    return wall, summary[-1] if summary else done.stdout.strip()[-300:]


def baseline(old: Path, points: int, rounds: int, interval: str) -> dict:
    from bench_compile import commit

    new = Path(__file__).resolve().parent.parent
    grid = ["--param", f"period_ratio={interval}#{points}"]
    runs = {"new converged": (new, []), "old full": (old, ["--classify", "full"])}
    walls: dict[str, list[float]] = {name: [] for name in runs}
    summaries: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (tree, mode) in runs.items():  # fill the kernel caches, untimed
            _sweep_process(tree, ["--param", "period_ratio=0.7:0.9#2", *mode],
                           os.path.join(tmp, f"warm-{name.split()[0]}.h5"))
        for r in range(rounds):
            order = list(runs) if r % 2 == 0 else list(runs)[::-1]
            for name in order:
                tree, mode = runs[name]
                wall, summaries[name] = _sweep_process(
                    tree, [*grid, *mode], os.path.join(tmp, f"{name.split()[0]}-{r}.h5"))
                walls[name].append(wall)
                print(f"round {r}: {name}: {wall:.1f} s, {points / wall:.2f} points/s; "
                      f"{summaries[name]}", flush=True)
    ratios = [o / n for o, n in zip(walls["old full"], walls["new converged"], strict=True)]
    return {
        "command": " ".join(["python benchmarks/bench_classify.py"] + sys.argv[1:]),
        "old": commit(old), "new": commit(new),
        "slice": f"fig4 period_ratio={interval}#{points}", "rounds": rounds,
        "wall_s": walls,
        "points_per_s": {k: [points / w for w in v] for k, v in walls.items()},
        "new_converged_over_old_full": ratios,
        "median_new_converged_over_old_full": float(np.median(ratios)),
        "regimes_last_round": summaries,
    }


def _old_full_wall_s() -> float:
    """The old tree's ``--classify full`` wall time of the whole scan (the median of
    results/bench_classify_baseline.json): what issue 17's 15x is read against."""
    baseline = json.loads((RESULTS / "bench_classify_baseline.json").read_text())
    return float(np.median(baseline["wall_s"]["old full"]))


def _scan_header(points: int, old_full: float) -> dict:
    """The first entries of ``budget``'s and ``bound``'s results."""
    return {"command": " ".join(["python benchmarks/bench_classify.py"] + sys.argv[1:]),
            "slice": f"fig4 period_ratio=0.3:2.0#{points}", "old_full_wall_s": old_full}


def budget(points: int, floor_rtol: float) -> dict:
    """Where the default scan's time goes, and the floor of its chaos watch.

    Runs the default sweep of the fig4 scan (``points`` points over T/T_Ax 0.3-2.0,
    one worker, warm kernels) and sums each point's own wall time (the store's
    ``wall_s``) by regime. Then, from each chaotic point's stored final section, it
    times ``CHAOS_WATCH`` cycles of sections at ``floor_rtol`` (default 1e-4, ten times
    looser than the watch's own ``WATCH_RTOL``): a lower bound of what any watch that
    long costs those points. Issue 17's 15x is read against the old tree's
    ``--classify full`` wall time of results/bench_classify_baseline.json.
    """
    from chaospound.dynamics.classify import ATOL_PER_RTOL, _with_solver
    from chaospound.dynamics.converged import CHAOS_WATCH
    from chaospound.dynamics.system import as_system, evolve
    from chaospound.store import open_sweep

    scene = load_preset("fig4")
    spec = SweepSpec(axes=(parse_axis(f"period_ratio=0.3:2.0#{points}"),))
    with tempfile.TemporaryDirectory() as tmp:
        run_sweep(scene, SweepSpec(axes=(parse_axis("period_ratio=0.7:0.8#2"),)),
                  os.path.join(tmp, "warm.h5"), progress=False)
        t0 = time.perf_counter()
        run_sweep(scene, spec, os.path.join(tmp, "scan.h5"), workers=1, progress=False)
        scan_wall = time.perf_counter() - t0
        with open_sweep(os.path.join(tmp, "scan.h5")) as store:
            regimes = np.array(store.regimes())
            wall = store.array("wall_s")
            final = store.array("final_state")
            ratios = store.points()[:, 0]
    by_regime = {str(r): {"points": int((regimes == r).sum()),
                          "wall_s": float(wall[regimes == r].sum()),
                          "mean_ms": 1e3 * float(wall[regimes == r].mean())}
                 for r in np.unique(regimes)}
    chaotic = np.flatnonzero(regimes == "chaotic")
    floor = 0.0
    for i in chaotic:
        target = as_system(scene.with_params(period_ratio=float(ratios[i])))
        flow = _with_solver(target, {"rtol": floor_rtol, "atol": ATOL_PER_RTOL * floor_rtol})
        t0 = time.perf_counter()
        evolve(flow, final[i], cycles=CHAOS_WATCH, start_at_section=True)
        floor += time.perf_counter() - t0
    old_full = _old_full_wall_s()
    allowed = old_full / 15.0
    others = sum(v["wall_s"] for r, v in by_regime.items() if r != "chaotic")
    return {
        **_scan_header(points, old_full),
        "scan_wall_s": scan_wall,
        "by_regime": by_regime,
        "budget_15x_s": allowed,
        "watch_floor": {"rtol": floor_rtol, "cycles": CHAOS_WATCH,
                        "chaotic_points": int(len(chaotic)), "seconds": floor},
        "others_plus_watch_floor_s": others + floor,
    }


def _scan_seconds(scene, spec, tmp: str, name: str) -> tuple[float, str]:
    """Wall time of the default sweep of ``spec`` (one worker) and its store's path."""
    path = os.path.join(tmp, name)
    t0 = time.perf_counter()
    run_sweep(scene, spec, path, workers=1, progress=False)
    return time.perf_counter() - t0, path


def bound(points: int, rounds: int, samples: list[Path], cycles: int) -> dict:
    """How far issue 17's 15x is from reach: with the chaos watch, without it, and with
    an engine that wastes no right-hand side evaluation.

    1. The default sweep of the fig4 scan (``points`` points, one worker) timed with
       the chaos watch (``CHAOS_WATCH``) and with it off (0), interleaved in
       ``rounds`` rounds.
    2. The agreement of both with the careful labels stored in ``samples`` (the
       agreement files; the careful classifier does not depend on the watch, so it is
       not run again): every row's point is classified again as the default sweep
       does, with the watch and without it.
    3. The engine's waste on the scan's impacting points: from each one's stored final
       section, ``cycles`` cycles at ``WATCH_RTOL`` and at ``EXPONENT_RTOL``; the
       right-hand side evaluations made over the method's evaluations per step (dopri5:
       6) times the accepted steps is
       what a step-size controller that never rejected a step, and an event location
       that cost nothing, could save at the same accepted steps (an upper bound: the
       accepted steps themselves are the tolerance's).
    """
    from chaospound.dynamics import converged
    from chaospound.dynamics.classify import ATOL_PER_RTOL, _with_solver
    from chaospound.dynamics.system import as_system, evolve
    from chaospound.engine import tables as kin
    from chaospound.solvers.tableaux import METHODS
    from chaospound.store import open_sweep

    watch = converged.CHAOS_WATCH
    scene = load_preset("fig4")
    spec = SweepSpec(axes=(parse_axis(f"period_ratio=0.3:2.0#{points}"),))
    timings = {"watch": [], "no watch": []}
    with tempfile.TemporaryDirectory() as tmp:
        run_sweep(scene, SweepSpec(axes=(parse_axis("period_ratio=0.7:0.8#2"),)),
                  os.path.join(tmp, "warm.h5"), progress=False)
        counts = {}
        for r in range(rounds):
            for mode in ("watch", "no watch"):
                converged.CHAOS_WATCH = watch if mode == "watch" else 0
                try:
                    seconds, path = _scan_seconds(scene, spec, tmp, f"{mode}{r}.h5")
                finally:
                    converged.CHAOS_WATCH = watch
                timings[mode].append(seconds)
                with open_sweep(path) as store:
                    regimes = np.array(store.regimes())
                    counts[mode] = {str(g): int((regimes == g).sum()) for g in np.unique(regimes)}
                    if mode == "watch":
                        final = store.array("final_state")
                        ratios = store.points()[:, 0]
                        impacting = np.flatnonzero(regimes != "none")
    waste = {}
    for name, rtol in (("watch", converged.WATCH_RTOL), ("exponent", converged.EXPONENT_RTOL)):
        rhs = accepted = rejected = events = 0
        for i in impacting:
            target = as_system(scene.with_params(period_ratio=float(ratios[i])))
            flow = _with_solver(target, {"rtol": rtol, "atol": ATOL_PER_RTOL * rtol})
            run = evolve(flow, final[i], cycles=cycles, start_at_section=True)
            new_evals = METHODS[flow.method].new_evals
            rhs += int(run.stats[kin.ST_RHS_EVALS])
            accepted += int(run.stats[kin.ST_ACCEPTED])
            rejected += int(run.stats[kin.ST_REJECTED])
            events += int(run.stats[kin.ST_EVENTS])
        n = len(impacting) * cycles
        waste[name] = {"rtol": rtol, "accepted_per_cycle": accepted / n,
                       "rejected_per_cycle": rejected / n, "event_steps_per_cycle": events / n,
                       "rhs_per_cycle": rhs / n,
                       "rhs_over_minimum": rhs / (new_evals * accepted)}
    ideal = max(w["rhs_over_minimum"] for w in waste.values())
    agreement_rows = {"watch": [0, 0], "no watch": [0, 0]}
    per_file = {}
    for sample in samples:
        rows = json.loads(sample.read_text())["rows"]
        tally = {"watch": 0, "no watch": 0, "watch_reproduces_stored": 0}
        for row in rows:
            name = row["set"]
            scene_r = load_preset(name.split()[0])
            if name.endswith("map"):
                axes = (parse_axis("gap=0.5:2.0#200"), parse_axis("period_ratio=0.3:2.0#200"))
            else:
                axes = (parse_axis("period_ratio=0.3:2.0#1000"),)
            spec_r = SweepSpec(axes=axes)
            for mode in ("watch", "no watch"):
                converged.CHAOS_WATCH = watch if mode == "watch" else 0
                try:
                    result = run_task(scene_r, spec_r, [int(row["index"])], None, False)[-1]
                finally:
                    converged.CHAOS_WATCH = watch
                label = result.regime
                if label in ("periodic", "group-periodic"):
                    label = f"{label} {result.impacts_per_period}-{result.period_cycles}"
                agree = row["careful"] != "unresolved" and label == row["careful"]
                tally[mode] += agree
                if mode == "watch":
                    tally["watch_reproduces_stored"] += label == row["converged"]
                agreement_rows[mode][0] += agree
                agreement_rows[mode][1] += 1
        per_file[sample.name] = {"points": len(rows), **tally}
    old_full = _old_full_wall_s()
    seconds = {mode: float(np.median(t)) for mode, t in timings.items()}
    return {
        **_scan_header(points, old_full),
        "scan_wall_s": timings,
        "regimes": counts,
        "ratio": {mode: old_full / s for mode, s in seconds.items()},
        "engine_waste": waste,
        "ratio_with_ideal_engine": {mode: ideal * old_full / s for mode, s in seconds.items()},
        "agreement": {mode: {"agree": a, "points": n, "share": a / n}
                      for mode, (a, n) in agreement_rows.items()},
        "agreement_by_sample": per_file,
    }


def approach(points: int, cycles: int) -> dict:
    """Whether the trajectory that step 3 confirmed a stable orbit from goes to it.

    Step 3 of the converged classification reads a point from the stable orbit that
    Newton's method found near the last section; it does not run the trajectory on to
    see it arrive. Here every point of the fig4 scan (``points`` points, the default
    sweep) that step 3 named so is checked: from the section Newton started from, the
    trajectory runs ``cycles`` more cycles at rtol 1e-8, and its distance to the nearest
    of the orbit's P sections (max norm, relative to the orbit's largest component) is
    read at 0, 100, 500, 1000 and ``cycles`` cycles.
    """
    from chaospound.dynamics import converged
    from chaospound.dynamics.classify import _with_solver
    from chaospound.dynamics.system import as_system, evolve

    found = []
    newton = converged._Classifier._newton

    def recording(self, period):
        start, after = self._last().copy(), self.cycles
        result = newton(self, period)
        if result is not None and self.evidence.get("confirmed_by") == "newton":
            found.append((start, after, result, self.evidence["max_multiplier"]))
        return result

    scene = load_preset("fig4")
    spec = SweepSpec(axes=(parse_axis(f"period_ratio=0.3:2.0#{points}"),))
    checkpoints = sorted({0, 100, 500, 1000, cycles})
    rows = []
    converged._Classifier._newton = recording
    try:
        for index in range(points):
            found.clear()
            label = run_task(scene, spec, [index], None, False)[-1].regime
            if not found:
                continue
            start, after, result, mu = found[-1]
            flow = _with_solver(as_system(scene.with_params(**spec.point_values(index))),
                                {"rtol": 1e-8, "atol": 1e-10})
            period = result.regime.period_cycles or 1
            orbit = evolve(flow, result.record.strobe.state[0], cycles=period,
                           start_at_section=True).sections[:period]
            run = evolve(flow, start, cycles=cycles, start_at_section=True).sections
            size = float(np.max(np.abs(orbit)))
            distance = [float(np.min(np.max(np.abs(orbit - run[k]), axis=1)) / size)
                        for k in checkpoints]
            rows.append({"index": index, "values": spec.point_values(index), "label": label,
                         "period": period, "max_multiplier": mu, "newton_after": after,
                         "distance": distance})
    finally:
        converged._Classifier._newton = newton
    last = np.array([r["distance"][-1] for r in rows])
    first = np.array([r["distance"][0] for r in rows])
    return {
        "command": " ".join(["python benchmarks/bench_classify.py"] + sys.argv[1:]),
        "slice": f"fig4 period_ratio=0.3:2.0#{points}",
        "checkpoints": checkpoints,
        "points_confirmed_by_newton": len(rows),
        "closer_at_the_end": int(np.sum(last < first)),
        "within_1e-5_at_the_end": int(np.sum(last < 1e-5)),
        "largest_final_distance": float(last.max()) if rows else None,
        "slowest": sorted(rows, key=lambda r: -r["distance"][-1])[:8],
        "rows": rows,
    }


def _sample_sets(per_set: int, seed: int):
    """The sample: seeded, and without the first point of a row (the points once
    needed a grid predecessor to warm-start from; kept so that runs stay comparable)."""
    rng = np.random.default_rng(seed)
    one = parse_axis("period_ratio=0.3:2.0#1000")
    for preset in ("fig4", "fig4-translational"):
        picks = np.sort(rng.choice(np.arange(1, len(one)), size=per_set, replace=False))
        yield preset, (one,), picks
    gap = parse_axis("gap=0.5:2.0#200")
    pr = parse_axis("period_ratio=0.3:2.0#200")
    flat = rng.choice(np.arange(200 * 200), size=per_set, replace=False)
    flat = np.sort(flat[flat % 200 != 0])
    yield "fig4 (gap, T/T_Ax) map", (gap, pr), flat


def _careful(point, transient: int, exponent: int, escalate: int):
    """The careful classification of ``point`` and whether it needed ``escalate`` times
    the transient (a first run that left the point unresolved)."""
    careful = classify(point, max_transient=transient, lyapunov_cycles=exponent)
    if careful.regime != "unresolved" or escalate <= 1:
        return careful, False
    return classify(point, max_transient=escalate * transient,
                    lyapunov_cycles=exponent), True


def agreement(per_set: int, seed: int, careful_transient: int, careful_exponent: int,
              careful_escalate: int) -> dict:
    rows = []
    for name, axes, picks in _sample_sets(per_set, seed):
        scene = load_preset(name.split()[0])
        spec = SweepSpec(axes=axes)
        for index in picks:
            index = int(index)
            t0 = time.perf_counter()
            result = run_task(scene, spec, [index], None, False)[-1]
            t_conv = time.perf_counter() - t0
            point = scene.with_params(**spec.point_values(index))
            t0 = time.perf_counter()
            careful, escalated = _careful(point, careful_transient, careful_exponent,
                                          careful_escalate)
            t_care = time.perf_counter() - t0
            label = result.regime
            if label in ("periodic", "group-periodic"):
                label = f"{label} {result.impacts_per_period}-{result.period_cycles}"
            rows.append({"set": name, "index": index, "values": spec.point_values(index),
                         "converged": label, "careful": careful.label,
                         "careful_transient": careful.transient_used,
                         "careful_escalated": escalated,
                         "converged_s": t_conv, "careful_s": t_care,
                         "agree": careful.regime != "unresolved" and label == careful.label})
            print(f"{name} {spec.point_values(index)}: converged {label} | careful "
                  f"{careful.label} ({t_conv:.2f} s, {t_care:.2f} s)", flush=True)
    agree = sum(r["agree"] for r in rows)
    impacting = [r for r in rows if r["careful"] != "none"]
    summary = {
        "command": " ".join(["python benchmarks/bench_classify.py"] + sys.argv[1:]),
        "points": len(rows),
        "agree": agree,
        "agreement": agree / len(rows),
        "converged_unresolved": sum(r["converged"] == "unresolved" for r in rows),
        "careful_unresolved": sum(r["careful"] == "unresolved" for r in rows),
        "careful_max_transient": careful_transient,
        "careful_exponent_cycles": careful_exponent,
        "careful_escalate": careful_escalate,
        "careful_escalated": sum(r["careful_escalated"] for r in rows),
        "agreement_where_careful_names": (
            sum(r["agree"] for r in rows if r["careful"] != "unresolved")
            / max(1, sum(r["careful"] != "unresolved" for r in rows))),
        "impacting_points": len(impacting),
        "by_set": {},
        "rows": rows,
    }
    for name in dict.fromkeys(r["set"] for r in rows):
        sub = [r for r in rows if r["set"] == name]
        summary["by_set"][name] = {"points": len(sub), "agree": sum(r["agree"] for r in sub)}
    return summary


def _markdown(s: dict) -> str:
    lines = [
        "# Converged (sweep default) against the careful classifier",
        "",
        f"Command: `PYTHONPATH=. {s['command']}`",
        "",
        f"{s['agree']} of {s['points']} points agree ({100 * s['agreement']:.2f} %); "
        f"unresolved: converged {s['converged_unresolved']}, careful "
        f"{s['careful_unresolved']}. Where the careful classifier names the point: "
        f"{100 * s['agreement_where_careful_names']:.2f} %. The careful classifier ran "
        f"up to {s['careful_max_transient']} transient cycles and "
        f"{s['careful_exponent_cycles']} exponent cycles"
        + (f", and {s['careful_escalate']} times the transient at the "
           f"{s['careful_escalated']} point{'' if s['careful_escalated'] == 1 else 's'} it "
           "first left unresolved."
           if s.get("careful_escalate", 1) > 1 else "."),
        "",
        "| set | points | agree |",
        "|---|---|---|",
    ]
    lines += [f"| {k} | {v['points']} | {v['agree']} |" for k, v in s["by_set"].items()]
    lines += ["", "Disagreements:", "", "| set | values | converged | careful |",
              "|---|---|---|---|"]
    lines += [f"| {r['set']} | {r['values']} | {r['converged']} | {r['careful']} "
              f"(transient {r['careful_transient']}) |" for r in s["rows"] if not r["agree"]]
    return "\n".join(lines) + "\n"


def birkhoff() -> dict:
    from chaospound import open_sweep
    from chaospound.dynamics.classify import (
        _classification_system,
        _principal_component,
        birkhoff_digits,
        length_weights,
    )
    from chaospound.dynamics.system import System
    from chaospound.simulate import simulate

    scene = load_preset("fig4")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fig4.h5"
        run_sweep(scene, SweepSpec(axes=(parse_axis("period_ratio=0.3:2.0#1000"),)), path,
                  progress=False)
        with open_sweep(path) as store:
            data = store.to_xarray()
            regimes, ratios = data.regime.values, data.period_ratio.values
            finals = data.final_state.values
    out: dict = {"command": "python benchmarks/bench_classify.py birkhoff", "sections": 1000,
                 "digits": {}, "summary": {}}
    for label in ("chaotic", "quasi-periodic", "unresolved"):
        digits = []
        for i in np.flatnonzero(regimes == label):
            point = scene.with_params(period_ratio=float(ratios[i]))
            system = System.from_scene(point)
            target, _, _ = _classification_system(system)
            record = simulate(target, transient=0, record=1000, initial_state=finals[i],
                              start_at_section=True)
            states = record.strobe.state * length_weights(point, system.state_names)
            digits.append(birkhoff_digits(_principal_component(states)))
        d = np.array(digits)
        out["digits"][label] = d.tolist()
        out["summary"][label] = {} if d.size == 0 else {
            "points": int(d.size), "min": float(d.min()), "median": float(np.median(d)),
            "q95": float(np.quantile(d, 0.95)), "max": float(d.max()),
            "at_least_5": int(np.sum(d >= 5.0))}
        print(label, out["summary"][label], flush=True)
    return out


def changes(preset: str, old: Path, new: Path, per_change: int, seed: int,
            careful_transient: int, careful_exponent: int, careful_escalate: int) -> dict:
    from collections import Counter

    from chaospound import open_sweep

    with open_sweep(old) as store:
        before = store.to_xarray()
    with open_sweep(new) as store:
        after = store.to_xarray()
    dims = [d for d in after.regime.dims if d != "branch"]
    was, now = before.regime.values, after.regime.values
    if was.shape != now.shape:
        raise SystemExit(f"{old} and {new} are not the same grid: {was.shape}, {now.shape}")
    coords = [after[d].values for d in dims]
    changed = Counter(zip(was[was != now].tolist(), now[was != now].tolist(), strict=True))
    rng = np.random.default_rng(seed)
    scene = load_preset(preset)
    rows = []
    for a, b in sorted(changed, key=lambda change: -changed[change]):
        where = np.argwhere((was == a) & (now == b))
        for p in rng.choice(len(where), size=min(per_change, len(where)), replace=False):
            index = where[p][-len(dims):]
            values = {d: float(c[i]) for d, c, i in zip(dims, coords, index, strict=True)}
            careful, _ = _careful(scene.with_params(**values), careful_transient,
                                  careful_exponent, careful_escalate)
            rows.append({"old": a, "new": b, "values": values, "careful": careful.regime,
                         "careful_label": careful.label})
            print(f"{values}: {a} -> {b}; careful {careful.label}", flush=True)
    summary: dict = {
        "command": " ".join(["python benchmarks/bench_classify.py"] + sys.argv[1:]),
        "points": int(was.size), "changed": {f"{a} -> {b}": n for (a, b), n in changed.items()},
        "careful_max_transient": careful_transient,
        "careful_exponent_cycles": careful_exponent, "careful_escalate": careful_escalate,
        "by_change": {}, "rows": rows}
    for a, b in changed:
        sub = [r for r in rows if (r["old"], r["new"]) == (a, b)]
        summary["by_change"][f"{a} -> {b}"] = {
            "sampled": len(sub), "careful_says_new": sum(r["careful"] == b for r in sub),
            "careful_says_old": sum(r["careful"] == a for r in sub)}
    return summary


def _changes_markdown(s: dict) -> str:
    lines = ["# Changed labels of a scan, against the careful classifier", "",
             f"Command: `PYTHONPATH=. {s['command']}`", "",
             f"{sum(s['changed'].values())} of {s['points']} points changed regime. For each "
             "change, a random sample classified by the careful classifier (up to "
             f"{s['careful_max_transient']} transient cycles, {s['careful_exponent_cycles']} "
             "exponent cycles):", "",
             "| change | points | sampled | careful says new | careful says old |",
             "|---|---|---|---|---|"]
    lines += [f"| {k} | {s['changed'][k]} | {v['sampled']} | {v['careful_says_new']} | "
              f"{v['careful_says_old']} |" for k, v in s["by_change"].items()]
    return "\n".join(lines) + "\n"


TABLE_RATIOS = (0.30, 0.45, 0.50, 0.60, 0.65, 0.70, 0.75, 0.80, 0.85, 0.90, 0.95, 1.00, 1.05,
                1.10, 1.20, 1.25, 1.30, 1.40, 1.60, 1.80, 2.00)


def _cell(regime) -> tuple[str, str]:
    """(label, evidence) cells of one classification."""
    label = regime.label
    if regime.corner_sequence and regime.regime != "none":
        label += " (" + " ".join(regime.corner_sequence) + ")"
    if regime.max_exponent is not None and regime.period_cycles is None:
        k = "-" if regime.zero_one is None else f"{regime.zero_one:.2f}"
        evidence = f"{regime.max_exponent:.3f} +- {regime.max_exponent_error:.3f}, K {k}"
        banded = regime.evidence.get("zero_one_banded")
        if banded is not None:
            evidence += f" ({banded:.2f} in {regime.evidence['zero_one_bands']} bands)"
    else:
        evidence = f"{regime.strobe_mismatch:.1e}"
    return label, evidence


def table() -> dict:
    rows = {}
    for ratio in TABLE_RATIOS:
        torsional = classify(load_preset("fig4").with_params(period_ratio=ratio))
        translational = classify(load_preset("fig4-translational").with_params(
            period_ratio=ratio))
        label, evidence = _cell(torsional)
        other, other_evidence = _cell(translational)
        if translational.regime not in ("none", "periodic", "group-periodic"):
            other += f" ({other_evidence})"
        row = f"| {ratio:.2f} | {label} | {evidence} | {torsional.transient_used} | {other} |"
        rows[f"{ratio:.2f}"] = row
        print(row, flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="part", required=True)
    sp = sub.add_parser("speed")
    sp.add_argument("--points", type=int, default=50)
    sp.add_argument("--rounds", type=int, default=3)
    sp.add_argument("--workers2", action="store_true")
    sp.add_argument("--slice", default="0.6:1.3", help="T/T_Ax interval LO:HI")
    sp.add_argument("--output", type=Path, default=RESULTS / "bench_classify.json")
    bl = sub.add_parser("baseline")
    bl.add_argument("--old", type=Path, required=True, help="the older tree (a worktree)")
    bl.add_argument("--points", type=int, default=50)
    bl.add_argument("--rounds", type=int, default=2)
    bl.add_argument("--slice", default="0.6:1.3", help="T/T_Ax interval LO:HI")
    bl.add_argument("--output", type=Path, default=RESULTS / "bench_classify_baseline.json")
    ag = sub.add_parser("agreement")
    ag.add_argument("--per-set", type=int, default=67)
    ag.add_argument("--seed", type=int, default=17)
    ag.add_argument("--careful-transient", type=int, default=6000)
    ag.add_argument("--careful-exponent", type=int, default=400)
    ag.add_argument("--careful-escalate", type=int, default=4)
    ag.add_argument("--output", type=Path, default=RESULTS / "classify_agreement.json")
    sub.add_parser("birkhoff")
    sub.add_parser("table")
    bu = sub.add_parser("budget")
    bu.add_argument("--points", type=int, default=1000)
    bu.add_argument("--floor-rtol", type=float, default=1e-4)
    bu.add_argument("--output", type=Path, default=RESULTS / "classify_budget.json")
    ap = sub.add_parser("approach")
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--cycles", type=int, default=2000)
    ap.add_argument("--output", type=Path, default=RESULTS / "classify_approach.json")
    bo = sub.add_parser("bound")
    bo.add_argument("--points", type=int, default=1000)
    bo.add_argument("--rounds", type=int, default=2)
    bo.add_argument("--cycles", type=int, default=50)
    bo.add_argument("--samples", type=Path, nargs="+", default=[
        RESULTS / "classify_agreement.json", *(RESULTS / f"classify_agreement_seed{k}.json"
                                              for k in (18, 19, 20))])
    bo.add_argument("--output", type=Path, default=RESULTS / "classify_bound.json")
    ch = sub.add_parser("changes")
    ch.add_argument("--preset", required=True)
    ch.add_argument("--old", type=Path, required=True, help="the store before")
    ch.add_argument("--new", type=Path, required=True, help="the store after")
    ch.add_argument("--per-change", type=int, default=16)
    ch.add_argument("--seed", type=int, default=1)
    ch.add_argument("--careful-transient", type=int, default=6000)
    ch.add_argument("--careful-exponent", type=int, default=400)
    ch.add_argument("--careful-escalate", type=int, default=4)
    ch.add_argument("--output", type=Path, default=RESULTS / "classify_changes.json")
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    if args.part == "speed":
        out = speed(args.points, args.rounds, args.workers2, args.slice)
        args.output.write_text(json.dumps(out, indent=1) + "\n")
    elif args.part == "baseline":
        out = baseline(args.old.resolve(), args.points, args.rounds, args.slice)
        args.output.write_text(json.dumps(out, indent=1) + "\n")
    elif args.part == "table":
        out = table()
    elif args.part == "budget":
        out = budget(args.points, args.floor_rtol)
        args.output.write_text(json.dumps(out, indent=1) + "\n")
    elif args.part == "approach":
        out = approach(args.points, args.cycles)
        args.output.write_text(json.dumps(out, indent=1) + "\n")
    elif args.part == "bound":
        out = bound(args.points, args.rounds, args.samples, args.cycles)
        args.output.write_text(json.dumps(out, indent=1) + "\n")
    elif args.part == "changes":
        from chaospound.sweep import single_thread_blas

        single_thread_blas()
        out = changes(args.preset, args.old, args.new, args.per_change, args.seed,
                      args.careful_transient, args.careful_exponent, args.careful_escalate)
        args.output.write_text(json.dumps(out, indent=1) + "\n")
        args.output.with_suffix(".md").write_text(_changes_markdown(out))
    elif args.part == "birkhoff":
        out = birkhoff()
        (RESULTS / "classify_birkhoff.json").write_text(json.dumps(out, indent=1) + "\n")
        out = out["summary"]
    else:
        out = agreement(args.per_set, args.seed, args.careful_transient, args.careful_exponent,
                        args.careful_escalate)
        args.output.write_text(json.dumps(out, indent=1) + "\n")
        args.output.with_suffix(".md").write_text(_markdown(out))
    print(json.dumps({k: v for k, v in out.items() if k != "rows"}, indent=1))


if __name__ == "__main__":
    main()
