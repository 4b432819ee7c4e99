"""The options every scene command shares: the scene or user's System they select
(:func:`add_scene_options`, :func:`scene_from_args`, :func:`target_from_args`), the
output options, the argparse types, and the engine a target's runs use."""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

from chaospound.cli.output import CliError, _note, _path
from chaospound.cli.status import STATUS_DELAY_S
from chaospound.messages import shorten

if TYPE_CHECKING:
    from chaospound.scene import Scene


#: run and solver options applied as scene overrides (option dest = flat parameter name)
RUN_OVERRIDES = ("transient", "record", "method", "rtol", "atol", "phase")


def add_scene_options(parser: argparse.ArgumentParser, *, run: bool = True) -> None:
    """Add the options that select and modify a scene.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A subcommand's parser.
    run : bool
        Also add the run and solver overrides (--transient, --record,
        --method, --rtol, --atol, --phase).

    Notes
    -----
    Values are kept as text and validated by the scene layer
    (:meth:`Scene.with_assignments`), so every error names the parameter,
    the value and the allowed range.
    """
    group = parser.add_argument_group("scene")
    group.add_argument(
        "scene_file", nargs="?", metavar="SCENE.toml",
        help="scene file (see 'chaospound presets'); simulate, section, impact-map, classify, "
        "lyapunov and sweep also take FILE.py:ATTR, a System defined in a Python file "
        "(docs/custom_systems.md)"
    )
    group.add_argument("--preset", metavar="NAME", help="a bundled scene instead of a file")
    group.add_argument(
        "--set",
        dest="assignments",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a parameter (repeatable; see 'chaospound params')",
    )
    if not run:
        return
    group.add_argument("--transient", metavar="N", help="cycles discarded before recording")
    group.add_argument("--record", metavar="N", help="cycles recorded")
    group.add_argument(
        "--method", metavar="M", help="dopri5, cash-karp, rk4, dop853 or paper (cash-karp, 1e-3)"
    )
    group.add_argument("--rtol", metavar="R", help="relative tolerance")
    group.add_argument("--atol", metavar="A", help="absolute tolerance")
    group.add_argument("--phase", metavar="F", help="section phase, a fraction of the period")


def add_output_options(parser: argparse.ArgumentParser, *, plot_help: str,
                       quiet_help: str = "status") -> argparse._ArgumentGroup:
    """The output options of an analysis command: --json, --plot, --quiet.

    ``--overwrite`` is accepted and hidden: a figure is a derived product and is
    redrawn; data files (.h5, .json) are never a --plot target.
    """
    out = parser.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print one JSON document only")
    out.add_argument("--plot", metavar="FILE.png", help=plot_help)
    out.add_argument("--overwrite", action="store_true", help=argparse.SUPPRESS)
    out.add_argument("--quiet", action="store_true",
                     help=f"no {quiet_help} line on stderr (compiling, running; shown on a "
                     f"terminal when the work takes more than {STATUS_DELAY_S:g} s)")
    return out


def scene_from_args(args: argparse.Namespace) -> Scene:
    """The scene selected and modified by :func:`add_scene_options`' options.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    Scene
        The preset or file, then every ``--set`` in order, then the run and
        solver options (which win over ``--set`` of the same name).

    Raises
    ------
    CliError
        Both or neither of --preset and a scene file, a missing file.
    SceneError
        An unknown preset, a malformed file, a bad or unknown parameter.
    """
    from chaospound.scene import load_preset, load_scene
    from chaospound.userfile import is_system_spec

    preset, path = args.preset, args.scene_file
    if is_system_spec(path):
        raise CliError(f"{_path(path)}: this command takes a scene (--preset NAME or SCENE.toml); "
                       "a system FILE.py:ATTR runs with simulate, section, impact-map, classify, "
                       "lyapunov and sweep")
    if preset is not None and path is not None:
        raise CliError(f"give --preset {shorten(preset)} or the scene file {_path(path)}, not both")
    if preset is None and path is None:
        raise CliError("no scene: give --preset NAME or a scene file (see 'chaospound presets')")
    if path is not None and not os.path.exists(path):
        raise CliError(f"scene file {_path(path)} not found")
    scene = load_preset(preset) if preset is not None else load_scene(path)
    if path is not None:
        _note_file_defaults(path, scene)
    overrides = [
        f"{name}={getattr(args, name)}"
        for name in RUN_OVERRIDES
        if getattr(args, name, None) is not None
    ]
    assignments = list(args.assignments) + overrides
    scene = scene.with_assignments(assignments) if assignments else scene
    _note_unread_contact_inputs(scene)
    return scene


