"""Run sweeps on a dask.distributed cluster (optional dependency).

The sweep engine (:mod:`chaospound.sweep`) cuts the grid into tasks of whole
chunks of points (or segments of continuation chains); this backend submits
them to a Dask scheduler instead of local processes, while the client keeps
writing results into the same HDF5 store in the same order, so the file is
identical to the local backend's whatever the number of workers and the order
of completion.

* The scene and the sweep definition are scattered once (broadcast) and each
  task carries only its point indices and, for continuation, a start state.
* Tasks are pure functions of their inputs; a worker that dies has its tasks
  rerun elsewhere by the scheduler (``retries`` more on errors), and results
  are written once, by the client, in order, so no point is lost or doubled.
* If the whole cluster goes away the sweep stops with an error, the file keeps
  every point written so far, and ``--resume`` (on Dask or locally) finishes it.
* Workers compile nothing per task: the kernels are numba-cached on disk.
"""

from __future__ import annotations

import itertools

__all__ = ["DaskBackend", "connect", "run_task_remote"]

DEFAULT_RETRIES = 3


class ClusterUnavailable(RuntimeError):
    """The scheduler cannot be reached (or went away mid-sweep)."""


def connect(scheduler: str, workers: int = 2):
    """A ``distributed.Client`` for ``tcp://HOST:PORT`` or a new LocalCluster ("local").

    Returns (client, cluster) where cluster is None for an existing scheduler;
    the caller closes both.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - the extra is not installed
        raise ValueError(
            "--scheduler needs dask.distributed: pip install 'chaospound[dask]'") from None
    if scheduler == "local":
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        return Client(cluster), cluster
    if not scheduler.startswith(("tcp://", "tls://", "inproc://", "ucx://")):
        raise ValueError(f"--scheduler {scheduler!r}: expected tcp://HOST:PORT or 'local'")
    try:
        return Client(scheduler, timeout="10s"), None
    except OSError as exc:
        raise ClusterUnavailable(f"cannot reach the Dask scheduler {scheduler}: "
                                 f"{str(exc).splitlines()[0]}") from None


def run_task_remote(payload, indices, start_state, continuation):
    """Worker side: run one task of the sweep (scene and spec from ``payload``)."""
    from .sweep import run_task

    scene, spec = payload
    return run_task(scene, spec, indices, start_state, continuation)


class DaskBackend:
    """Sweep backend submitting tasks to a ``distributed.Client``."""

    _counter = itertools.count()

    def __init__(self, client, scene, spec, retries: int = DEFAULT_RETRIES) -> None:
        self.client = client
        self.retries = retries
        info = client.scheduler_info()
        self.workers = max(1, sum(w.get("nthreads", 1) for w in info["workers"].values()))
        [self._payload] = client.scatter([(scene, spec)], broadcast=True, hash=False)
        self._futures = set()
        self._tag = f"chaospound-{next(self._counter)}"

    def submit(self, task):
        key = f"{self._tag}-{task.branch}-{task.key[0]}-{task.key[1]}"
        fut = self.client.submit(run_task_remote, self._payload, list(task.indices),
                                 task.start_state, task.continuation, key=key, pure=False,
                                 retries=self.retries)
        self._futures.add(fut)
        return fut

    def wait_some(self, futures):
        from distributed import wait

        done, _ = wait(futures, return_when="FIRST_COMPLETED")
        return list(done)

    def result(self, fut):
        try:
            value = fut.result()
        except Exception as exc:  # the cluster went away or the task kept failing
            raise ClusterUnavailable(f"Dask task failed: {type(exc).__name__}: "
                                     f"{str(exc).splitlines()[0] if str(exc) else ''}") from None
        finally:
            self._futures.discard(fut)
        return value

    def abort(self) -> None:
        try:
            self.client.cancel(list(self._futures))
        except Exception:
            pass
        self._futures.clear()

    def close(self) -> None:
        self.abort()
