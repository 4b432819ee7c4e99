"""The append-only journal of a running sweep: SQLite in WAL mode, one row a point.

A sweep writes its finished points here, not into the HDF5 file: each batch
is one SQLite transaction, made durable (``synchronous=FULL``: the write-ahead
log is fsynced) before the points count as done. SQLite's commit is atomic,
so whatever kills the process, at whatever moment, the journal holds exactly
the batches whose commit returned, and a partly written batch is rolled back
the next time the journal is opened. Nothing committed is ever rewritten in
place, unlike the partly filled chunks of a growing HDF5 dataset.

Files beside the output ``X.h5``: ``X.h5.journal`` (the database) and, while
it is open, SQLite's ``X.h5.journal-wal`` and ``X.h5.journal-shm``. Copy or
move all of them together.

Tables::

    meta(key TEXT PRIMARY KEY, value BLOB)
        format, version, n_state, n_exponents, branches (JSON list), attrs (JSON:
        the root attributes of the HDF5 file), created, wall_s
    grid(axis INTEGER PRIMARY KEY, name TEXT, values BLOB)   float64 bytes
    orders(branch TEXT PRIMARY KEY, order BLOB)    visiting order, int64 bytes
    points(branch, idx, pos, status, regime, n_impacts, n_strobe, payload)
        one row per finished point; pos = position in the branch's visiting
        order; payload = the point's values, packed by the store (opaque here)
"""

from __future__ import annotations

import contextlib
import json
import os
import sqlite3
from pathlib import Path

import numpy as np

__all__ = ["JOURNAL_FORMAT", "Journal", "JournalError", "fsync_dir", "journal_path"]

JOURNAL_FORMAT = "chaospound-sweep-journal"
JOURNAL_VERSION = 1
SUFFIX = ".journal"


class JournalError(ValueError):
    """A journal that is not a chaospound journal or cannot be read."""


def journal_path(output) -> Path:
    """The journal of a sweep output file."""
    output = Path(output)
    return output.with_name(output.name + SUFFIX)


def sidecars(path: Path) -> tuple[Path, Path]:
    """SQLite's write-ahead log and shared-memory index of a journal."""
    return (path.with_name(path.name + "-wal"), path.with_name(path.name + "-shm"))


def remove(path: Path) -> None:
    """Delete a journal: the database first, then its sidecars.

    A stale ``-wal`` without its database must never meet a new database of
    the same name (SQLite would replay it), so :meth:`Journal.create` removes
    leftover sidecars too.
    """
    for p in (path, *sidecars(path)):
        with contextlib.suppress(FileNotFoundError):
            p.unlink()


# ---------------------------------------------------------------- the journal


