"""Speed of a steady run against scipy's ``solve_ivp`` on the same equations.

:func:`run_benchmark` times, on one scene and in one process:

* ``chaospound``: :func:`chaospound.simulate.simulate` (jitted Dormand-Prince
  with located contact events), best of ``repeats`` after a warm-up call;
* ``scipy-python``: ``scipy.integrate.solve_ivp(method="RK45")`` with a
  pure-Python transcription of the same equations (docs/model.md sections
  5-6). That second copy of the physics is a benchmark baseline, not part of
  the library: it lives in the source tree, ``benchmarks/python_twin.py``
  (:func:`load_python_twin`); without it (an installed package) this run is
  left out and reported missing;
* ``scipy-numba``: ``solve_ivp(method="RK45")`` with the jitted kernel
  :func:`rhs` of the composed engine wrapped in a Python function;
* ``cli``: ``chaospound simulate`` end to end in a subprocess (warm numba
  cache), best of ``cli_repeats``.

The integrations are timed in interleaved rounds (each round: a few
chaospound runs, one run of each ``solve_ivp`` variant, a few more chaospound
runs), and each keeps its best time, so that every variant meets the same
periods of load on a shared machine.

All runs cover the same time span (the scene's transient + record cycles, from
forcing time 0) with the scene's rtol and atol, from the same initial state.
``solve_ivp`` has no contact-event landing: it integrates the plain ODE, so
its step count differs from chaospound's. Two speed-ups are reported:

* ``wall``: ratio of total wall times for the same run (the user's view);
* ``per_step``: ratio of times per accepted step (cost of one step, whatever
  the step counts).

Speed is measured here, never asserted in tests; the measured numbers are in
results/bench_simulate.json. The only file this module writes is a temporary
scene TOML for timing the CLI on a modified scene.
"""

from __future__ import annotations

import functools
import importlib.util
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType

import numpy as np

from .kernels.params import MODEL_DIMS, MODEL_NAMES
from .scene import Scene
from .simulate import SimulationError, simulate

__all__ = ["PYTHON_TWIN", "TARGETS", "format_benchmark", "load_python_twin", "run_benchmark"]

#: the pure-Python equations of the "scipy-python" run, in a source checkout
PYTHON_TWIN = Path(__file__).resolve().parents[1] / "benchmarks" / "python_twin.py"

#: the project's speed goals, set for fig3a (40 + 8 cycles, rtol 1e-6; met at the
#: preset's 1e-5 as well)
TARGETS = {
    "us_per_step": 0.5,  #: chaospound, microseconds per accepted step, at most
    "speedup_python": 100.0,  #: wall-time speed-up over solve_ivp + Python rhs, at least
    "speedup_numba": 75.0,  #: wall-time speed-up over solve_ivp + numba rhs, at least
    "cli_s": 2.0,  #: ``chaospound simulate`` end to end, warm cache, seconds, at most
}
#: stop the timing rounds once the solve_ivp runs have taken this long (s)
SCIPY_BUDGET_S = 20.0
#: chaospound runs timed before and after the solve_ivp runs of each round
CHAOSPOUND_RUNS_PER_ROUND = 3
RUNS = ("chaospound", "scipy-python", "scipy-numba")
RUN_LABELS = {
    "chaospound": "chaospound simulate",
    "scipy-python": "solve_ivp RK45, Python rhs",
    "scipy-numba": "solve_ivp RK45, numba rhs",
}


