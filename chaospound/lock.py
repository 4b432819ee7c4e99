"""One writer per sweep output: an exclusive lock taken before anything is created.

The lock is ``OUTPUT.lock`` beside the output, held with ``flock(LOCK_EX)`` on
an open descriptor. The kernel releases it when the holder dies, however it
dies (SIGKILL, OOM killer, power loss), so a lock file left behind by a killed
sweep is stale by construction and the next sweep simply takes it over. The
file records the holder (pid, host, start time) for the refusal message.

Races are closed the usual way: after ``flock`` succeeds the holder checks
that the path still names the descriptor's inode (a releasing sweep unlinks
the file before it unlocks), and tries again if not. Forked children close
their copy of the descriptor (:func:`os.register_at_fork`), so an orphaned
worker can never keep a lock alive.
"""

from __future__ import annotations

import contextlib
import os
import socket
import time
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: sweeps cannot be written here
    fcntl = None

__all__ = ["OutputBusy", "OutputLock", "holder"]

#: descriptors of the locks held by this process, closed in forked children
_HELD: set[int] = set()


def _close_in_child() -> None:
    for fd in list(_HELD):
        with contextlib.suppress(OSError):
            os.close(fd)
    _HELD.clear()


os.register_at_fork(after_in_child=_close_in_child)


class OutputBusy(ValueError):
    """Another live process holds the output (a ValueError: bad input, exit 2)."""


class OutputLock:
    """Exclusive, crash-released lock on a sweep output path.

    Parameters
    ----------
    output : str or Path
        The sweep file to be written; the lock file is ``output + ".lock"``.

    Raises
    ------
    OutputBusy
        A live process holds the lock; the message names it.
    """

    def __init__(self, output) -> None:
        self.output = Path(output)
        self.path = self.output.with_name(self.output.name + ".lock")
        self.fd: int | None = None
        self._acquire()

    def _acquire(self) -> None:
        if fcntl is None:  # pragma: no cover
            raise OutputBusy(f"{self.output}: writing sweeps needs a POSIX system (flock)")
        for _ in range(100):
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _read_holder(fd)
                os.close(fd)
                raise OutputBusy(f"{self.output}: a running sweep ({holder}) is writing it; "
                                 "wait for it to finish or stop it first") from None
            except OSError:
                os.close(fd)
                raise
            try:
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                same = False
            if not same:  # the previous holder unlinked it as we locked: lock the new one
                os.close(fd)
                continue
            _HELD.add(fd)
            self.fd = fd
            os.ftruncate(fd, 0)
            os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}, since "
                         f"{time.strftime('%Y-%m-%d %H:%M:%S')}\n".encode())
            return
        raise OutputBusy(f"{self.output}: could not take the lock {self.path}")

    def release(self) -> None:
        """Remove the lock file, then unlock (in that order: see the module docstring)."""
        if self.fd is None:
            return
        with contextlib.suppress(OSError):
            os.unlink(self.path)
        _HELD.discard(self.fd)
        os.close(self.fd)
        self.fd = None

    def __enter__(self) -> OutputLock:
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def holder(output) -> str | None:
    """Who holds the lock of ``output`` now (its pid and host), or None; creates nothing."""
    output = Path(output)
    if fcntl is None:  # pragma: no cover
        return None
    try:
        fd = os.open(output.with_name(output.name + ".lock"), os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return _read_holder(fd)
    except OSError:
        return None
    finally:
        os.close(fd)  # closing also drops the shared lock, if it was taken
    return None


def _read_holder(fd: int) -> str:
    try:
        text = os.pread(fd, 200, 0).decode("utf-8", errors="replace").strip()
    except OSError:
        text = ""
    return text.splitlines()[0] if text else "another process"
