"""Reading accelerograms (PEER NGA ``.AT2`` and plain text) and converting them to model units.

Python only; the kernels that evaluate a record are in :mod:`.record`.

Formats
-------
PEER NGA ``.AT2``
    Free header lines, then one line giving the number of points and the sample
    interval in any of the forms met in the NGA databases::

        NPTS= 4000, DT= .0100 SEC
        NPTS=  4000, DT=   .0050 SEC,
        npts = 4000 , dt = 0.005 sec
        4000   .0100   NPTS, DT          (the older PEER strong-motion format)

    then the NPTS acceleration values, up to 5 (or any number) a line, in free or
    Fortran E format (``.1234E-02``, ``-0.1234567E-02``, ``1.0D-3``). The first
    value is at t = 0, the k-th at ``k * DT``. The units are read from the header
    (``UNITS OF G``, ``CM/S/S``, ``CM/SEC^2``, ``M/S/S``...); if it states none,
    the ``units`` argument of :func:`load_record`, else ``g``.
Plain text
    Comment lines start with ``#``, ``%`` or ``!``; one header line of column
    names may precede the numbers; separators are blanks, commas, semicolons or
    tabs. Without ``dt`` the columns are ``time, a_x`` or ``time, a_x, a_y``
    (time in s, strictly increasing, not necessarily uniform); with ``dt`` they
    are ``a_x`` or ``a_x, a_y`` sampled at ``k * dt``.

Two horizontal components come from two files (both ``.AT2``, or both text with
one acceleration column, on the same time base) or from a text file with two
acceleration columns.

Every problem with a file raises :class:`ValueError` with one line naming the file
and the problem (the command line turns it into exit status 2).

Units
-----
Accelerations are converted to m/s^2 (:data:`UNITS`: ``g`` is the standard
9.80665 m/s^2), multiplied by the scale factor, and then made dimensionless with
the model's scales (docs/model.md section 2): with a length scale ``A_g`` [m] and
the time scale ``omega_Ax`` [rad/s],

    t = omega_Ax * tau,        u_g'' = a / (A_g * omega_Ax^2),

tau the physical time [s] and a the physical acceleration [m/s^2]; the integrated
``u_g`` is then in units of A_g and ``u_g'`` in units of A_g omega_Ax.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "UNITS",
    "Accelerogram",
    "load_record",
    "read_at2",
    "read_text",
    "to_model",
    "unit_factor",
]

STANDARD_GRAVITY = 9.80665  #: m/s^2

#: m/s^2 per unit, by canonical name
UNITS = {"g": STANDARD_GRAVITY, "m/s^2": 1.0, "cm/s^2": 0.01}

_UNIT_ALIASES = {
    "g": "g",
    "m/s^2": "m/s^2",
    "m/s2": "m/s^2",
    "m/s/s": "m/s^2",
    "m/sec^2": "m/s^2",
    "m/sec/sec": "m/s^2",
    "m/sec2": "m/s^2",
    "cm/s^2": "cm/s^2",
    "cm/s2": "cm/s^2",
    "cm/s/s": "cm/s^2",
    "cm/sec^2": "cm/s^2",
    "cm/sec/sec": "cm/s^2",
    "cm/sec2": "cm/s^2",
    "gal": "cm/s^2",
}

#: a real number in free or Fortran format (D or E exponent, optional leading digit)
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?"
_NUMBER_RE = re.compile(_NUMBER)
_HEADER_NEW = re.compile(
    r"NPTS\s*=\s*(?P<n>[-+]?\d+)\s*[,;]?\s*DT\s*=\s*(?P<dt>" + _NUMBER + r")", re.IGNORECASE
)
_HEADER_OLD = re.compile(
    r"^\s*(?P<n>[-+]?\d+)\s*[,;]?\s+(?P<dt>" + _NUMBER + r")\s+NPTS\s*[,;]?\s*DT", re.IGNORECASE
)
_PER_SECOND_SQUARED = r"\s*/\s*S(?:EC)?\s*(?:/\s*S(?:EC)?|\^?\s*2|\*\*\s*2)"  # /s/s, /sec^2...
_AT2_UNITS = (  # (pattern in the header, unit), first match wins
    (re.compile(r"\bCM" + _PER_SECOND_SQUARED, re.IGNORECASE), "cm/s^2"),
    (re.compile(r"\bGALS?\b", re.IGNORECASE), "cm/s^2"),
    (re.compile(r"\bM" + _PER_SECOND_SQUARED, re.IGNORECASE), "m/s^2"),
    (re.compile(r"UNITS?\s+OF\s+G\b|\bIN\s+G\b|\(G\)", re.IGNORECASE), "g"),
)
_UNITS_STATED = re.compile(r"UNITS?\s+(?:OF|IN)\s+(\S+)", re.IGNORECASE)
_SEPARATORS = re.compile(r"[\s,;]+")


@dataclass(frozen=True)
class Accelerogram:
    """A ground acceleration history in SI units.

    Attributes
    ----------
    time : numpy.ndarray
        Sample times [s], strictly increasing.
    x : numpy.ndarray
        Acceleration of the x component [m/s^2] at ``time``.
    y : numpy.ndarray or None
        Acceleration of the y component [m/s^2], or None for one component.
    source : str
        The file name(s), for messages.
    """

    time: np.ndarray
    x: np.ndarray
    y: np.ndarray | None
    source: str


def unit_factor(units: str, source: str = "record") -> float:
    """m/s^2 per unit of ``units`` (``g``, ``m/s^2``, ``cm/s^2`` and spellings such as ``gal``).

    Raises
    ------
    ValueError
        Naming ``source`` and the unknown unit.
    """
    key = units.strip().lower().replace(" ", "")
    if key not in _UNIT_ALIASES:
        raise ValueError(f"{source}: unknown units {units!r}; use one of g, m/s^2, cm/s^2")
    return UNITS[_UNIT_ALIASES[key]]


def _parse_float(token: str) -> float:
    return float(token.replace("D", "E").replace("d", "e"))


def _numbers(line: str, where: str) -> list[float]:
    """The numbers of one data line; ValueError on anything else."""
    values = []
    for token in _SEPARATORS.split(line.strip()):
        if not token:
            continue
        if _NUMBER_RE.fullmatch(token):
            values.append(_parse_float(token))
            continue
        # Fortran fixed-width fields may touch: "-.1234E-02-.5678E-03"
        parts = _NUMBER_RE.findall(token)
        if parts and "".join(parts) == token:
            values.extend(_parse_float(part) for part in parts)
            continue
        raise ValueError(f"{where}: non-numeric value {token!r}")
    return values


def _read_lines(path: Path) -> list[str]:
    try:
        text = path.read_text(encoding="utf-8-sig", errors="replace")
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if not text.strip():
        raise ValueError(f"{path}: empty file")
    return text.splitlines()


def _at2_units(header: Sequence[str], path: Path) -> str | None:
    for line in header:
        for pattern, unit in _AT2_UNITS:
            if pattern.search(line):
                return unit
    for line in header:
        stated = _UNITS_STATED.search(line)
        if stated:
            raise ValueError(f"{path}: unknown units {stated.group(1)!r} in the AT2 header")
    return None


def read_at2(path: str | Path) -> tuple[float, np.ndarray, str | None]:
    """Read a PEER NGA ``.AT2`` file.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    dt : float
        Sample interval [s].
    acceleration : numpy.ndarray
        The NPTS values, in the file's units (the first at t = 0).
    units : str or None
        Canonical name of the units stated in the header, None if it states none.

    Raises
    ------
    ValueError
        One line naming the file and the problem: empty file, no NPTS/DT line,
        NPTS not matching the number of values, a non-numeric value, DT not
        positive, unknown units.
    """
    path = Path(path)
    lines = _read_lines(path)
    found = next(((index, match) for index, line in enumerate(lines)
                  if (match := _HEADER_NEW.search(line) or _HEADER_OLD.search(line))), None)
    if found is None:
        raise ValueError(f"{path}: no 'NPTS=..., DT=...' line in the AT2 header")
    index, match = found
    npts = int(match.group("n"))
    dt = _parse_float(match.group("dt"))
    if npts < 2:
        raise ValueError(f"{path}: NPTS={npts}, need at least 2 samples")
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"{path}: DT={match.group('dt')} is not a positive interval")
    units = _at2_units(lines[: index + 1], path)
    values: list[float] = []
    for number, line in enumerate(lines[index + 1 :], start=index + 2):
        values.extend(_numbers(line, f"{path}, line {number}"))
    if len(values) != npts:
        raise ValueError(f"{path}: NPTS={npts} in the header but {len(values)} values follow")
    acceleration = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(acceleration)):
        raise ValueError(f"{path}: non-finite acceleration value")
    return dt, acceleration, units


def read_text(path: str | Path, dt: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read a plain one-, two- or three-column text accelerogram.

    Parameters
    ----------
    path : str or Path
        The file.
    dt : float, optional
        Sample interval [s]. Given: the columns are accelerations (``a_x`` or
        ``a_x, a_y``) at ``k * dt``. Omitted: the first column is the time [s].

    Returns
    -------
    time : numpy.ndarray
        Sample times [s].
    acceleration : numpy.ndarray
        Shape (n, 1) or (n, 2): the components, in the file's units.

    Raises
    ------
    ValueError
        One line naming the file and the problem: empty, non-numeric value,
        ragged rows, too many columns, one column without ``dt``, fewer than 2
        samples, time not strictly increasing, non-finite values.
    """
    path = Path(path)
    lines = _read_lines(path)
    rows: list[list[float]] = []
    header_allowed = True
    for number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped or stripped[0] in "#%!":
            continue
        tokens = [token for token in _SEPARATORS.split(stripped) if token]
        if header_allowed and not any(_NUMBER_RE.fullmatch(token) for token in tokens):
            header_allowed = False  # one line of column names
            continue
        header_allowed = False
        rows.append(_numbers(stripped, f"{path}, line {number}"))
    if not rows:
        raise ValueError(f"{path}: empty file (no numbers)")
    width = len(rows[0])
    for row in rows:
        if len(row) != width:
            raise ValueError(f"{path}: rows of {width} and {len(row)} columns")
    data = np.asarray(rows, dtype=np.float64)
    if not np.all(np.isfinite(data)):
        raise ValueError(f"{path}: non-finite value")
    if len(data) < 2:
        raise ValueError(f"{path}: {len(data)} sample, need at least 2")
    if dt is None:
        if width == 1:
            raise ValueError(f"{path}: one column (acceleration only) needs the sample interval dt")
        if width > 3:
            raise ValueError(f"{path}: {width} columns; expected time, a_x[, a_y]")
        time, acceleration = data[:, 0], data[:, 1:]
        if not np.all(np.diff(time) > 0.0):
            raise ValueError(f"{path}: time is not strictly increasing")
    else:
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"{path}: dt={dt} is not a positive interval")
        if width > 2:
            raise ValueError(f"{path}: {width} columns with dt given; expected a_x[, a_y]")
        time, acceleration = np.arange(len(data)) * float(dt), data
    return np.ascontiguousarray(time), np.ascontiguousarray(acceleration)


