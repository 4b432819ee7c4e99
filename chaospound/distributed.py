"""Run sweeps on a dask.distributed cluster (optional dependency).

The sweep engine (:mod:`chaospound.sweep`) cuts the grid into tasks of whole
chunks of points (or segments of continuation chains); this backend submits
them to a Dask scheduler instead of local processes, while the client keeps
committing results to the same store (its journal, keyed by grid index), so the
file is identical to the local backend's whatever the number of workers and
the order of completion.

* The scene and the sweep definition travel once: they are the result of one
  small task (the "payload") that every sweep task depends on, so a worker
  fetches them once and each task carries only its point indices and, for
  continuation, a start state. Being a task (not scattered data), the payload
  is recomputed by the scheduler if every worker holding it dies.
* Tasks are pure functions of their inputs; a worker that dies has its tasks
  rerun elsewhere by the scheduler (``retries`` more on errors), and results
  are committed once, by the client, keyed by their grid index, so no point is
  lost or doubled.
* If the scheduler goes away the sweep stops with :class:`ClusterUnavailable`,
  the file keeps every point written so far, and ``--resume`` (on Dask or
  locally) finishes it.
* Workers compile nothing per task: the kernels are numba-cached on disk
  (``chaospound/kernels/__pycache__``, or ``NUMBA_CACHE_DIR``) and loaded once
  per worker process.
"""

from __future__ import annotations

import contextlib
import math
import re
import time
import uuid

__all__ = ["ClusterUnavailable", "DaskBackend", "connect", "default_chunk", "disconnect",
           "run_task_remote"]

DEFAULT_RETRIES = 3  #: reruns of a task that raised (a dead worker's tasks are rerun anyway)
CONNECT_TIMEOUT = "10s"  #: to reach an existing scheduler
CLOSE_TIMEOUT = 10  #: seconds to close a client or a LocalCluster
WORKERS_REFRESH_S = 2.0  #: how often the cluster's thread count is re-read (it may scale)
TASK_COST = 1.5  #: CPU of one task's bookkeeping, in fig4 points (benchmarks/bench_dask.py)
MAX_CHUNK = 256  #: default points per task, at most (more on clusters of more threads)
_ADDRESS = re.compile(r"(?:(tcp|tls|ucx)://)?(\[[0-9a-fA-F:.]+\]|[^\s:/\[\]]+):(\d{1,5})")


class ClusterUnavailable(RuntimeError):
    """The scheduler cannot be reached (or went away mid-sweep)."""


