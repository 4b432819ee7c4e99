"""Sweep grids: ``NAME=GRID`` texts parsed into axes, every value checked against a scene.

A grid is ``start:stop:step``, ``start:stop#count`` or a comma-separated list
of values (see :func:`parse_axis`). This is the edge where user input (the
``--param`` options, a scene file's ``[sweep]`` table) enters a sweep, so:

* parsing is linear in the length of the text: it splits on ``#``, ``:`` and
  ``,`` and converts each piece with ``float``/``int`` (no regular expression
  that could backtrack); one number has at most :data:`MAX_NUMBER_LENGTH`
  characters and a grid at most :data:`MAX_POINTS` values. A list grid has no
  cap of its own on its length: at most ``MAX_POINTS`` numbers of at most
  ``MAX_NUMBER_LENGTH`` characters each, and both caps are checked before any
  number is converted (by counting commas, then by the longest piece);
* no arithmetic can overflow into an exception: non-finite numbers, zero or
  subnormal steps and spans wider than the float range are refused with a
  message;
* every grid value is valid for the scene before anything is written (see
  :func:`check_axis` for why the check is complete without building a
  scene per value); for a user's System (:func:`chaospound.custom_system`) the
  names are its named parameters and the values are checked by
  ``System.with_params``;
* every message is one line and quotes at most about 80 characters of the
  user's text (:func:`chaospound.messages.shorten`).

Errors are ``ValueError``; the command line reports them as one line and exit 2.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from decimal import Decimal

import numpy as np

from .messages import shorten
from .scene import PARAMETERS, SHORTHANDS, Scene, SceneError, _spec

__all__ = [
    "MAX_NUMBER_LENGTH",
    "MAX_POINTS",
    "INITIAL_PHASE",
    "Axis",
    "axes_from_scene",
    "check_axes",
    "check_axis",
    "grid_values",
    "initial_axis",
    "make_axis",
    "parse_axes",
    "parse_axis",
    "state_names_of",
]

MAX_POINTS = 10_000_000  #: most values of one axis
#: most characters of one number of a grid (a float64 needs 24; 100 leaves room for
#: zeros and signs, and keeps a pasted 100 000-digit value from being parsed at all)
MAX_NUMBER_LENGTH = 100
#: axes with at most this many distinct values are checked value by value (about
#: 20 us each); larger ones by their extremes (see :func:`check_axis`)
EXHAUSTIVE_CHECK = 1000

_SYNTAX = "use start:stop:step, start:stop#count or v1,v2,..."


#: the name of the initial-phase axis of a basin scan (a fraction of the period)
INITIAL_PHASE = "initial_phase"
AXIS_KINDS = ("parameter", "state", "phase")


@dataclass(frozen=True)
class Axis:
    """One swept quantity and its values.

    ``kind`` is "parameter" (a scene's or system's parameter: the sweeps), or,
    for basins of attraction (:mod:`chaospound.basins`), "state" (a component
    of the initial state, by its name in the model's state) or "phase" (the
    forcing phase at the start, :data:`INITIAL_PHASE`).
    """

    name: str
    values: np.ndarray
    spec: str
    kind: str = "parameter"

    def __len__(self) -> int:
        return int(self.values.shape[0])


def _target(scene):
    """A Scene, a user's System, or None: a System made from a scene is its scene."""
    from .dynamics.system import System

    if isinstance(scene, System) and scene.scene is not None:
        return scene.scene
    return scene


def _is_system(target) -> bool:
    return target is not None and not isinstance(target, Scene)


def parse_axis(text: str, scene: Scene | None = None) -> Axis:
    """Parse ``name=GRID`` where GRID is ``start:stop:step``, ``start:stop#count``
    or a comma-separated list of values.

    ``start:stop:step`` includes ``stop`` when it lies on the grid (to within
    1e-9 of a step); ``start:stop#count`` is ``numpy.linspace(start, stop, count)``,
    except that a grid whose step is a decimal (``0.85:0.95#5``: 0.025) holds the
    doubles nearest its decimal values, as a step grid does (0.9, not
    0.8999999999999999).
    With a ``scene`` (or a System) every value is checked against it
    (:func:`check_axis`).
    """
    text = str(text)
    if "=" not in text:
        raise ValueError(f"--param {shorten(text, quote=True)}: expected NAME=GRID, "
                         "e.g. period_ratio=0.3:2.0:0.005")
    name, grid = (s.strip() for s in text.split("=", 1))
    return make_axis(name, grid, scene)