class Journal:
    """An open sweep journal (use :meth:`create` or :meth:`open`)."""

    def __init__(self, path: Path, conn: sqlite3.Connection) -> None:
        self.path = path
        self.conn = conn
        meta = dict(conn.execute("SELECT key, value FROM meta"))
        if meta.get("format") != JOURNAL_FORMAT:
            raise JournalError(f"{path}: not a chaospound sweep journal")
        if int(meta.get("version", 0)) > JOURNAL_VERSION:
            raise JournalError(f"{path}: journal version is newer than this chaospound")
        self.attrs: dict = json.loads(meta["attrs"])
        self.n_state = int(meta["n_state"])
        self.n_exponents = int(meta["n_exponents"])
        self.created = str(meta["created"])
        self.grid = {name: np.frombuffer(values, dtype=np.float64).copy()
                     for name, values in conn.execute("SELECT name, \"values\" FROM grid "
                                                      "ORDER BY axis")}
        self.orders = {b: np.frombuffer(o, dtype=np.int64).copy()
                       for b, o in conn.execute("SELECT branch, \"order\" FROM orders")}
        self.branches = list(json.loads(meta["branches"]))

    # ------------------------------------------------------------ opening
    @classmethod
    def create(cls, path: Path, attrs: dict, grid: dict, orders: dict, n_state: int,
               n_exponents: int, created: str) -> Journal:
        """A new, empty journal, replacing any old one at ``path``.

        It is built under a temporary name and renamed into place, so a journal
        is never seen half-created (by a reader, or after a kill).
        """
        remove(path)  # stale sidecars of an old journal must not be replayed into this one
        tmp = path.with_name(f"{path.name}.new-{os.getpid()}")
        remove(tmp)
        conn = _connect(tmp)
        with conn:
            conn.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value BLOB)")
            conn.execute("CREATE TABLE orders (branch TEXT PRIMARY KEY, \"order\" BLOB)")
            conn.execute("CREATE TABLE grid (axis INTEGER PRIMARY KEY, name TEXT, "
                         "\"values\" BLOB)")
            conn.execute("CREATE TABLE points (branch TEXT, idx INTEGER, pos INTEGER, "
                         "status INTEGER, regime INTEGER, n_impacts INTEGER, "
                         "n_strobe INTEGER, payload BLOB, PRIMARY KEY (branch, idx))")
            conn.execute("CREATE INDEX points_pos ON points (branch, pos)")
            rows = {
                "format": JOURNAL_FORMAT, "version": JOURNAL_VERSION,
                "attrs": json.dumps(attrs), "n_state": n_state, "n_exponents": n_exponents,
                "created": created, "wall_s": 0.0,
                "branches": json.dumps(list(orders)),
            }
            conn.executemany("INSERT INTO meta VALUES (?, ?)", rows.items())
            conn.executemany("INSERT INTO grid VALUES (?, ?, ?)",
                             [(axis, name, np.asarray(values, dtype=np.float64).tobytes())
                              for axis, (name, values) in enumerate(grid.items())])
            conn.executemany("INSERT INTO orders VALUES (?, ?)",
                             [(b, np.asarray(o, dtype=np.int64).tobytes())
                              for b, o in orders.items()])
        conn.close()  # checkpoints into the database file and removes the sidecars
        os.replace(tmp, path)
        fsync_dir(path.parent)
        return cls(path, _connect(path))

    @classmethod
    def open(cls, path: Path, *, readonly: bool = False) -> Journal:
        """An existing journal; a batch whose commit never returned is rolled back."""
        if not path.exists():
            raise JournalError(f"{path}: no such file")
        try:
            conn = _connect(path, readonly=readonly)
            return cls(path, conn)
        except (sqlite3.Error, KeyError, ValueError, TypeError) as exc:
            if isinstance(exc, JournalError):
                raise
            raise JournalError(f"{path}: not a readable chaospound sweep journal "
                               f"({str(exc).splitlines()[0][:80]})") from None

    def close(self) -> None:
        """Close; the last connection's close checkpoints the log and removes the sidecars."""
        if self.conn is not None:
            self.conn.close()
            self.conn = None

    # ------------------------------------------------------------ writing
    def commit(self, branch: str, rows: list[tuple], wall_s: float) -> None:
        """Append finished points in one durable transaction.

        ``rows``: (idx, pos, status, regime, n_impacts, n_strobe, payload) each.
        """
        with self.conn:
            self.conn.executemany(
                "INSERT OR REPLACE INTO points VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                [(branch, *row) for row in rows])
            self.conn.execute("UPDATE meta SET value = value + ? WHERE key = 'wall_s'",
                              (wall_s,))

    # ------------------------------------------------------------ reading
    @contextlib.contextmanager
    def snapshot(self):
        """Every read inside sees the same committed state (a reader beside a writer)."""
        self.conn.execute("BEGIN")
        try:
            yield self
        finally:
            self.conn.execute("COMMIT")

    @property
    def wall_s(self) -> float:
        return float(self.conn.execute("SELECT value FROM meta WHERE key = 'wall_s'")
                     .fetchone()[0])

    def statuses(self, branch: str) -> np.ndarray:
        """Status per grid index (0 pending, 1 done, 2 failed)."""
        out = np.zeros(self.orders[branch].size, dtype=np.int8)
        for idx, status in self.conn.execute(
                "SELECT idx, status FROM points WHERE branch = ?", (branch,)):
            out[idx] = status
        return out

    def payload(self, branch: str, idx: int) -> bytes | None:
        row = self.conn.execute("SELECT payload FROM points WHERE branch = ? AND idx = ?",
                                (branch, int(idx))).fetchone()
        return None if row is None else row[0]

    def counts(self, branch: str) -> tuple[int, int, int]:
        """Finished points, impact rows and stroboscopic rows of a branch."""
        n, imp, strobe = self.conn.execute(
            "SELECT COUNT(*), COALESCE(SUM(n_impacts), 0), COALESCE(SUM(n_strobe), 0) "
            "FROM points WHERE branch = ?", (branch,)).fetchone()
        return int(n), int(imp), int(strobe)

    def regime_counts(self) -> dict[int, int]:
        """Regime code -> number of finished points, over all branches."""
        return {int(code): int(n) for code, n in self.conn.execute(
            "SELECT regime, COUNT(*) FROM points GROUP BY regime")}

    def payload_bytes(self) -> int:
        return int(self.conn.execute(
            "SELECT COALESCE(SUM(LENGTH(payload)), 0) FROM points").fetchone()[0])

    def rows_in_order(self, branch: str, batch: int):
        """Payloads of a branch's finished points in visiting order, in lists of at most
        ``batch``."""
        cursor = self.conn.execute("SELECT payload FROM points WHERE branch = ? "
                                   "ORDER BY pos", (branch,))
        while True:
            rows = cursor.fetchmany(batch)
            if not rows:
                return
            yield [blob for (blob,) in rows]


def _connect(path: Path, readonly: bool = False) -> sqlite3.Connection:
    if readonly:
        conn = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True,
                               isolation_level=None, check_same_thread=False)
        conn.execute("PRAGMA query_only = ON")
        return _with_transactions(conn)
    conn = sqlite3.connect(str(path), isolation_level=None, check_same_thread=False)
    conn.execute("PRAGMA journal_mode = WAL")
    conn.execute("PRAGMA synchronous = FULL")  # the log is fsynced at every commit
    return _with_transactions(conn)


def _with_transactions(conn: sqlite3.Connection) -> sqlite3.Connection:
    conn.isolation_level = "DEFERRED"  # `with conn:` is one transaction
    return conn


def fsync_dir(folder: Path) -> None:
    """Make a created or renamed file's directory entry durable."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
