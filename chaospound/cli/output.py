"""What the command line writes: exit codes, error and note lines on stderr,
finished text and strict JSON on stdout, aligned tables."""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Callable, Sequence

from chaospound.messages import shorten
from chaospound.units import UNITS

PROG = "chaospound"
EXIT_OK = 0
EXIT_FAILURE = 1  #: a numerical failure (SimulationError)
EXIT_USAGE = 2  #: bad input: usage, scene, files
EXIT_INTERRUPTED = 130  #: Ctrl-C (128 + SIGINT)
#: most characters of a file name quoted in a message: more than any real path
#: (PATH_MAX is 4096 bytes, real ones are far shorter), less than a pasted screenful
PATH_LIMIT = 1024
#: longest error line: a last resort, the user's values are already cut short where
#: they are quoted (chaospound.messages.shorten)
MESSAGE_LIMIT = 2000
EXIT_BROKEN_PIPE = 141  #: stdout closed early (128 + SIGPIPE), e.g. ``| head``
#: units of the wall-clock times in the JSON documents (``wall_s``)
WALL_UNITS = {"wall_s": "seconds (wall clock)"}


class CliError(ValueError):
    """Bad command-line input (exit code 2); the message is one line."""


def _is_simulation_error(exc: BaseException) -> bool:
    """True for chaospound.simulate.SimulationError (without importing the kernels)."""
    module = sys.modules.get("chaospound.dynamics.system")  # defines SimulationError
    return module is not None and isinstance(exc, module.SimulationError)


def _path(path: object) -> str:
    """A file name as quoted in a message (whole unless absurdly long)."""
    return shorten(path, PATH_LIMIT, quote=True)


def _fail(message: str, code: int) -> int:
    """Report one line on stderr and return ``code``."""
    message = shorten(" ".join(message.split()), MESSAGE_LIMIT)
    sys.stderr.write(f"{PROG}: error: {message}\n")
    sys.stderr.flush()
    return code


def _note(message: str) -> None:
    """One informational line on stderr (``chaospound: note: ...``); stdout stays clean."""
    sys.stderr.write(f"{PROG}: note: {' '.join(message.split())}\n")
    sys.stderr.flush()


def _emit(text: str) -> None:
    """Write finished text to stdout (after all work, so errors leave stdout empty)."""
    sys.stdout.write(text if text.endswith("\n") else text + "\n")
    sys.stdout.flush()


def _silence_stdout() -> None:
    """After a broken pipe: point stdout at /dev/null so exit does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


def _with_units(document: dict) -> dict:
    """Add the ``units`` object (:data:`UNITS`, as in the sweep file) to a JSON document."""
    document["units"] = {**UNITS, **WALL_UNITS}
    return document


def _json_text(document: object) -> str:
    """Strict JSON (NaN and infinities become null), one document."""
    return json.dumps(_finite(document), allow_nan=False) + "\n"


def _finite(value: object) -> object:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(item) for item in value]
    return value


def _table(headers: Sequence[str] | None, rows: Sequence[Sequence[str]], align: str) -> str:
    """Aligned text columns; ``align`` has one "l" or "r" per column."""
    lines = [list(headers)] if headers else []
    lines += [list(row) for row in rows]
    widths = [max(len(line[j]) for line in lines) for j in range(len(align))]
    pad: dict[str, Callable[[str, int], str]] = {"l": str.ljust, "r": str.rjust}
    return "\n".join(
        "  ".join(pad[a](cell, w) for a, cell, w in zip(align, line, widths, strict=True)).rstrip()
        for line in lines
    )
