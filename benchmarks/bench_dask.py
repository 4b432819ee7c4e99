"""Sweep throughput: local backend against Dask.distributed, and Dask's cost per task.

The fig4 scan (preset fig4: 40 + 8 cycles per point, dopri5, rtol 1e-6) over
``period_ratio=0.3:2.0#N`` (N = 400 by default), run

* locally with 1 and with 2 worker processes (default chunk), and
* on a Dask LocalCluster of 2 single-threaded worker processes, at several
  chunk sizes (points per task), including the default one.

Every configuration runs ``--repeats`` times after a warm-up (numba caches
loaded in every process); the best wall time and the least CPU time count.
Each file is checked to equal the local workers=1 file (timing fields aside).

Scheduling overhead, three ways:

1. CPU time (robust on a shared machine, where wall times follow the load):
   the CPU seconds of the whole sweep (this process, its children, the Dask
   workers) minus those of the serial run, which is pure computation and the
   HDF5 writes. For Dask the idle cluster's background (event loops,
   heartbeats; measured over 5 s with nothing to do, times the wall time) is
   taken out first; the rest, divided by the number of tasks, is the CPU cost
   of one task: submit, scheduling, sending the task and its result.
2. Empty tasks: tasks of zero points through the same backend and the same
   submit / wait / result loop as a sweep (same in-flight limit): the wall
   time per task with no compute to hide it, and its CPU time in this process
   (the client, and the LocalCluster's scheduler) and in the workers.
3. Wall time: ``(P * wall - compute) / tasks``, with P the worker processes
   and compute the sum of the points' own ``wall_s`` (time inside
   :func:`chaospound.sweep.run_point`, as stored in the file). It charges
   everything that is not a point's computation to the tasks, the idle tail
   at the end of the sweep included; on a loaded machine it is noisy.

Usage::

    python benchmarks/bench_dask.py [--points 400] [--repeats 3] [--chunks 1,2,5,10,50,100]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

from chaospound.cli import write_json_file
from chaospound.distributed import DaskBackend
from chaospound.distributed import default_chunk as dask_default_chunk
from chaospound.scene import load_preset
from chaospound.store import TIMING_FIELDS, open_sweep
from chaospound.sweep import SweepSpec, _LocalBackend, _Task, make_axis, run_sweep

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUTPUT = ROOT / "results" / "bench_dask.json"
EMPTY_TASKS = 400


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=400, help="grid points (400)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs each (best counts)")
    parser.add_argument("--chunks", default="1,2,5,10,50,100",
                        help="Dask chunk sizes (comma-separated; the default one is added)")
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT), help="JSON file written")
    args = parser.parse_args()

    scene = load_preset("fig4").with_assignments(["rtol=1e-6"])
    spec = SweepSpec(axes=(make_axis("period_ratio", f"0.3:2.0#{args.points}", scene),),
                     classify="paper")
    chunks = sorted({int(c) for c in args.chunks.split(",")})
    result = {
        "scene": "fig4", "rtol": 1e-6, "transient": scene.run.transient,
        "record": scene.run.record, "grid": f"period_ratio=0.3:2.0#{args.points}",
        "points": args.points, "repeats": args.repeats, "machine": machine(),
        "method": __doc__[__doc__.index("Scheduling overhead"):__doc__.index("Usage")].strip(),
        "runs": [], "empty_tasks": {},
    }
    with tempfile.TemporaryDirectory() as tmp:
        reference = os.path.join(tmp, "reference.h5")
        run_sweep(scene, spec, reference, progress=False)  # warm-up, and the reference file
        local = {f"local workers={w}": {"workers": w} for w in (1, 2)}
        result["runs"] += measure_all(scene, spec, tmp, reference, args.repeats, local)
        result["empty_tasks"]["local workers=2"] = empty_tasks(
            _LocalBackend(2, scene, spec), EMPTY_TASKS)

        from distributed import Client, LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          host="127.0.0.1", dashboard_address=None) as cluster, \
                Client(cluster) as client:
            for _ in range(2):  # loads the kernels in every worker, first-task costs
                run_sweep(scene, spec, os.path.join(tmp, "warm.h5"), client=client,
                          progress=False, overwrite=True)
            default = dask_default_chunk(client, spec.n_points)
            result["default_chunk"] = {"local workers=1": local_default_chunk(spec, 1),
                                       "local workers=2": local_default_chunk(spec, 2),
                                       "dask 2 threads": default}
            dask = {f"dask 2 processes chunk={c}": {"client": client, "chunk": c}
                    for c in chunks}
            dask[f"dask 2 processes default chunk={default}"] = {"client": client}
            result["runs"] += measure_all(scene, spec, tmp, reference, args.repeats, dask)
            result["empty_tasks"]["dask 2 processes"] = empty_tasks(
                DaskBackend(client, scene, spec), EMPTY_TASKS, client)
            result["dask_idle_cpu_per_s"] = idle_cpu(client)
    serial = result["runs"][0]
    for r in result["runs"]:
        extra = r["cpu_s"] - serial["cpu_s"]
        if r["label"].startswith("dask"):  # the cluster's background, apart
            r["background_cpu_s"] = result["dask_idle_cpu_per_s"] * r["wall_s"]
            extra -= r["background_cpu_s"]
        r["cpu_overhead_per_task_ms"] = 1e3 * extra / r["tasks"]
        r["cpu_overhead_percent"] = 100 * extra / serial["cpu_s"]
    result["machine"]["load_average_end"] = list(os.getloadavg())
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    write_json_file(result, args.output, overwrite=True)
    print(format_table(result))
    print(f"\nwrote {args.output}")


def local_default_chunk(spec: SweepSpec, workers: int) -> int:
    """The chunk run_sweep picks by default for the local backend."""
    return int(min(32, max(1, spec.n_points // (workers * 8))))


def measure_all(scene, spec, tmp, reference, repeats, configs: dict) -> list[dict]:
    """Every configuration ``repeats`` times, in turns (so that a busy spell of a shared
    machine falls on all of them); best wall time, least CPU time, file equality."""
    path = os.path.join(tmp, "run.h5")
    runs = {label: [] for label in configs}
    for _ in range(repeats):
        for label, options in configs.items():
            client = options.get("client")
            cpu = cpu_seconds(client)
            summary = run_sweep(scene, spec, path, overwrite=True, progress=False, **options)
            cpu = cpu_seconds(client) - cpu
            if differences(reference, path):
                raise SystemExit(f"{label}: the file differs from the local workers=1 file")
            compute = float(np.nansum(open_sweep(path).array("wall_s")))
            runs[label].append((summary.wall_s, compute, cpu))
    rows = []
    for label, options in configs.items():
        client, chunk = options.get("client"), options.get("chunk")
        wall, compute, _ = min(runs[label])
        cpu = min(r[2] for r in runs[label])
        if chunk is None:
            chunk = (dask_default_chunk(client, spec.n_points) if client is not None
                     else local_default_chunk(spec, options.get("workers", 1)))
        tasks = -(-spec.n_points // chunk)
        processes = 2 if (client is not None or options.get("workers") == 2) else 1
        rows.append({
            "label": label, "chunk": chunk, "tasks": tasks, "wall_s": wall,
            "all_wall_s": [r[0] for r in runs[label]], "points_per_s": spec.n_points / wall,
            "compute_s": compute, "processes": processes, "cpu_s": cpu,
            "all_cpu_s": [r[2] for r in runs[label]],
            "efficiency": compute / (processes * wall),
            "overhead_per_task_ms": 1e3 * (processes * wall - compute) / tasks,
            "compute_per_task_ms": 1e3 * compute / tasks, "equal_to_local": True,
        })
        print(f"  {label}: {spec.n_points / wall:.1f} points/s, {cpu:.2f} CPU s",
              file=sys.stderr)
    return rows


def cpu_seconds(client=None) -> float:
    """CPU time so far of this process, its finished children and the Dask workers."""
    t = os.times()
    workers = sum(client.run(time.process_time).values()) if client is not None else 0.0
    return time.process_time() + t.children_user + t.children_system + workers


def empty_tasks(backend, n: int, client=None) -> dict:
    """Tasks of zero points through ``backend``, with the sweep loop's in-flight limit.

    CPU time: this process (the client, and the scheduler of a LocalCluster) and
    the workers (Dask: ``time.process_time`` in each; local: the pool's children,
    counted once the pool has shut down)."""
    limit = 2 * backend.workers + 2
    nothing = np.zeros(0, dtype=np.int64)
    tasks = iter([_Task("fresh", (k, 0), nothing, None, False, True) for k in range(n)])
    workers_cpu = (lambda: sum(client.run(time.process_time).values())) if client else None
    before = (time.perf_counter(), time.process_time(), os.times(),
              workers_cpu() if workers_cpu else 0.0)
    try:
        in_flight, done = set(), 0
        while True:
            while len(in_flight) < limit:
                task = next(tasks, None)
                if task is None:
                    break
                in_flight.add(backend.submit(task))
            if not in_flight:
                break
            for fut in backend.wait_some(list(in_flight)):
                in_flight.discard(fut)
                assert backend.result(fut) == []
                done += 1
        wall = time.perf_counter() - before[0]
        after_workers = workers_cpu() if workers_cpu else 0.0
    finally:
        backend.close()
    client_cpu = time.process_time() - before[1]
    if workers_cpu:
        worker_cpu = after_workers - before[3]
    else:
        t = os.times()
        worker_cpu = (t.children_user + t.children_system
                      - before[2].children_user - before[2].children_system)
    return {"tasks": done, "in_flight": limit, "wall_s": wall,
            "ms_per_task": 1e3 * wall / done,
            "client_cpu_ms_per_task": 1e3 * client_cpu / done,
            "workers_cpu_ms_per_task": 1e3 * worker_cpu / done}


def idle_cpu(client, seconds: float = 5.0) -> float:
    """CPU seconds per second that the idle LocalCluster (this process, workers) uses."""
    before, started = cpu_seconds(client), time.perf_counter()
    time.sleep(seconds)
    return (cpu_seconds(client) - before) / (time.perf_counter() - started)


def differences(a, b) -> list[str]:
    """Datasets and attributes that differ between two sweep files (timing fields aside)."""
    out = []
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        def walk(ga, gb, where):
            for key in set(ga.attrs) | set(gb.attrs):
                if key not in TIMING_FIELDS and not (
                        key in ga.attrs and key in gb.attrs
                        and np.array_equal(np.asarray(ga.attrs[key]), np.asarray(gb.attrs[key]))):
                    out.append(f"{where}@{key}")
            for key in set(ga) | set(gb):
                if key not in ga or key not in gb:
                    out.append(f"{where}/{key}")
                elif isinstance(ga[key], h5py.Group):
                    walk(ga[key], gb[key], f"{where}/{key}")
                elif key not in TIMING_FIELDS:
                    x, y = ga[key][()], gb[key][()]
                    if x.dtype != y.dtype or not np.array_equal(
                            x, y, equal_nan=x.dtype.kind == "f"):
                        out.append(f"{where}/{key}")
        walk(fa, fb, "")
    return out


def machine() -> dict:
    return {"cpu_count": os.cpu_count(), "platform": platform.platform(),
            "python": platform.python_version(),
            "load_average_1_5_15": list(os.getloadavg()),
            "dask": _version("dask"), "distributed": _version("distributed"),
            "numba": _version("numba")}


def _version(name: str) -> str:
    try:
        return __import__(name).__version__
    except ImportError:
        return "-"


def format_table(result: dict) -> str:
    m = result["machine"]
    lines = [
        f"fig4 scan, {result['grid']}, {result['transient']} + {result['record']} cycles, "
        f"rtol {result['rtol']:g}; {m['cpu_count']} CPUs, load average "
        f"{m['load_average_1_5_15'][0]:.1f} at the start, {m['load_average_end'][0]:.1f} at "
        "the end",
        "",
        f"{'backend':33} {'chunk':>5} {'tasks':>5} {'wall s':>6} {'points/s':>8} "
        f"{'CPU s':>6} {'CPU overhead':>12} {'per task':>8} {'wall overhead':>13}",
        f"{'':33} {'':>5} {'':>5} {'':>6} {'':>8} {'':>6} {'vs serial':>12} {'CPU ms':>8} "
        f"{'per task ms':>13}",
    ]
    for r in result["runs"]:
        lines.append(f"{r['label']:33} {r['chunk']:>5} {r['tasks']:>5} {r['wall_s']:>6.2f} "
                     f"{r['points_per_s']:>8.1f} {r['cpu_s']:>6.2f} "
                     f"{r['cpu_overhead_percent']:>11.1f}% "
                     f"{r['cpu_overhead_per_task_ms']:>8.1f} "
                     f"{r['overhead_per_task_ms']:>13.1f}")
    lines += ["", f"idle LocalCluster (client, scheduler, nannies, 2 workers): "
              f"{result['dask_idle_cpu_per_s']:.3f} CPU s per s, left out of the Dask rows' "
              "CPU overhead", "",
              "empty tasks (chunks of zero points, the sweep's loop and in-flight limit):",
              f"{'backend':33} {'wall ms/task':>12} {'client CPU ms/task':>18} "
              f"{'workers CPU ms/task':>19}"]
    for label, e in result["empty_tasks"].items():
        lines.append(f"{label:33} {e['ms_per_task']:>12.2f} {e['client_cpu_ms_per_task']:>18.2f} "
                     f"{e['workers_cpu_ms_per_task']:>19.2f}")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