# ================================================================ public
def run_benchmark(
    scene: Scene,
    *,
    repeats: int = 5,
    cli: bool = True,
    cli_repeats: int = 3,
    scipy_budget_s: float = SCIPY_BUDGET_S,
) -> dict:
    """Time chaospound against ``solve_ivp(RK45)`` on one scene.

    Parameters
    ----------
    scene : Scene
        The scene; its run settings (transient + record cycles, phase) fix the
        time span, its solver settings rtol and atol.
    repeats : int
        Rounds of timed runs (>= 1): each round times chaospound
        ``2 * CHAOSPOUND_RUNS_PER_ROUND`` times around one run of each
        ``solve_ivp`` variant; the best (minimum) of each counts. Rounds stop
        early once the ``solve_ivp`` runs have taken ``scipy_budget_s``.
    cli : bool
        Also time ``chaospound simulate`` end to end in a subprocess.
    cli_repeats : int
        Timed subprocess runs (after one that warms the numba cache).
    scipy_budget_s : float
        Time budget of the timed ``solve_ivp`` runs, both variants together (s).

    Returns
    -------
    dict
        JSON-ready: ``scene``, ``model``, ``n_states``, ``span``, ``rtol``,
        ``atol``, ``method``, ``machine``, one entry per run in :data:`RUNS`
        (``wall_s``, ``steps``, ``rhs_evals``, ``us_per_step``,
        ``ns_per_rhs_eval``, ``repeats``, ...), ``speedup`` (``wall`` and
        ``per_step`` ratios of each scipy run to chaospound), ``cli``
        (``None`` when not timed) and ``targets``.
    """
    if repeats < 1 or cli_repeats < 1:
        raise ValueError(f"repeats = {repeats}, cli_repeats = {cli_repeats}: need >= 1")
    model = scene.model_id()
    p = scene.pack(model)
    y0 = scene.initial_vector(model)
    period = scene.period
    cycles = scene.run.transient + scene.run.record
    t_end = scene.run.phase * period + cycles * period
    rtol, atol = scene.solver.rtol, scene.solver.atol

    twin = load_python_twin()
    funs = {} if twin is None else {"scipy-python": twin.python_fun(model, p)}
    funs["scipy-numba"] = numba_fun(model, p)
    simulate(scene)  # warm-up: loads or compiles the kernels
    for fun in funs.values():
        _solve_ivp(fun, y0, period, rtol, atol)  # warm-up
    sims: list[tuple[float, object]] = []
    scipy_runs: dict[str, list[tuple[float, object]]] = {name: [] for name in funs}
    spent = 0.0
    for _ in range(repeats):
        sims.extend(_time_simulate(scene, CHAOSPOUND_RUNS_PER_ROUND))
        for name, fun in funs.items():
            wall, sol = _time_call(lambda fun=fun: _solve_ivp(fun, y0, t_end, rtol, atol))
            spent += wall
            scipy_runs[name].append((wall, sol))
        sims.extend(_time_simulate(scene, CHAOSPOUND_RUNS_PER_ROUND))
        if spent >= scipy_budget_s:
            break
    wall, sim = min(sims, key=lambda pair: pair[0])
    y_end = sim.strobe.state[-1]
    ours = _entry(wall, sim.stats.steps, sim.stats.rhs_evals, len(sims))
    ours.update(
        kernel_s=min(s.stats.wall_s for _, s in sims),
        rejected=sim.stats.rejected,
        events=sim.stats.events,
        impacts=len(sim.impacts),
    )

    result = {
        "scene": scene.name,
        "model": MODEL_NAMES[model],
        "n_states": MODEL_DIMS[model],
        "span": {
            "t_start": 0.0,
            "t_end": t_end,
            "transient": scene.run.transient,
            "record": scene.run.record,
            "phase": scene.run.phase,
        },
        "method": scene.solver.method,
        "rtol": rtol,
        "atol": atol,
        "machine": machine_info(),
        "chaospound": ours,
        "missing": {} if twin is not None else {
            "scipy-python": f"{PYTHON_TWIN} not found (a source checkout has it)"},
    }
    for name, runs in scipy_runs.items():
        wall, sol = min(runs, key=lambda pair: pair[0])
        entry = _entry(wall, sol.t.size - 1, sol.nfev, len(runs))
        entry["final_state_diff"] = float(np.max(np.abs(sol.y[:, -1] - y_end)))
        result[name] = entry
    result["speedup"] = {
        name: {
            "wall": result[name]["wall_s"] / ours["wall_s"],
            "per_step": result[name]["us_per_step"] / ours["us_per_step"],
        }
        for name in funs
    }
    result["cli"] = time_cli(scene, repeats=cli_repeats) if cli else None
    result["targets"] = _targets(result)
    return result