#: run and solver settings of a System that --set may change (name -> parser)
SYSTEM_SETTINGS = {"transient": int, "record": int, "method": str, "rtol": float,
                   "atol": float, "steps_per_cycle": int, "max_steps": int}


def target_from_args(args: argparse.Namespace):
    """The scene, or the user's System, selected by the scene options.

    A scene argument ``FILE.py:ATTR`` loads a System
    (:func:`chaospound.userfile.load_system`); ``--set NAME=VALUE`` then sets
    its named parameters (``System.with_params``) or its run and solver
    settings (transient, record, method, rtol, atol, steps_per_cycle,
    max_steps), and the run options (--transient, --record, --method, --rtol,
    --atol) win over ``--set``. Anything else is :func:`scene_from_args`.

    Returns
    -------
    Scene or System

    Raises
    ------
    CliError, SystemSpecError, SceneError
        Bad input, one line each (exit code 2).
    """
    from chaospound.userfile import is_system_spec, load_system

    path = args.scene_file
    if not is_system_spec(path):
        return scene_from_args(args)
    if args.preset is not None:
        raise CliError(f"give --preset {shorten(args.preset)} or the system {_path(path)}, "
                       "not both")
    if getattr(args, "phase", None) is not None:
        raise CliError(f"--phase {shorten(args.phase)}: a system's sections are taken at "
                       "t = k T (set its period instead)")
    system = load_system(path)
    overrides = [f"{name}={getattr(args, name)}" for name in RUN_OVERRIDES
                 if getattr(args, name, None) is not None]
    return _system_with_assignments(system, list(args.assignments) + overrides)


def _system_with_assignments(system, assignments: Sequence[str]):
    """A System with ``NAME=VALUE`` assignments applied in order (see target_from_args)."""
    import dataclasses

    from chaospound.solvers.tableaux import METHOD_NAMES

    for text in assignments:
        name, eq, value = (part.strip() for part in str(text).partition("="))
        if not eq or not name:
            raise CliError(f"--set {shorten(text, quote=True)}: expected NAME=VALUE")
        if name in SYSTEM_SETTINGS:
            try:
                parsed = SYSTEM_SETTINGS[name](value)
            except ValueError:
                kind = {int: "an integer", float: "a number"}[SYSTEM_SETTINGS[name]]
                raise CliError(f"--set {name}={shorten(value)}: not {kind}") from None
            if name == "method" and parsed not in METHOD_NAMES:
                raise CliError(f"--set method={shorten(value)}: need one of "
                               f"{', '.join(METHOD_NAMES)}")
            if isinstance(parsed, float) and not (math.isfinite(parsed) and parsed > 0.0):
                raise CliError(f"--set {name}={shorten(value)}: need a finite number > 0")
            if name == "rtol" and parsed >= 1.0:  # as a scene's rtol (scene.PARAMETERS)
                raise CliError(f"--set rtol={shorten(value)}: need rtol in (0, 1)")
            if isinstance(parsed, int) and parsed < (1 if name != "transient" else 0):
                raise CliError(f"--set {name}={shorten(value)}: too small")
            system = dataclasses.replace(system, **{name: parsed})
            continue
        if name not in system.parameter_names:
            known = ", ".join((*system.parameter_names, *SYSTEM_SETTINGS))
            raise CliError(f"--set {shorten(name, quote=True)}: not a parameter of system "
                           f"{shorten(system.name, quote=True)} (it has: {known})")
        try:
            number = float(value)
        except ValueError:
            raise CliError(f"--set {name}={shorten(value)}: not a number") from None
        system = system.with_params(**{name: number})
    return system