def _read_one(path: Path, units: str | None, dt: float | None) -> tuple[np.ndarray, np.ndarray]:
    """(time [s], acceleration [m/s^2] of shape (n, k)) of one file of either format."""
    if path.suffix.lower() == ".at2":
        step, values, stated = read_at2(path)
        if stated is None:
            factor = unit_factor(units if units is not None else "g", str(path))
        elif units is not None and unit_factor(units, str(path)) != UNITS[stated]:
            raise ValueError(f"{path}: the header states units {stated!r}, not {units!r}")
        else:
            factor = UNITS[stated]
        time = np.arange(len(values)) * step
        return time, values[:, None] * factor
    time, values = read_text(path, dt)
    factor = unit_factor(units if units is not None else "g", str(path))
    return time, values * factor


def load_record(
    files: str | Path | Sequence[str | Path],
    units: str | None = None,
    dt: float | None = None,
    scale: float = 1.0,
) -> Accelerogram:
    """Load one accelerogram (one or two horizontal components) in m/s^2.

    Parameters
    ----------
    files : path or sequence of paths
        One file (an ``.AT2``, or text with one or two acceleration columns), or
        two files with one component each (x first), on the same time base.
    units : str, optional
        ``g``, ``m/s^2`` or ``cm/s^2`` (or ``gal``...). ``.AT2`` files state their
        own (a conflicting ``units`` is an error); text files default to ``g``.
    dt : float, optional
        Sample interval [s] of text files without a time column.
    scale : float
        Factor on the accelerations (dimensionless), e.g. for incremental
        dynamic analysis.

    Returns
    -------
    Accelerogram
        Times [s] and accelerations [m/s^2], scaled.

    Raises
    ------
    ValueError
        One line naming the file and the problem.
    """
    paths = [Path(files)] if isinstance(files, (str, Path)) else [Path(f) for f in files]
    if not 1 <= len(paths) <= 2:
        raise ValueError(f"record: one or two files (x, y), got {len(paths)}")
    if not math.isfinite(scale):
        raise ValueError(f"record: scale factor {scale} is not finite")
    source = " + ".join(str(path) for path in paths)
    parts = [_read_one(path, units, dt) for path in paths]
    time = parts[0][0]
    columns = [column for _, values in parts for column in values.T]
    if len(paths) == 2:
        for path, (other, values) in zip(paths[1:], parts[1:], strict=True):
            if values.shape[1] != 1 or parts[0][1].shape[1] != 1:
                raise ValueError(f"{path}: two files must hold one component each")
            if len(other) != len(time) or not np.array_equal(other, time):
                raise ValueError(f"{path}: not on the time base of {paths[0]} "
                                 f"({len(other)} against {len(time)} samples)")
    x = np.ascontiguousarray(columns[0] * scale)
    y = np.ascontiguousarray(columns[1] * scale) if len(columns) > 1 else None
    return Accelerogram(time=np.ascontiguousarray(time, dtype=np.float64), x=x, y=y, source=source)


def to_model(
    record: Accelerogram, length_scale: float, omega: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The record in model units: ``t = omega tau``, ``u_g'' = a / (A_g omega^2)``.

    Parameters
    ----------
    record : Accelerogram
        Times [s], accelerations [m/s^2].
    length_scale : float
        A_g [m], the model's unit of length.
    omega : float
        omega_Ax [rad/s], tower A's translational circular frequency (the model's
        unit of frequency).

    Returns
    -------
    t, a_x, a_y : numpy.ndarray (a_y None for one component)
        Dimensionless times and accelerations.
    """
    if not (math.isfinite(length_scale) and length_scale > 0.0):
        raise ValueError(f"{record.source}: length scale A_g={length_scale} m is not positive")
    if not (math.isfinite(omega) and omega > 0.0):
        raise ValueError(f"{record.source}: omega_Ax={omega} rad/s is not positive")
    factor = 1.0 / (length_scale * omega * omega)
    t = record.time * omega
    a_y = None if record.y is None else record.y * factor
    return t, record.x * factor, a_y