def format_benchmark(result: dict) -> str:
    """The benchmark as a readable text table (from :func:`run_benchmark`'s dict)."""
    span = result["span"]
    machine = result["machine"]
    head = (
        f"scene {result['scene']} ({result['model']}, {result['n_states']} states): "
        f"{span['transient']} + {span['record']} cycles, t = 0 .. {span['t_end']:.6g}; "
        f"{result['method']} vs RK45, rtol {result['rtol']:g}, atol {result['atol']:g}\n"
        f"machine: {machine['cpu']}, {machine['cpu_count']} CPUs; Python {machine['python']}, "
        f"numpy {machine['numpy']}, scipy {machine['scipy']}, numba {machine['numba']}"
    )
    columns = ("run", "wall ms", "steps", "rhs evals", "us/step", "ns/rhs",
               "x wall", "x per step", "runs", "|dy| end")  # fmt: skip
    rows = []
    for name in (name for name in RUNS if name in result):
        entry = result[name]
        speed = result["speedup"].get(name, {"wall": 1.0, "per_step": 1.0})
        diff = entry.get("final_state_diff")
        rows.append((
            RUN_LABELS[name],
            f"{1e3 * entry['wall_s']:.4g}",
            str(entry["steps"]),
            str(entry["rhs_evals"]),
            f"{entry['us_per_step']:.3g}",
            f"{entry['ns_per_rhs_eval']:.0f}",
            f"{speed['wall']:.1f}",
            f"{speed['per_step']:.1f}",
            str(entry["repeats"]),
            "-" if diff is None else f"{diff:.2g}",
        ))  # fmt: skip
    ours = result["chaospound"]
    notes = [
        f"chaospound: {ours['rejected']} rejected steps, {ours['events']} located contact "
        f"events, {ours['impacts']} impacts recorded; kernel time {1e3 * ours['kernel_s']:.4g} ms",
        "x wall = scipy wall time / chaospound wall time for the same run; "
        "x per step = the same for time per accepted step",
        "|dy| end = max |y_scipy - y_chaospound| at the end of the span "
        "(solve_ivp does not land on contact kinks)",
    ]
    notes += [f"{RUN_LABELS[name]}: not run, {why}"
              for name, why in result.get("missing", {}).items()]
    cli = result["cli"]
    if cli is not None:
        notes.append(
            f"CLI end to end: {cli['wall_s']:.3g} s, best of {cli['repeats']} "
            f"(warm cache): {' '.join(cli['argv'])}"
        )
    lines = [
        f"  {label}: {goal['value']:.4g} (goal {goal['comparison']} {goal['target']:g}): "
        f"{'met' if goal['met'] else 'NOT met'}"
        for label, goal in result["targets"].items()
    ]
    return "\n\n".join([
        head,
        _table(columns, rows, "lrrrrrrrrr"),
        "\n".join(notes),
        "speed goals of chaospound (set for preset fig3a, 40 + 8 cycles, rtol 1e-6 or the "
        f"preset's 1e-5; this run: rtol {result['rtol']:g}; on an idle machine, other scenes "
        "and busy machines may miss them):\n" + "\n".join(lines),
    ]) + "\n"  # fmt: skip


@functools.cache
def load_python_twin() -> ModuleType | None:
    """``benchmarks/python_twin.py`` (``python_rhs``, ``python_fun``), or None if absent.

    The pure-Python equations are a baseline to measure against, kept out of
    the package; a source checkout (the editable install the benchmarks are
    run from) has them next to the package, an installed wheel does not.
    """
    if not PYTHON_TWIN.is_file():
        return None
    spec = importlib.util.spec_from_file_location("chaospound_python_twin", PYTHON_TWIN)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def numba_fun(model: int, p: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
    """``fun(t, y)`` for ``solve_ivp`` calling the composed engine's jitted ``rhs``.

    The ground motion is the packed vector's (``P_GROUND``: 1 sine, 0 none).
    """
    from .engine.compose import Composition, engine_for
    from .kernels.params import P_GROUND

    ground = "sine" if p[P_GROUND] == 1.0 else "none"
    rhs = engine_for(Composition(MODEL_NAMES[model], ground=ground)).module.rhs
    out = np.empty(MODEL_DIMS[model])

    def fun(t, y):
        rhs(t, y, p, out)
        return out.copy()

    return fun


def time_cli(scene: Scene, *, repeats: int = 3) -> dict:
    """Best wall time of ``chaospound simulate`` on the scene, in a subprocess.

    An unmodified preset runs as ``chaospound simulate --preset NAME``; any
    other scene is written to a temporary TOML file first. One untimed run
    warms the numba cache.

    Returns
    -------
    dict
        ``argv`` (as shown), ``wall_s`` (best), ``all_s``, ``repeats``.
    """
    from .scene import list_presets, load_preset

    command = _cli_command()
    with tempfile.TemporaryDirectory(prefix="chaospound-bench-") as folder:
        if scene.name in list_presets() and load_preset(scene.name) == scene:
            args = ["--preset", scene.name]
            shown = args
        else:
            path = os.path.join(folder, "scene.toml")
            with open(path, "w", encoding="utf-8") as handle:
                handle.write(scene.to_toml())
            args = [path]
            shown = [f"{scene.name}.toml"]
        argv = command + ["simulate"] + args
        times = [_run_once(argv) for _ in range(repeats + 1)][1:]
    return {
        "argv": [os.path.basename(command[0])] + command[1:] + ["simulate"] + shown,
        "wall_s": min(times),
        "all_s": times,
        "repeats": repeats,
    }


def machine_info() -> dict:
    """Processor, CPU count and library versions (for the report)."""
    import numba
    import scipy

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            for line in handle:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
    }