def connect(scheduler: str, workers: int = 2):
    """A ``distributed.Client`` for ``tcp://HOST:PORT`` or a new LocalCluster ("local").

    Parameters
    ----------
    scheduler : str
        ``"local"``: start a LocalCluster of ``workers`` single-threaded worker
        processes on this machine (loopback only). Else the address of a
        running scheduler, ``tcp://HOST:PORT`` (``tls://``, ``ucx://``; a bare
        ``HOST:PORT`` means ``tcp://``).
    workers : int
        Worker processes of the LocalCluster (ignored for an address).

    Returns
    -------
    (client, cluster)
        ``cluster`` is None for an existing scheduler; the caller closes both.

    Raises
    ------
    ValueError
        A malformed address, ``workers`` < 1, or dask.distributed missing.
    ClusterUnavailable
        No scheduler answers at the address within 10 s.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - the extra is not installed
        raise ValueError(
            "--scheduler needs dask.distributed: pip install 'chaospound[dask]'") from None
    if scheduler == "local":
        if workers < 1:
            raise ValueError(f"--workers {workers}: must be >= 1")
        # no dashboard; the scheduler's small HTTP server (health, metrics) on any free
        # port, not 8787, which another cluster may hold (that would warn on stderr)
        with _sigint_ignored():  # inherited: a terminal's Ctrl-C reaches only the client
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   host="127.0.0.1", dashboard_address=None,
                                   scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
        try:
            return Client(cluster), cluster
        except BaseException:
            cluster.close()
            raise
    address = _check_address(scheduler)
    try:
        return Client(address, timeout=CONNECT_TIMEOUT), None
    except (OSError, TimeoutError, AssertionError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ClusterUnavailable(f"cannot reach the Dask scheduler {address}: {first}") from None


def disconnect(client, cluster=None) -> None:
    """Close what :func:`connect` returned, quietly (also after the scheduler died).

    A client that lost its scheduler logs its failed reconnection as an error
    with a traceback when closed; a command line reports that as one line
    already, so logging is muted while closing.
    """
    import logging

    muted = logging.root.manager.disable
    logging.disable(logging.CRITICAL)
    try:
        for thing in (client, cluster):
            if thing is not None:
                try:
                    thing.close(timeout=CLOSE_TIMEOUT)
                except Exception:  # already closed, or its scheduler is gone
                    pass
    finally:
        logging.disable(muted)


def default_chunk(client, n_points: int) -> int:
    """Points per task of a sweep of ``n_points`` on ``client``'s cluster of T threads.

    Two costs depend on the chunk: every task costs the client, the scheduler
    and a worker a few milliseconds of CPU, about ``TASK_COST`` points of the
    fig4 window (40 + 8 cycles; benchmarks/bench_dask.py), a fraction
    ``TASK_COST / chunk`` of the compute; and at the end of the sweep the
    threads idle for about half a task each, a fraction ``T chunk / (2 n)``.
    Their sum is least at ``chunk = sqrt(2 TASK_COST n / T)``. Then at least T
    points, so that the client, which handles the tasks one after the other,
    keeps up with T threads; at most ``n / (2 T)`` (two tasks or more per
    thread) and ``MAX_CHUNK`` points (progress, work lost with a worker).
    Dearer points (Lyapunov exponents, ``classify="full"``) make the task cost
    smaller still in proportion.
    """
    try:
        threads = _cluster_threads(client)
    except Exception as exc:  # the scheduler is gone
        raise ClusterUnavailable(_lost(exc)) from None
    chunk = max(round(math.sqrt(2 * TASK_COST * n_points / threads)), threads)
    return int(max(1, min(chunk, max(MAX_CHUNK, threads), n_points // (2 * threads))))


def run_task_remote(payload, indices, start_state, continuation):
    """Worker side: run one task of the sweep (scene and spec from ``payload``)."""
    from .point import run_task

    scene, spec = payload
    return run_task(scene, spec, indices, start_state, continuation)


def _payload(scene, spec):
    """The payload task: its result is what every sweep task of one sweep shares."""
    return scene, spec


class DaskBackend:
    """Sweep backend submitting tasks to a ``distributed.Client``.

    Keys are unique per sweep (a random tag), so sweeps from several clients,
    or a resumed sweep, never share or reuse each other's results. Finished
    tasks are collected with ``distributed.as_completed`` and their results
    fetched in one round trip per batch: the client's cost per task does not
    grow with the number of tasks in flight (about two per worker thread).
    """

    def __init__(self, client, scene, spec, retries: int = DEFAULT_RETRIES) -> None:
        from distributed import as_completed

        if client.status != "running":
            raise ClusterUnavailable(f"the Dask client is {client.status}, not running")
        self.client = client
        self.retries = retries
        self._tag = f"chaospound-{uuid.uuid4().hex[:12]}"
        self._workers = 1
        self._checked = -float("inf")
        _ = self.workers  # first reading of the cluster size
        self._payload = client.submit(_payload, scene, spec, key=f"{self._tag}-payload",
                                      pure=False, retries=self.retries)
        self._futures = set()  # submitted, result not yet taken
        self._completed = as_completed()
        self._results = {}  # finished future -> its result, until result() takes it

    @property
    def workers(self) -> int:
        """Threads in the cluster now (at least 1), re-read every few seconds.

        The sweep keeps about twice this many tasks in flight, so a cluster
        that scales up (dask-jobqueue) is used as it grows.
        """
        now = time.monotonic()
        if now - self._checked >= WORKERS_REFRESH_S and self.client.status == "running":
            self._checked = now
            with contextlib.suppress(Exception):  # keep the last reading; wait_some
                self._workers = _cluster_threads(self.client)  # reports a lost scheduler
        return self._workers

    def submit(self, task):
        key = f"{self._tag}-{task.branch}-{task.key[0]}-{task.key[1]}"
        try:
            fut = self.client.submit(run_task_remote, self._payload, task.indices,
                                     task.start_state, task.continuation, key=key, pure=False,
                                     retries=self.retries)
        except Exception as exc:  # a closed client or comm
            raise ClusterUnavailable(_lost(exc)) from None
        self._futures.add(fut)
        self._completed.add(fut)
        return fut

    def wait_some(self, futures):
        """Every submitted task finished by now (at least one), results fetched.

        ``futures`` (the caller's tasks in flight) are the backend's own; a
        task that failed for good, or futures cancelled because the client lost
        the scheduler, raise :class:`ClusterUnavailable`.
        """
        if self._completed.is_empty():
            raise RuntimeError("wait_some: no task in flight")
        try:
            batch = self._completed.next_batch(block=True)
            values = self.client.gather(batch)
        except Exception as exc:
            raise ClusterUnavailable(_lost(exc)) from None
        self._results.update(zip(batch, values, strict=True))
        return batch

    def result(self, fut):
        self._futures.discard(fut)
        return self._results.pop(fut)

    def abort(self) -> None:
        try:
            if self.client.status == "running":
                self.client.cancel(list(self._futures) + [self._payload])
        except Exception:
            pass
        self._completed.clear()
        self._futures.clear()
        self._results.clear()

    def close(self) -> None:
        self.abort()


def _lost(exc: Exception) -> str:
    """One line for a task that will not deliver."""
    from concurrent.futures import CancelledError

    if isinstance(exc, CancelledError | OSError):  # futures cancelled, comm closed
        return "lost the connection to the Dask scheduler"
    text = str(exc).splitlines()[0] if str(exc) else ""
    return f"Dask task failed: {type(exc).__name__}{': ' + text if text else ''}"


@contextlib.contextmanager
def _sigint_ignored():
    """SIGINT ignored while LocalCluster starts its worker processes, which inherit it.

    Ctrl-C at a terminal goes to the whole process group; the client handles it
    (commits the finished points, exit 130) and closes the cluster, so workers
    should not die of it first, each with a traceback.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _cluster_threads(client) -> int:
    """Worker threads in the cluster now (at least 1)."""
    info = client.scheduler_info(n_workers=0)
    return max(1, int(info.get("total_threads", 0)))


def _check_address(scheduler: str) -> str:
    """``scheme://HOST:PORT`` from the --scheduler text, or ValueError."""
    if scheduler.startswith("inproc://"):  # in-process clusters (tests)
        return scheduler
    m = _ADDRESS.fullmatch(scheduler.strip())
    if m is None or not 1 <= int(m.group(3)) <= 65535:
        raise ValueError(f"--scheduler {scheduler!r}: expected tcp://HOST:PORT (port 1-65535) "
                         "or 'local'")
    return f"{m.group(1) or 'tcp'}://{m.group(2)}:{int(m.group(3))}"