def make_axis(name: str, grid: str, scene: Scene | None = None) -> Axis:
    """An Axis from a parameter name and a grid string (see :func:`parse_axis`)."""
    name, grid = str(name), str(grid).strip()
    scene = _target(scene)
    if _is_system(scene):
        known = scene.parameter_names
        if name not in known:
            import difflib

            close = difflib.get_close_matches(name, list(known), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            listed = ", ".join(known) if known else "none"
            raise ValueError(f"unknown sweep parameter {shorten(name, quote=True)}{hint}; "
                             f"system {shorten(scene.name, quote=True)} has: {listed}")
    elif name not in PARAMETERS and name not in SHORTHANDS:
        import difflib

        # the cutoff makes difflib skip long names after an O(1) length test
        close = difflib.get_close_matches(name, list(PARAMETERS) + list(SHORTHANDS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ValueError(f"unknown sweep parameter {shorten(name, quote=True)}{hint}; "
                         "`chaospound params` lists them all")
    elif name in PARAMETERS and (spec := _spec(name)).kind not in ("float", "int"):
        what = ("one of " + ", ".join(spec.choices) if spec.kind == "choice"
                else "true or false" if spec.kind == "bool" else "not a number")
        raise ValueError(f"{name}: not a numeric parameter ({what}); a sweep varies a "
                         f"number: run one sweep per value with --set {name}=...")
    values = grid_values(name, grid)
    axis = Axis(name=name, values=values, spec=grid)
    if scene is not None:
        check_axis(scene, axis)
    return axis


def grid_values(name: str, grid: str) -> np.ndarray:
    """The values of a grid string; ``ValueError`` (one line) if it is not one.

    Linear in ``len(grid)``: one pass of ``str.partition``/``split``, then
    ``float`` on pieces of at most :data:`MAX_NUMBER_LENGTH` characters.
    """
    shown = f"{name}={shorten(grid)}"
    if ":" in grid or "#" in grid:
        head, hash_sign, count_text = grid.partition("#")
        parts = head.split(":", 3)  # at most 4 pieces: more than 3 is refused anyway
        if hash_sign:
            if len(parts) != 2:
                raise ValueError(f"{shown}: not a grid; {_SYNTAX}")
            start, stop = (_number(shown, p) for p in parts)
            count = _count(shown, count_text)
            with np.errstate(over="ignore", invalid="ignore"):  # reported below
                values = np.linspace(start, stop, count)
            exact = _decimal_count_values(parts[0], parts[1], count)
            if exact is not None:
                values = exact
        else:
            if len(parts) != 3:
                raise ValueError(f"{shown}: not a grid; {_SYNTAX}")
            start, stop, step = (_number(shown, p) for p in parts)
            values = _range(shown, start, stop, step)
            exact = _decimal_values(parts[0], parts[2], values.size)
            if exact is not None:
                values = exact
    else:
        values = _list(shown, grid)
    if values.size == 0:
        raise ValueError(f"{shown}: empty range")
    if not np.all(np.isfinite(values)):  # linspace or start + k step beyond the float range
        raise ValueError(f"{shown}: non-finite values (the grid overflows float64)")
    unique, counts = np.unique(values, return_counts=True)
    if unique.size < values.size:  # the same point twice: one label, two rows to select
        raise ValueError(f"{shown}: the value {unique[np.argmax(counts > 1)]:g} is repeated "
                         "(a grid's values must differ)")
    return values


def _number(shown: str, text: str) -> float:
    """One finite number of a grid."""
    text = text.strip()
    if len(text) > MAX_NUMBER_LENGTH:
        raise ValueError(f"{shown}: a number of {len(text)} characters "
                         f"(at most {MAX_NUMBER_LENGTH})")
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{shown}: not a grid; {_SYNTAX}") from None
    if not math.isfinite(value):
        raise ValueError(f"{shown}: non-finite value {text!r} (must be a finite float64)")
    return value


def _count(shown: str, text: str) -> int:
    """The count of ``start:stop#count``: ASCII digits, 1 to MAX_POINTS."""
    text = text.strip()
    if not (text.isascii() and text.isdigit()):
        raise ValueError(f"{shown}: not a grid; {_SYNTAX}")
    digits = text.lstrip("0")
    if len(digits) > len(str(MAX_POINTS)):  # too large, and no int() of 10**5 digits
        raise ValueError(f"{shown}: {shorten(digits, 20)} points, more than {MAX_POINTS}")
    count = int(digits or "0")
    if count < 1:
        raise ValueError(f"{shown}: empty range (count 0)")
    if count > MAX_POINTS:
        raise ValueError(f"{shown}: {count} points, more than {MAX_POINTS}")
    return count


def _range(shown: str, start: float, stop: float, step: float) -> np.ndarray:
    """``start:stop:step``; the arithmetic is done so that nothing overflows."""
    if step == 0 or (stop > start and step < 0) or (stop < start and step > 0):
        raise ValueError(f"{shown}: empty range (step {step} does not lead from "
                         f"{start} to {stop})")
    steps = (stop - start) / step  # >= 0; inf if stop - start overflows or step is tiny
    if math.isinf(stop - start):  # |stop - start| > 1.8e308: divide first
        steps = stop / step - start / step
    if not steps < 1e15:  # also inf: no floor(inf); below, the count is exact
        many = f"about {steps + 1:.3g}" if math.isfinite(steps) else "too many"
        raise ValueError(f"{shown}: {many} points (step {step:g} from {start:g} to "
                         f"{stop:g}), more than {MAX_POINTS}")
    count = math.floor(steps + 1e-9) + 1
    if count > MAX_POINTS:
        raise ValueError(f"{shown}: {count} points, more than {MAX_POINTS}")
    k = np.arange(count)
    with np.errstate(over="ignore"):
        values = start + step * k
        if not np.all(np.isfinite(values)):
            # step * k may overflow while start + step * k does not (-1e308:1e308:1e308):
            # halving is exact for these normal numbers; a real overflow stays inf and is
            # reported by grid_values
            values = 2.0 * (0.5 * start + (0.5 * step) * k)
    return values


def _scaled_integers(*texts: str) -> tuple[list[int], int] | None:
    """Decimal numbers as integers times ``10**exponent`` (one exponent, between -15 and
    0: the most decimals written); None if one is not a decimal or has more places."""
    try:
        numbers = [Decimal(text.strip()) for text in texts]
    except ArithmeticError:
        return None
    exponents = [n.as_tuple().exponent for n in numbers]
    if not all(isinstance(e, int) for e in exponents):  # nan, inf
        return None
    exponent = min(*exponents, 0)
    if exponent < -15:
        return None
    return [int(n * 10 ** -exponent) for n in numbers], exponent


def _decimal_values(start: str, step: str, count: int) -> np.ndarray | None:
    """``start + k step`` as the doubles nearest the decimal values the user typed.

    ``0.3:2.0:0.1`` then holds exactly the doubles of 0.3, 0.4, ..., 2.0 (``start
    + k step`` in floating point gives 0.7999999999999999 for 0.8), so that grid
    coordinates compare equal to typed values (``.sel(period_ratio=0.8)``). With
    both numbers written with at most 15 decimals, n = (start + k step) 10^d is an
    integer below 2^53, exact in float64, and n / 10^d is one correctly rounded
    division. None when that does not hold (the float formula is used).
    """
    scaled = _scaled_integers(start, step)
    if scaled is None:
        return None
    (first_n, stride_n), exponent = scaled
    scale = 10 ** -exponent
    last_n = first_n + stride_n * (count - 1)
    if max(abs(first_n), abs(stride_n), abs(last_n)) >= 2**53:  # also a lone point's step
        return None
    return (first_n + stride_n * np.arange(count, dtype=np.int64)) / float(scale)


def _decimal_count_values(start: str, stop: str, count: int) -> np.ndarray | None:
    """``start:stop#count`` as the doubles nearest its decimal values, where its step
    ``(stop - start) / (count - 1)`` is a decimal of at most 15 places.

    ``0.85:0.95#5`` then holds the double of 0.9 (``numpy.linspace`` gives
    0.8999999999999999), as ``0.85:0.95:0.025`` does (:func:`_decimal_values`).
    None where the step is not such a decimal (``0.3:2.0#1000``: 1.7 / 999) or the
    numbers do not fit: ``numpy.linspace`` is used.
    """
    scaled = _scaled_integers(start, stop) if count >= 2 else None
    if scaled is None:
        return None
    (first_n, last_n), exponent = scaled
    span = last_n - first_n
    for extra in range(16 + exponent):  # decimals of the step beyond those typed
        if span * 10**extra % (count - 1) == 0:
            step = Decimal(span * 10**extra // (count - 1)).scaleb(exponent - extra)
            return _decimal_values(start, str(step), count)
    return None


def _list(shown: str, grid: str) -> np.ndarray:
    """``v1,v2,...``; empty items are skipped."""
    if grid.count(",") >= MAX_POINTS:
        raise ValueError(f"{shown}: {grid.count(',') + 1} values, more than {MAX_POINTS}")
    parts = [p for p in (s.strip() for s in grid.split(",")) if p]
    longest = max(parts, key=len, default="")
    if len(longest) > MAX_NUMBER_LENGTH:
        _number(shown, longest)  # raises: too long
    try:
        values = np.array([float(p) for p in parts], dtype=np.float64)
    except ValueError:
        raise ValueError(f"{shown}: not a grid; {_SYNTAX}") from None
    if not np.all(np.isfinite(values)):
        bad = parts[int(np.flatnonzero(~np.isfinite(values))[0])]
        raise ValueError(f"{shown}: non-finite value {bad!r} (must be a finite float64)")
    return values


# ------------------------------------------------------------ values vs the scene


def check_axis(scene: Scene, axis: Axis) -> None:
    """Raise ``ValueError`` naming the parameter and the value unless every value of
    ``axis`` makes a valid scene.

    Why checking a few values is complete. With the other parameters fixed, the
    scene accepts a float value ``v`` of one parameter when ``v`` satisfies

    1. the parameter's range (:class:`chaospound.scene._Spec`: ``low``, ``high``),
       an interval;
    2. the overlap of the towers, ``|offset_y| < (l_A + l_B)/2``: an interval in
       ``offset_y``, ``length_A``, ``length_B`` or ``length``;
    3. with a fixed ``model`` of the reduced kind (wall, pair): ``e_y = 0`` and
       ``offset_y = 0``, where ``e_y`` is ``ecc_y`` or ``ecc_y_ratio * length``:
       a point or a half-line (an interval) in each of them;
    4. ``atol = 1e-3 rtol > 0`` while atol follows rtol: a half-line in ``rtol``;
    5. for the integer parameters (``transient``, ``record``, ``steps_per_cycle``,
       ``max_steps``), an integral value: not an interval;
    6. choice and boolean parameters refuse every float.

    An axis of a contact input that the scene's contact law does not read
    (:meth:`Scene.unused_contact_inputs`, e.g. ``restitution`` under the elastic
    ``hertz`` law) is refused too: its points would all be the same.

    1-4 and 6 make the valid values an interval (empty for 6): if the smallest and
    the largest value of the grid are valid, every value between them is. 5 is
    checked on every value at once with numpy (the first non-integral value, if
    any, is given to the scene, which names it). So three scenes are built
    whatever the size of the grid. Grids of at most :data:`EXHAUSTIVE_CHECK`
    distinct values (every list a person types) are checked value by value
    anyway, in grid order, so the first bad value is the one reported;
    tests/test_input_limits.py compares the two ways.
    """
    scene = _target(scene)
    if not _is_system(scene) and axis.name in scene.unused_contact_inputs():
        from .scene import not_read_message

        raise ValueError(f"sweep {axis.name}={shorten(axis.spec)}: every point would be the "
                         f"same: {not_read_message(scene.contact.contact_law, axis.name)}")
    bad = _first_invalid(scene, axis.name, axis.values)
    if bad is not None:
        value, exc = bad
        problem = str(exc)
        if not problem.startswith(f"{axis.name} = "):  # e.g. the overlap: name the value
            problem = f"at {axis.name} = {value!r}: {problem}"
        raise ValueError(f"sweep {axis.name}={shorten(axis.spec)}: {problem}") from None


def _first_invalid(scene: Scene, name: str, values: np.ndarray,
                   exhaustive: int = EXHAUSTIVE_CHECK) -> tuple[float, SceneError] | None:
    """The first value (of the values tried, see :func:`check_axis`) that makes an
    invalid scene (or System), with its error; None if there is none."""
    refused = ValueError if _is_system(scene) else SceneError
    for value in _candidates(values, exhaustive):
        try:
            scene.with_params(**{name: value})
        except refused as exc:
            return value, exc
    return None


def _candidates(values: np.ndarray, exhaustive: int) -> list[float]:
    """The values whose check covers every value of ``values`` (see check_axis)."""
    if values.size <= exhaustive:
        return list(dict.fromkeys(values.tolist()))  # distinct, in grid order
    fractional = values != np.floor(values)
    first = int(np.argmax(fractional))  # the first True, or 0 if there is none
    tried = [float(values.min()), float(values.max())]
    if fractional[first]:
        tried.append(float(values[first]))
    return tried


def check_axes(scene: Scene, axes: Sequence[Axis]) -> None:
    """Check every axis (:func:`check_axis`) and, for two axes, their combinations.

    Two parameters may only be valid together in part of the plane (e.g.
    ``length_A`` and ``offset_y`` through the overlap condition). Every joint
    condition of the scene (2. and 3. of :func:`check_axis`) makes the valid set
    convex in the two values, so the grid's box is valid when its four corners
    are: the corners are checked, or every pair of distinct values when there are
    at most :data:`EXHAUSTIVE_CHECK` of them.
    """
    scene = _target(scene)
    for axis in axes:
        check_axis(scene, axis)
    if len(axes) != 2 or axes[0].name == axes[1].name:
        return  # other counts and duplicates are refused by SweepSpec
    first, second = axes
    values = [_candidates(a.values, EXHAUSTIVE_CHECK) for a in axes]
    if len(values[0]) * len(values[1]) > EXHAUSTIVE_CHECK:
        values = [[float(a.values.min()), float(a.values.max())] for a in axes]
    refused = ValueError if _is_system(scene) else SceneError
    for x, y in itertools.product(*values):
        try:
            scene.with_params(**{first.name: x, second.name: y})
        except refused as exc:
            raise ValueError(f"sweep {first.name}={x!r} with {second.name}={y!r}: "
                             f"{exc}") from None


def parse_axes(texts: Iterable[str], scene: Scene) -> list[Axis]:
    """Axes from ``--param`` texts, every grid point checked against ``scene`` (a Scene
    or a System)."""
    scene = _target(scene)
    axes = [parse_axis(t, scene) if _is_system(scene) else parse_axis(t) for t in texts]
    check_axes(scene, axes)
    return axes


def axes_from_scene(scene: Scene) -> list[Axis]:
    """The sweep stored in a preset's [sweep] table, as axes."""
    axes = [make_axis(name, grid) for name, grid in scene.sweep]
    check_axes(scene, axes)
    return axes


# ------------------------------------------------------ initial-condition axes


def state_names_of(target) -> tuple[str, ...]:
    """Names of the state components of a scene (its model's) or a System."""
    target = _target(target)
    if isinstance(target, Scene):
        from .scene import STATE_NAMES

        return STATE_NAMES[target.model_id()]
    return tuple(target.state_names)


def initial_axis(text: str, target) -> Axis:
    """An axis of initial conditions from ``NAME=GRID`` (a basin scan's ``--grid``).

    ``NAME`` is a state component of the target's model (``X_A``, ``dX_A``, ...
    for a scene; the system's ``state_names``) or :data:`INITIAL_PHASE` (the
    forcing phase at the start, a fraction of the period in [0, 1)); ``GRID`` as
    in :func:`parse_axis`. ``ValueError`` (one line, listing the valid names)
    for anything else.
    """
    text = str(text)
    if "=" not in text:
        raise ValueError(f"--grid {shorten(text, quote=True)}: expected NAME=GRID, "
                         "e.g. X_A=-8:8#101")
    name, grid = (s.strip() for s in text.split("=", 1))
    names = state_names_of(target)
    if name == INITIAL_PHASE:
        kind = "phase"
        resolved = _target(target)
        ground = (resolved.excitation.ground if isinstance(resolved, Scene)
                  else getattr(resolved, "ground", "sine"))
        if ground == "record":  # a record is not periodic: its time origin is fixed
            raise ValueError(f"{INITIAL_PHASE}: needs a periodic forcing, not a ground "
                             "record (scan state components instead)")
    elif name in names:
        kind = "state"
    else:
        import difflib

        valid = [*names, INITIAL_PHASE]
        target = _target(target)
        parameters = (target.parameter_names if _is_system(target)
                      else (*PARAMETERS, *SHORTHANDS))
        if name in parameters:
            raise ValueError(f"{shorten(name, quote=True)} is a parameter, not an initial "
                             f"condition (fix it with --set); scan: {', '.join(valid)}")
        close = difflib.get_close_matches(name, valid, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ValueError(f"unknown initial-condition axis {shorten(name, quote=True)}{hint}; "
                         f"valid: {', '.join(valid)}")
    values = grid_values(name, grid)
    if kind == "phase" and not (np.all(values >= 0.0) and np.all(values < 1.0)):
        raise ValueError(f"{name}={shorten(grid)}: the initial phase is a fraction of the "
                         "period, in [0, 1)")
    return Axis(name=name, values=values, spec=grid, kind=kind)
