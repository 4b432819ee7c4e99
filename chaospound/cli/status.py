"""The status line on stderr (compiling, running, a stage of the work) and the
whole command's wall time."""

from __future__ import annotations

import sys
import threading
import time

from chaospound.cli.output import PROG

#: a status line appears once the work has taken this long (s)
STATUS_DELAY_S = 2.0
#: seconds between redraws of the status line
STATUS_INTERVAL_S = 1.0
#: what a first run's compilation of the kernels takes (s): 20-38 s measured on a fresh
#: clone, 54 s on two busy cores
COMPILE_ESTIMATE_S = "10-15"
_COMMAND_START = time.perf_counter()  #: reset by main(): the whole command's start


class _Status:
    """A status line on stderr, redrawn in place with the seconds elapsed.

    Shown only on a terminal (never into a file, a pipe or a test's capture), never
    with ``--quiet``, and only once the work has taken ``delay`` seconds; cleared
    when the work ends, so that stdout and logs hold results only.

    Use as a context manager; :meth:`set` changes the text (a stage of the work).
    """

    def __init__(self, text: str, *, quiet: bool = False, delay: float | None = None,
                 stream=None) -> None:
        self.stream = sys.stderr if stream is None else stream
        try:
            terminal = bool(self.stream.isatty())
        except (AttributeError, ValueError):
            terminal = False
        self.enabled = terminal and not quiet
        self.delay = STATUS_DELAY_S if delay is None else delay
        self.text = text
        self.shown = False
        self._start = time.perf_counter()
        self._done = threading.Event()
        self._thread: threading.Thread | None = None

    def set(self, text: str) -> None:
        self.text = text

    def __enter__(self) -> _Status:
        self._start = time.perf_counter()
        if self.enabled:
            self._thread = threading.Thread(target=self._run, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._done.set()
        if self._thread is not None:
            self._thread.join()
        if self.shown:
            self._write("\r\033[K")

    def _run(self) -> None:
        if self._done.wait(self.delay):
            return
        while True:
            elapsed = time.perf_counter() - self._start
            self._write(f"\r\033[K{PROG}: {self.text} ... {elapsed:.0f} s")
            self.shown = True
            if self._done.wait(STATUS_INTERVAL_S):
                return

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):
            pass


def _load_kernels(quiet: bool, warm=None, engine=None, params=None) -> None:
    """Load the engine of the work before the work, outside its timing: from numba's
    disk cache (well under a second), or by compiling it (the first run of a
    composition after installing or editing, about :data:`COMPILE_ESTIMATE_S` s),
    which is announced at once on a terminal. ``engine`` is the engine the work runs
    (default: the default scene's); ``warm`` the call that loads it (default: one
    tiny step of ``engine`` on ``params``, the packed vector of the work's System)."""
    from chaospound.simulate import kernels_cached, warm_up

    if engine is None:
        from chaospound.engine.compose import engine_for
        from chaospound.simulate import DEFAULT_COMPOSITION

        engine = engine_for(DEFAULT_COMPOSITION)
    if warm is None:
        def warm() -> None:
            warm_up(engine, params)
    cached = kernels_cached(engine.composition)
    if cached is False:
        text, delay = f"compiling kernels, first run only, about {COMPILE_ESTIMATE_S} s", 0.0
    else:
        text, delay = "loading the compiled kernels", None
    with _Status(text, quiet=quiet, delay=delay):
        warm()


def _command_seconds() -> float:
    """Seconds since the command started (:func:`main`): parsing, loading or compiling
    the kernels, the work and the reports."""
    return time.perf_counter() - _COMMAND_START


def _start_command() -> None:
    """Start the clock of :func:`_command_seconds` (called by :func:`chaospound.cli.main`)."""
    global _COMMAND_START
    _COMMAND_START = time.perf_counter()