def _is_system(target) -> bool:
    from chaospound.scene import Scene

    return not isinstance(target, Scene)


#: the defaults named when a scene file sets no parameter
FILE_DEFAULTS_SHOWN = ("period_ratio", "freq_ratio", "mass_ratio", "gap", "beta", "chi",
                       "length_A", "width_ratio_A", "zeta_x_A", "method", "rtol", "transient",
                       "record")


def _note_unread_contact_inputs(scene: Scene) -> None:
    """A contact input set to other than its default that the scene's law does not read
    (``restitution`` with the elastic ``hertz`` law) changes nothing: say so on stderr
    rather than let the run look like what was asked for."""
    from chaospound.scene import not_read_message

    for name in scene.unused_contact_inputs(changed_only=True):
        value = getattr(scene.contact, name)
        shown = f"{value:g}" if isinstance(value, float) else str(value).lower()
        _note(f"{name} = {shown} has no effect: "
              f"{not_read_message(scene.contact.contact_law, name)}")


def _note_file_defaults(path: str, scene: Scene) -> None:
    """A scene file that sets no parameter (e.g. an empty file) runs the default scene:
    say so on stderr, with the main defaults, instead of running silently."""
    try:
        import tomllib
    except ModuleNotFoundError:  # pragma: no cover - Python 3.10
        import tomli as tomllib
    try:
        with open(path, "rb") as stream:
            data = tomllib.load(stream)
    except (OSError, ValueError):
        return  # load_scene read it already; nothing to add
    if any(isinstance(table, dict) and table for table in data.values()):
        return
    values = scene.to_dict()
    shown = ", ".join(f"{name.removesuffix('_A').replace('zeta_x', 'zeta')} = {values[name]:g}"
                      if isinstance(values[name], float | int) else f"{name} = {values[name]}"
                      for name in FILE_DEFAULTS_SHOWN)
    _note(f"scene file {_path(path)} sets no parameter: running the default scene ({shown}; "
          "every default: 'chaospound params')")


def _positive_float(text: str) -> float:
    """argparse type: a number > 0."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a number > 0")
    return value


def _float_pair(text: str) -> tuple[float, float]:
    """argparse type: two finite numbers separated by a comma (``7,4.5``)."""
    parts = text.split(",")
    try:
        pair = tuple(float(p) for p in parts)
    except ValueError:
        pair = ()
    if len(pair) != 2 or not all(math.isfinite(v) for v in pair):
        raise argparse.ArgumentTypeError(f"{text!r}: must be two numbers, e.g. 0.5,1.5")
    return pair


def _engine_of(scene) -> dict:
    """The engine a scene's (or a System's) runs use (its composition's) and the
    packed vector it runs on: ``_load_kernels``'s ``engine`` and ``params``."""
    from chaospound.dynamics.system import System

    system = scene if isinstance(scene, System) else System.from_scene(scene)
    return {"engine": system.engine(), "params": system.params}


def _system_warm(target):
    """The call that loads a user System's engine (one period), or None for a scene."""
    if not _is_system(target):
        return None

    def warm() -> None:
        from chaospound.dynamics.system import evolve

        evolve(target, cycles=1)
    return warm


def _count(text: str) -> int:
    """argparse type: an integer >= 1 (--workers, --chunk: 0 and -2 get the same words)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: must be an integer >= 1")
    return value


def _count0(text: str) -> int:
    """argparse type: an integer >= 0 (counts where 0 means none, or that the command
    checks itself to name the option in its message)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"{shorten(text, quote=True)}: must be an integer >= 0")
    return value