# ============================================================== timing helpers
def _entry(wall: float, steps: int, rhs_evals: int, repeats: int) -> dict:
    return {
        "wall_s": wall,
        "steps": int(steps),
        "rhs_evals": int(rhs_evals),
        "us_per_step": 1e6 * wall / max(steps, 1),
        "ns_per_rhs_eval": 1e9 * wall / max(rhs_evals, 1),
        "repeats": repeats,
    }


def _time_call(call: Callable[[], object]) -> tuple[float, object]:
    start = time.perf_counter()
    out = call()
    return time.perf_counter() - start, out


def _time_simulate(scene: Scene, runs: int) -> list[tuple[float, object]]:
    """``runs`` timed :func:`simulate` calls on the scene: (wall time, result) each."""
    return [_time_call(lambda: simulate(scene)) for _ in range(runs)]


def _solve_ivp(fun, y0, t_end, rtol, atol):
    """``solve_ivp(RK45)`` over [0, t_end]; a failed run is an error, not a time."""
    from scipy.integrate import solve_ivp

    sol = solve_ivp(fun, (0.0, t_end), y0, method="RK45", rtol=rtol, atol=atol)
    if not sol.success:
        raise SimulationError(f"solve_ivp (RK45) failed: {sol.message}")
    return sol


def _cli_command() -> list[str]:
    """The ``chaospound`` console script next to this Python, else ``python -m chaospound``."""
    script = os.path.join(os.path.dirname(sys.executable), "chaospound")
    if os.path.isfile(script) and os.access(script, os.X_OK):
        return [script]
    found = shutil.which("chaospound")
    return [found] if found else [sys.executable, "-m", "chaospound"]


def _run_once(argv: list[str]) -> float:
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        message = done.stderr.strip().splitlines()[-1:] or ["no message"]
        raise SimulationError(f"{' '.join(argv)} failed ({done.returncode}): {message[0]}")
    return wall


def _targets(result: dict) -> dict:
    speedup = result["speedup"]
    goals = {"chaospound us per step": (result["chaospound"]["us_per_step"], "<=", "us_per_step")}
    if "scipy-python" in speedup:
        goals["x wall vs Python rhs"] = (speedup["scipy-python"]["wall"], ">=", "speedup_python")
    goals["x wall vs numba rhs"] = (speedup["scipy-numba"]["wall"], ">=", "speedup_numba")
    if result["cli"] is not None:
        goals["CLI end to end, s"] = (result["cli"]["wall_s"], "<=", "cli_s")
    return {
        label: {
            "value": value,
            "comparison": cmp,
            "target": TARGETS[key],
            "met": bool(value <= TARGETS[key] if cmp == "<=" else value >= TARGETS[key]),
        }
        for label, (value, cmp, key) in goals.items()
    }


def _table(headers: Sequence[str], rows: Sequence[Sequence[str]], align: str) -> str:
    lines = [list(headers)] + [list(row) for row in rows]
    widths = [max(len(line[j]) for line in lines) for j in range(len(align))]
    return "\n".join(
        "  ".join(
            cell.ljust(w) if a == "l" else cell.rjust(w)
            for a, cell, w in zip(align, line, widths, strict=True)
        ).rstrip()
        for line in lines
    )
