"""The ``chaospound`` command line.

Commands::

    chaospound presets [NAME]            table of presets, or one preset's TOML
    chaospound params [NAME ...]         flat parameter names, meaning and range
    chaospound simulate (--preset NAME | SCENE.toml) [--set k=v ...] [--json] ...
    chaospound section (--preset NAME | SCENE.toml) [--phase P] [--cycles N] [--plot FILE] ...
    chaospound impact-map (--preset NAME | SCENE.toml) [--plot FILE] [--json] ...
    chaospound sweep (--preset NAME | SCENE.toml) [--param NAME=GRID ...] -o FILE.h5 ...
    chaospound plot FILE.h5 [-o FILE.png|.pdf|.svg] [--branch NAME] [--dpi N] [--size W,H] ...
    chaospound orbit (--preset NAME | SCENE.toml) [--period K] [--json]
    chaospound continue (--preset NAME | SCENE.toml) --param NAME=START:STOP [--period K] -o B.h5
    chaospound plot BRANCH.h5 [--over SWEEP.h5] [-o FILE.png]

Every command that runs a scene takes the same scene options, added by
:func:`add_scene_options` and turned into a validated
:class:`~chaospound.scene.Scene` by :func:`scene_from_args`; later commands
(lyapunov, classify, sweep, plot, bench) reuse both. ``simulate``, ``classify``,
``lyapunov`` and ``sweep`` also take a user's system, ``FILE.py:ATTR`` in place
of the scene file (:func:`target_from_args`, :mod:`chaospound.userfile`).

Exit codes: 0 success; 1 a numerical failure
(:class:`~chaospound.simulate.SimulationError`); 2 bad input (usage, scene
parameters, scene files, output files), reported as one line
``chaospound: error: ...`` on stderr with nothing written; 130 interrupted.

Heavy modules (numpy through the scene layer, numba through the kernels) are
imported inside the command functions, so ``chaospound --help`` and usage
errors stay fast.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, NoReturn

from chaospound.messages import QUOTE_LIMIT, shorten
from chaospound.units import UNITS

if TYPE_CHECKING:
    from chaospound.scene import Scene
    from chaospound.simulate import Simulation

__all__ = [
    "CliError",
    "EXIT_FAILURE",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_USAGE",
    "add_scene_options",
    "build_parser",
    "main",
    "note_sweep_overrides",
    "scene_from_args",
    "target_from_args",
    "write_json_file",
]

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

#: run and solver options applied as scene overrides (option dest = flat parameter name)
RUN_OVERRIDES = ("transient", "record", "method", "rtol", "atol", "phase")
#: columns of the readable impact table
IMPACT_COLUMNS = ("#", "cycle", "phase", "velocity", "corner", "peak pen", "peak force", "duration")
#: the units row under the impact table's header (chaospound.units.UNITS)
IMPACT_UNITS = ("", "", "of T", "A_g omega_Ax", "", "A_g", "A_g k_Ax", "1/omega_Ax")
#: units of the wall-clock times in the JSON documents (``wall_s``)
WALL_UNITS = {"wall_s": "seconds (wall clock)"}


#: a status line appears once the work has taken this long (s)
STATUS_DELAY_S = 2.0
#: seconds between redraws of the status line
STATUS_INTERVAL_S = 1.0
#: what a first run's compilation of the kernels takes (s): 20-38 s measured on a fresh
#: clone, 54 s on two busy cores
COMPILE_ESTIMATE_S = "10-15"
_COMMAND_START = time.perf_counter()  #: reset by main(): the whole command's start


class CliError(ValueError):
    """Bad command-line input (exit code 2); the message is one line."""


# ================================================================== main
def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit code: 0 success, 1 numerical failure, 2 bad input, 130
        interrupted. Only ``python -m chaospound`` and the console script turn
        it into ``SystemExit``.
    """
    global _COMMAND_START
    _COMMAND_START = time.perf_counter()
    try:
        try:
            args = build_parser().parse_args(argv)
            return args.func(args)
        except _ParserExit as done:  # --help, --version
            return done.status
        except ValueError as exc:  # SceneError, CliError, usage errors
            return _fail(str(exc), EXIT_USAGE)
        except RuntimeError as exc:
            if not _is_simulation_error(exc):
                raise
            return _fail(str(exc), EXIT_FAILURE)
    except KeyboardInterrupt:
        return _fail("interrupted", EXIT_INTERRUPTED)
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_BROKEN_PIPE


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand.

    Returns
    -------
    argparse.ArgumentParser
        Usage errors raise :class:`CliError`; ``--help`` and ``--version``
        raise a private exception that :func:`main` turns into exit code 0.
    """
    from chaospound import __version__

    parser = _Parser(
        prog=PROG,
        description="Chaotic seismic pounding between two towers: scenes, runs, analyses.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add in (_add_presets, _add_params, _add_simulate, _add_section, _add_impact_map,
                _add_lyapunov, _add_classify, _add_sweep, _add_plot, _add_bench, _add_orbit,
                _add_continue):
        add(commands)
    return parser


# ========================================================= scene options
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
        help="scene file (see 'chaospound presets'); simulate, classify, lyapunov and sweep "
        "also take FILE.py:ATTR, a System defined in a Python file (docs/custom_systems.md)"
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
                       "a system FILE.py:ATTR runs with simulate, classify, lyapunov and sweep")
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
    return scene.with_assignments(assignments) if assignments else scene


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


def _system_header(system) -> list[tuple[str, str]]:
    """The report header of a user's System: name, model, parameters, period, solver."""
    values = ", ".join(f"{k} = {v:g}" for k, v in system.parameter_values.items())
    where = f" ({system.origin})" if system.origin else ""
    return [
        ("system", f"{system.name}{where}"),
        ("model", f"custom ({system.dim} states: {' '.join(system.state_names)})"
                  + ("" if system.has_gap else ", no gap function")),
        ("parameters", values or "-"),
        ("period", f"T = {system.period:.6g}"),
        ("solver", _solver_text(system)),
    ]  # fmt: skip


def _system_document(system) -> dict:
    from chaospound.sweep import system_identity

    return system_identity(system)


#: the defaults named when a scene file sets no parameter
FILE_DEFAULTS_SHOWN = ("period_ratio", "freq_ratio", "mass_ratio", "gap", "beta", "chi",
                       "length_A", "width_ratio_A", "zeta_x_A", "method", "rtol", "transient",
                       "record")


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


def note_sweep_overrides(args: argparse.Namespace, scene: Scene | None = None) -> str | None:
    """Say on stderr when a swept parameter is also given by --set (or a run option).

    ``chaospound sweep --set gap=2 --param gap=1,2`` sweeps gap over 1, 2: the sweep
    overrides the --set. Call after the scene is built; the swept names are those of
    ``args.params`` (``--param NAME=GRID``), else of the scene's [sweep] table.

    Returns
    -------
    str or None
        The note written (one line), or None when nothing is overridden.
    """
    from chaospound.scene import SHORTHANDS

    params = list(getattr(args, "params", None) or [])
    swept = [text.split("=", 1)[0].strip() for text in params]
    if not swept and scene is not None:
        swept = [name for name, _ in scene.sweep]
    swept = [name for name in swept if name]
    given = [(f"--set {text}", text.split("=", 1)[0].strip())
             for text in getattr(args, "assignments", None) or [] if "=" in text]
    given += [(f"--{name} {getattr(args, name)}", name) for name in RUN_OVERRIDES
              if getattr(args, name, None) is not None]
    overridden = []
    for option, name in given:
        covered = {name, *SHORTHANDS.get(name, ())}
        hits = [s for s in swept if covered & {s, *SHORTHANDS.get(s, ())}]
        if hits:
            overridden.append(f"{option} (swept: {', '.join(hits)})")
    if not overridden:
        return None
    message = (f"the sweep overrides {'; '.join(overridden)}: each point takes the "
               "swept value")
    _note(message)
    return message


def write_json_file(document: object, path: str, *, overwrite: bool = False) -> None:
    """Write JSON atomically: a temporary file in the same folder, then a rename.

    Parameters
    ----------
    document : object
        JSON-serialisable; non-finite floats become ``null``.
    path : str
        Target file.
    overwrite : bool
        Replace an existing file (else :class:`CliError`).
    """
    text = _json_text(document)
    check_output_path(path, overwrite=overwrite)
    folder = os.path.dirname(os.path.abspath(path))
    try:
        handle = tempfile.NamedTemporaryFile(
            "w", encoding="utf-8", dir=folder, prefix=".chaospound-", suffix=".tmp", delete=False
        )
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None
    try:
        with handle:
            handle.write(text)
        check_output_path(path, overwrite=overwrite)
        os.replace(handle.name, path)
    except BaseException as exc:
        os.unlink(handle.name)
        if isinstance(exc, OSError):
            raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None
        raise


def check_output_path(path: str, *, overwrite: bool) -> None:
    """Raise :class:`CliError` unless ``path`` can be written (before any work)."""
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise CliError(f"output {_path(path)} is a directory")
    if os.path.exists(path) and not overwrite:
        raise CliError(f"output {_path(path)} exists (use --overwrite to replace it)")
    if not os.path.isdir(folder):
        raise CliError(f"output {_path(path)}: folder {_path(folder)} does not exist")


def check_figure_path(path: str) -> None:
    """Raise :class:`CliError` unless a figure can be drawn to ``path`` (before any work).

    A figure is a derived product: an existing figure is redrawn (no --overwrite
    needed). Refused: a directory, a missing folder, and an extension that is not a
    figure format (so a data file such as .h5 or .json is never replaced by a figure).
    """
    from matplotlib.figure import Figure

    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise CliError(f"output {_path(path)} is a directory")
    if not os.path.isdir(folder):
        raise CliError(f"output {_path(path)}: folder {_path(folder)} does not exist")
    extension = os.path.splitext(path)[1].lstrip(".").lower()
    formats = Figure().canvas.get_supported_filetypes()
    if extension and extension not in formats:
        raise CliError(f"output {_path(path)}: .{shorten(extension)} is not a figure format "
                       f"(use {', '.join('.' + f for f in FIGURE_FORMATS)})")


#: figure formats named in help texts and messages (matplotlib writes more)
FIGURE_FORMATS = ("png", "pdf", "svg")


# ============================================================== presets
def _add_presets(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "presets",
        help="list the bundled scenes, or print one as TOML",
        description="List the bundled scenes; with NAME print its TOML "
        "(e.g. 'chaospound presets fig3a > my.toml', then edit and run my.toml).",
    )
    parser.add_argument("name", nargs="?", metavar="NAME", help="print this preset's TOML")
    parser.set_defaults(func=_cmd_presets)


def _cmd_presets(args: argparse.Namespace) -> int:
    from importlib import resources

    from chaospound.scene import list_presets, load_preset

    if args.name is None:
        rows = [(name, load_preset(name).description) for name in list_presets()]
        _emit(_table(("preset", "description"), rows, "ll"))
        return EXIT_OK
    name = args.name.removesuffix(".toml")
    load_preset(name)  # checks the name and the file
    _emit(resources.files("chaospound").joinpath("presets", name + ".toml").read_text("utf-8"))
    return EXIT_OK


# =============================================================== params
def _add_params(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "params",
        help="list the scene parameters (for --set and scene files)",
        description="Flat parameter names, their meaning and allowed range.",
    )
    parser.add_argument("names", nargs="*", metavar="NAME", help="only these parameters")
    parser.set_defaults(func=_cmd_params)


def _cmd_params(args: argparse.Namespace) -> int:
    from chaospound.scene import parameter_help

    described = parameter_help()
    for name in args.names:
        if name not in described:
            raise CliError(f"unknown parameter {shorten(name, quote=True)} "
                           "(see 'chaospound params')")
    names = args.names or list(described)
    defaults = parameter_defaults()
    rows = [(n, defaults[n], described[n]) for n in names]
    _emit(_table(("parameter", "default", "meaning; range"), rows, "lll"))
    return EXIT_OK


#: parameters whose default is derived from others: what it follows
_DERIVED_DEFAULTS = {
    "mass_ratio": "auto: freq_ratio**2",
    "gyration": "auto: sqrt((l^2+w^2)/12)",
    "width": "width_ratio l",
    "atol": "1e-3 rtol",
}


def parameter_defaults() -> dict[str, str]:
    """Default of every flat parameter and shorthand, as shown by ``chaospound params``.

    Values of the default scene (:class:`~chaospound.scene.Scene` ``()``); a default
    that follows other parameters says what it follows and its default value, e.g.
    ``"auto: freq_ratio**2 = 2.25"``. A shorthand shows the default of the names it sets.
    """
    from chaospound.scene import PARAMETERS, SHORTHANDS, Scene

    values = Scene().to_dict()
    out = {}
    for name in PARAMETERS:
        value = values[name]
        if isinstance(value, bool):
            shown = str(value).lower()
        elif isinstance(value, float):
            shown = f"{value:g}"
        else:
            shown = str(value)
        rule = _DERIVED_DEFAULTS.get(name.removesuffix("_A").removesuffix("_B"))
        out[name] = f"{rule} = {shown}" if rule else shown
    out["model"] = "auto"  # to_dict gives the reduction used; the setting is auto
    for short, names in SHORTHANDS.items():
        out[short] = out[names[0]]
    return out


# ============================================================= simulate
def _add_simulate(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "simulate",
        help="run a scene to steady state: impacts and stroboscopic section",
        description="Run a scene (transient, then record cycles) and report its impacts.",
    )
    add_scene_options(parser)
    out = parser.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print one JSON document only")
    out.add_argument(
        "--trajectory",
        type=_count0,
        default=0,
        metavar="N",
        help="dense samples per cycle over the record window (JSON 'trajectory')",
    )
    out.add_argument("--output", metavar="FILE.json", help="also write the JSON to this file")
    out.add_argument("--overwrite", action="store_true", help="replace an existing --output")
    out.add_argument("--plot", metavar="FILE.png",
                     help="write the run's figure: time histories of the record window "
                     "(displacements, rotations, clearance with the impacts, contact force) "
                     "beside the phase diagrams (.png, .pdf or .svg; an existing figure is "
                     "redrawn)")
    out.add_argument("--quiet", action="store_true",
                     help="no status line on stderr (compiling, running; shown on a terminal "
                     f"when the work takes more than {STATUS_DELAY_S:g} s)")
    parser.set_defaults(func=_cmd_simulate)


def _cmd_simulate(args: argparse.Namespace) -> int:
    scene = target_from_args(args)
    if args.output is not None:
        check_output_path(args.output, overwrite=args.overwrite)
    if args.plot is not None:
        check_figure_path(args.plot)
        if args.output is not None and os.path.abspath(args.plot) == os.path.abspath(args.output):
            raise CliError(f"--plot {_path(args.plot)} is the --output file")
    _load_kernels(args.quiet, warm=_system_warm(scene), engine=_engine_of(scene))
    transient, record = ((scene.transient, scene.record) if _is_system(scene)
                         else (scene.run.transient, scene.run.record))
    cycles = f"{transient} transient + {record} recorded cycles"
    with _Status(f"running {scene.name}: {cycles}", quiet=args.quiet) as status:
        sim = _run_simulation(scene, args.trajectory)
        if args.plot is not None:
            status.set(f"drawing {scene.name}'s time histories and phase diagrams")
            _simulation_save_plot(sim, args.trajectory, args.plot,
                                  scene if _is_system(scene) else None)
    document = _simulation_document(sim)
    if _is_system(scene):
        document["system"] = _system_document(scene)
    if args.output is not None:
        write_json_file(document, args.output, overwrite=args.overwrite)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_simulation_report(sim, args.trajectory, args.output, args.plot,
                                 scene if _is_system(scene) else None))
    return EXIT_OK


def _simulation_save_plot(sim: Simulation, samples_per_cycle: int, path: str,
                          system=None) -> None:
    """Time histories and phase diagrams of the run (rerun with dense samples unless the
    run has at least :data:`PHASE_PLOT_SAMPLES` per cycle: the same steps, interpolated);
    the phase diagrams alone for a user's ``system``."""
    from chaospound.plot import plot_phase_diagrams, plot_run

    if samples_per_cycle < PHASE_PLOT_SAMPLES:
        sim = _run_simulation(sim.scene if sim.scene is not None else system,
                              PHASE_PLOT_SAMPLES)
    if sim.scene is None:  # a user's system: no contact model to draw, its phase diagrams
        _save_figure(plot_phase_diagrams(sim), path)
        return
    from chaospound.simulate import contact_history

    _save_figure(plot_run(sim, contact_history(sim)), path)


def _save_figure(fig, path: str) -> None:
    """Write a figure atomically (redrawn if it exists); file errors become CliError."""
    from chaospound.plot import save

    check_figure_path(path)
    try:
        save(fig, path)
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None


def _run_simulation(scene: Scene, samples_per_cycle: int) -> Simulation:
    """Run the scene (simulate loads the jitted kernels before its timer starts)."""
    from chaospound.simulate import simulate

    return simulate(scene, samples_per_cycle=samples_per_cycle)


def _simulation_document(sim: Simulation) -> dict:
    document = _with_units(sim.to_json_dict())
    if sim.trajectory is not None:
        document["trajectory"] = {
            "time": sim.trajectory.time.tolist(),
            "state": sim.trajectory.state.tolist(),
        }
    return document


def _scene_title(scene) -> str:
    return f"{scene.name}: {scene.description}" if scene.description else scene.name


def _solver_text(solver) -> str:
    """Method and accuracy setting, as shown in every report header."""
    if solver.method == "rk4":
        return f"rk4, {solver.steps_per_cycle} steps per cycle"
    return f"{solver.method}, rtol {solver.rtol:g}, atol {solver.atol:g}"


def _scene_rows(scene, model: str, period: float) -> list[tuple[str, str]]:
    """The rows every report of a scene starts with: scene, model, period ratio."""
    return [("scene", _scene_title(scene)), ("model", model),
            ("period ratio", f"T/T_Ax = {scene.excitation.period_ratio:g} (T = {period:.6g})")]


def _simulation_report(sim: Simulation, samples_per_cycle: int, output: str | None,
                       plot: str | None = None, system=None) -> str:
    """Header, impact table and summary of one run (of a scene, or of ``system``), as text."""
    scene, imp = sim.scene, sim.impacts
    if system is not None:
        header = [*_system_header(system),
                  ("cycles", f"{sim.transient} transient + {sim.record} recorded")]
    else:
        header = [
            *_scene_rows(scene, f"{sim.model} ({len(sim.state_names)} states: "
                                f"{' '.join(sim.state_names)})", sim.period),
            ("cycles", f"{sim.transient} transient + {sim.record} recorded, "
                       f"section phase {scene.run.phase:g}"),
            ("solver", _solver_text(scene.solver)),
        ]  # fmt: skip
    blocks = [_table(None, header, "ll")]
    if len(imp):
        rows = [
            (
                str(i + 1),
                str(int(imp.cycle[i])),
                f"{imp.phase[i]:.5f}",
                f"{imp.velocity[i]:.6g}",
                label,
                f"{imp.peak_penetration[i]:.4g}",
                f"{imp.peak_force[i]:.4g}",
                f"{imp.duration[i]:.4g}",
            )
            for i, label in enumerate(imp.labels)
        ]
        units = IMPACT_UNITS if system is None else ("", "", "of T", "", "", "", "", "")
        blocks.append(_table(IMPACT_COLUMNS, [units, *rows], "rrrrlrrr"))
    else:
        blocks.append("no impacts in the record window")
    summary = _summary(sim, samples_per_cycle, output)
    if plot is not None:
        drawn = "phase diagrams" if system is not None else "time histories and phase diagrams"
        summary.append(("wrote", f"{plot} ({drawn})"))
    blocks.append(_table(None, summary, "ll"))
    return "\n\n".join(blocks) + "\n"


def _summary(sim: Simulation, samples_per_cycle: int, output: str | None) -> list[tuple[str, str]]:
    imp, stats = sim.impacts, sim.stats
    last_cycle = sim.transient + sim.record - 1
    last = [label for label, k in zip(imp.labels, imp.cycle, strict=True) if k == last_cycle]
    per_step = 1e6 * stats.wall_s / stats.steps if stats.steps else math.nan
    rows = [
        ("impacts per cycle", f"{len(imp) / sim.record:.4g} ({len(imp)} in {sim.record} cycles)"),
        (
            "velocity",
            f"min {imp.velocity.min():.6g}, max {imp.velocity.max():.6g} (A_g omega_Ax)"
            if len(imp) else "-",
        ),
        (f"corners, cycle {last_cycle}", " ".join(last) if last else "none"),
        (
            "steps",
            f"{stats.steps} accepted, {stats.rejected} rejected, "
            f"{stats.rhs_evals} rhs evaluations, {stats.events} events",
        ),
        ("wall time", f"{stats.wall_s:.4g} s in the kernels ({per_step:.3g} us per accepted "
                      f"step); {_command_seconds():.3g} s the whole command (start-up, kernels "
                      "loaded or compiled, reports)"),
    ]
    if samples_per_cycle:
        rows.append(("trajectory", f"{samples_per_cycle} samples per cycle (JSON 'trajectory')"))
    if output is not None:
        rows.append(("wrote", output))
    return rows


# ============================================================== section
#: relative distance (to the section's size) within which two section points are one
SECTION_TOL = 1e-6
#: most section points listed by the text report (all are in the JSON)
SECTION_ROWS = 12


def _add_section(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "section",
        help="stroboscopic Poincare section: the state once per excitation period",
        description="The states at t = (phase + k) T for k = transient .. transient + cycles "
        "(T the excitation period): a response of period P cycles gives P distinct points, "
        "a quasi-periodic one a closed curve, a chaotic one a cloud. The report counts the "
        "distinct points. --transient sets the cycles discarded first (the scene's, 40 "
        "for the presets).",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("section")
    group.add_argument("--cycles", type=_count, default=200, metavar="N",
                       help="cycles recorded (200): N + 1 points")
    group.add_argument("--tol", type=_positive_float, default=SECTION_TOL, metavar="TOL",
                       help="two points closer than TOL times the section's size count as "
                       f"one distinct point ({SECTION_TOL:g})")
    add_output_options(parser, plot_help="draw the points in the panels of the phase "
                       "diagrams (.png, .pdf or .svg; an existing figure is redrawn)")
    parser.set_defaults(func=_cmd_section)


def _scene_for_run(args: argparse.Namespace) -> Scene:
    """The scene of a run command, its --plot path checked, the kernels loaded."""
    scene = scene_from_args(args)
    if args.plot is not None:
        check_figure_path(args.plot)
    _load_kernels(args.quiet, engine=_engine_of(scene))
    return scene


def _cmd_section(args: argparse.Namespace) -> int:
    from chaospound.dynamics.poincare import stroboscopic_section

    scene = _scene_for_run(args)
    with _Status(f"section of {scene.name}: {scene.run.transient} transient + {args.cycles} "
                 "cycles", quiet=args.quiet):
        section = stroboscopic_section(scene, phase=scene.run.phase, cycles=args.cycles)
    distinct, counts, size = distinct_points(section.states, args.tol)
    if args.plot is not None:
        from chaospound.plot import plot_strobe

        fig = plot_strobe(section)
        fig.suptitle(f"{scene.name}, $T/T_{{Ax}}$ = {scene.excitation.period_ratio:g}, "
                     f"{section.model} model: section at phase {section.phase:g}, cycles "
                     f"{int(section.cycles[0])}-{int(section.cycles[-1])}, {len(section)} "
                     f"points, {len(distinct)} distinct")
        _save_figure(fig, args.plot)
    document = _with_units(section.to_json_dict())
    document["transient_cycles"] = int(section.cycles[0])
    document["distinct_points"] = len(distinct)
    document["distinct_tol"] = args.tol
    document["scene"] = scene.to_dict()
    if args.json:
        _emit(_json_text(document))
        return EXIT_OK
    header = [
        *_scene_rows(scene, f"{section.model} ({len(section.state_names)} states: "
                            f"{' '.join(section.state_names)})", section.period),
        ("section", f"t = ({section.phase:g} + k) T, k = {int(section.cycles[0])} .. "
                    f"{int(section.cycles[-1])}: {len(section)} points"),
        ("solver", _solver_text(scene.solver)),
        ("distinct points", f"{len(distinct)} (within {args.tol:g} of the section's size "
                            f"{size:.4g})"),
    ]  # fmt: skip
    names = section.state_names
    rows = [(str(i + 1), str(n), *(f"{v:.6g}" for v in section.states[j]))
            for i, (j, n) in enumerate(zip(distinct[:SECTION_ROWS], counts, strict=False))]
    blocks = [_table(None, header, "ll"),
              _table(("#", "points", *names), [("", "", *(_state_unit(n) for n in names)),
                                               *rows], "rr" + "r" * len(names))]
    if len(distinct) > SECTION_ROWS:
        blocks.append(f"(first {SECTION_ROWS} of {len(distinct)} distinct points; all "
                      "points in --json)")
    return _emit_report(blocks, [], args.plot)


def _emit_report(blocks: list[str], tail: list[tuple[str, str]], plot: str | None) -> int:
    """Print a command's text report: its blocks, then a last table with ``tail``, the
    whole command's wall time and the figure written."""
    tail = [*tail, ("wall time", f"{_command_seconds():.3g} s the whole command")]
    if plot is not None:
        tail.append(("wrote", plot))
    _emit("\n\n".join([*blocks, _table(None, tail, "ll")]) + "\n")
    return EXIT_OK


def distinct_points(states, tol: float) -> tuple[list[int], list[int], float]:
    """The distinct points of a section, in order of first appearance.

    Two points are one when their distance is at most ``tol`` times the section's
    size (the largest absolute state component over the points, at least 1e-300).

    Returns
    -------
    (indices, counts, size)
        The index of each distinct point's first occurrence, how many points
        fall on it, and the size used.
    """
    import numpy as np

    states = np.asarray(states, dtype=float)
    size = float(max(np.max(np.abs(states), initial=0.0), 1e-300))
    firsts: list[int] = []
    counts: list[int] = []
    for i, point in enumerate(states):
        for k, j in enumerate(firsts):
            if float(np.max(np.abs(point - states[j]))) <= tol * size:
                counts[k] += 1
                break
        else:
            firsts.append(i)
            counts.append(1)
    return firsts, counts, size


def _state_unit(name: str) -> str:
    """The unit row of a state column (lengths in A_g, rotations in rad, ...)."""
    rate = name.startswith("d")
    if name.lstrip("d").startswith("th"):
        return "rad omega_Ax" if rate else "rad"
    return "A_g omega_Ax" if rate else "A_g"


# =========================================================== impact-map
def _add_impact_map(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "impact-map",
        help="impact map n -> n+1: phase and velocity of consecutive impacts",
        description="Run a scene (transient, then record cycles) and list its impacts as "
        "the map n -> n+1 of consecutive impacts: (phase_n, V_n) -> (phase_n+1, V_n+1), "
        "with the corners. A response with n impacts per period repeats every n impacts "
        "(n fixed points of the n-th iterate); a chaotic one spreads over a curve or a "
        "cloud. --record sets the cycles recorded.",
    )
    add_scene_options(parser)
    add_output_options(parser, plot_help="draw the impact sequence and the return maps of "
                       "phase and velocity (.png, .pdf or .svg; an existing figure is redrawn)")
    parser.set_defaults(func=_cmd_impact_map)


def _cmd_impact_map(args: argparse.Namespace) -> int:
    from chaospound.dynamics.impact_map import impact_map

    scene = _scene_for_run(args)
    cycles = f"{scene.run.transient} transient + {scene.run.record} recorded cycles"
    with _Status(f"running {scene.name}: {cycles}", quiet=args.quiet):
        sim = _run_simulation(scene, 0)
    imap = impact_map(sim)
    if args.plot is not None:
        from chaospound.plot import plot_impact_map

        fig = plot_impact_map(imap)
        fig.suptitle(f"{scene.name}, $T/T_{{Ax}}$ = {scene.excitation.period_ratio:g}: "
                     f"{fig.get_suptitle()}, cycles {sim.transient}-"
                     f"{sim.transient + sim.record - 1}")
        _save_figure(fig, args.plot)
    document = _with_units(imap.to_json_dict())
    document["transient_cycles"] = sim.transient
    document["record_cycles"] = sim.record
    document["scene"] = scene.to_dict()
    if args.json:
        _emit(_json_text(document))
        return EXIT_OK
    header = [
        *_scene_rows(scene, sim.model, sim.period),
        ("cycles", f"{sim.transient} transient + {sim.record} recorded"),
        ("solver", _solver_text(scene.solver)),
    ]  # fmt: skip
    blocks = [_table(None, header, "ll")]
    labels = imap.labels
    if len(imap) >= 2:
        rows = [(str(i + 1), str(int(imap.cycle[i])), labels[i], f"{imap.phase[i]:.5f}",
                 f"{imap.velocity[i]:.6g}", labels[i + 1], f"{imap.phase[i + 1]:.5f}",
                 f"{imap.velocity[i + 1]:.6g}") for i in range(len(imap) - 1)]
        columns = ("n", "cycle", "corner n", "phase n", "V n", "corner n+1", "phase n+1",
                   "V n+1")
        units = ("", "", "", "of T", "A_g omega_Ax", "", "of T", "A_g omega_Ax")
        blocks.append(_table(columns, [units, *rows], "rrlrrlrr"))
    else:
        blocks.append(f"{len(imap)} impact{'' if len(imap) == 1 else 's'} in the record "
                      "window: no pair n -> n+1")
    tail = [("impacts", f"{len(imap)} ({len(imap) / sim.record:.4g} per cycle), "
                        f"{max(len(imap) - 1, 0)} pairs")]
    return _emit_report(blocks, tail, args.plot)


# ================================================================ bench
def _add_bench(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "bench",
        help="speed against scipy's solve_ivp on this machine",
        description="Time one steady run (default: preset fig3a) against "
        "scipy.integrate.solve_ivp(RK45) with a pure-Python and a numba right-hand side, "
        "same span and tolerances, in one run; also 'chaospound simulate' end to end.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("benchmark")
    group.add_argument(
        "--repeats", type=_count0, default=5, metavar="N",
        help="timing rounds (5): chaospound 6x around one run of each solve_ivp variant;"
        " the best of each counts",
    )
    group.add_argument(
        "--no-cli", action="store_true", help="skip timing 'chaospound simulate' in a subprocess"
    )
    group.add_argument("--json", action="store_true", help="print one JSON document only")
    parser.set_defaults(func=_cmd_bench)


def _cmd_bench(args: argparse.Namespace) -> int:
    from chaospound.bench import format_benchmark, run_benchmark

    if args.repeats < 1:
        raise CliError(f"--repeats {args.repeats}: must be an integer >= 1")
    if args.preset is None and args.scene_file is None:
        args.preset = "fig3a"
    scene = scene_from_args(args)
    result = run_benchmark(scene, repeats=args.repeats, cli=not args.no_cli)
    _emit(_json_text(_with_units(result)) if args.json else format_benchmark(result))
    return EXIT_OK


# ============================================================= lyapunov
LYAPUNOV_BLOCKS = 10  #: blocks of the error bars (standard error of block means)
LYAPUNOV_SEPARATION = 1e-7  #: initial separation of the two-trajectory method
LYAPUNOV_TWO_RTOL = 1e-10  #: the two trajectories' integration error must stay << separation
LYAPUNOV_TWO_ATOL = 1e-12


def _add_lyapunov(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "lyapunov",
        help="Lyapunov exponents of a scene's steady response, with error bars",
        description="Lyapunov exponents from the variational equations (QR every excitation "
        "period), with standard errors of block means, the trace identity and the Kaplan-Yorke "
        "dimension; optionally the largest exponent from two nearby trajectories.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("lyapunov")
    group.add_argument(
        "--k", type=_count0, default=None, metavar="K", help="number of exponents (default: all)"
    )
    group.add_argument(
        "--cycles", type=_count0, default=400, metavar="N", help="excitation cycles averaged (400)"
    )
    group.add_argument(
        "--tangent-transient",
        type=_count0,
        default=20,
        metavar="N",
        help="cycles discarded while the tangent vectors align (20)",
    )
    group.add_argument(
        "--two-trajectory",
        action="store_true",
        help="also the largest exponent from two nearby trajectories "
        f"(separation {LYAPUNOV_SEPARATION:g}, rtol tightened to <= {LYAPUNOV_TWO_RTOL:g})",
    )
    add_output_options(parser, plot_help="write the convergence figure (.png, .pdf or .svg; "
                       "an existing figure is redrawn)")
    parser.set_defaults(func=_cmd_lyapunov)


def _cmd_lyapunov(args: argparse.Namespace) -> int:
    from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
    from chaospound.dynamics.system import System

    scene = target_from_args(args)
    system = scene if _is_system(scene) else System.from_scene(scene)
    if args.k is not None and not 1 <= args.k <= system.dim:
        raise CliError(
            f"--k {args.k}: must be between 1 and {system.dim} "
            f"(the {system.model_name} model's state dimension)"
        )
    if args.cycles < LYAPUNOV_BLOCKS:
        raise CliError(
            f"--cycles {args.cycles}: must be >= {LYAPUNOV_BLOCKS} "
            f"(the error bars use {LYAPUNOV_BLOCKS} blocks)"
        )
    if args.plot is not None:
        check_figure_path(args.plot)
    # warm the jitted kernels up, so that the reported wall time is the work's
    _load_kernels(args.quiet, lambda: lyapunov_spectrum(
        system, k=args.k, transient=0, tangent_transient=0, cycles=2, n_blocks=2),
        engine=system.engine("qr"))
    start = time.perf_counter()
    with _Status(f"Lyapunov exponents: {system.transient} transient + {args.tangent_transient} "
                 f"tangent transient + {args.cycles} averaged cycles", quiet=args.quiet):
        spectrum = lyapunov_spectrum(
            system,
            k=args.k,
            tangent_transient=args.tangent_transient,
            cycles=args.cycles,
            n_blocks=LYAPUNOV_BLOCKS,
        )
    wall = time.perf_counter() - start
    two, two_system, two_wall = None, None, 0.0
    if args.two_trajectory:
        two_system = system
        if system.method != "rk4":
            two_system = system.with_solver(
                rtol=min(system.rtol, LYAPUNOV_TWO_RTOL), atol=min(system.atol, LYAPUNOV_TWO_ATOL)
            )
        start = time.perf_counter()
        with _Status(f"two trajectories: {args.cycles} cycles", quiet=args.quiet):
            two = largest_exponent_two_trajectory(
                two_system,
                cycles=args.cycles,
                separation=LYAPUNOV_SEPARATION,
                n_blocks=LYAPUNOV_BLOCKS,
            )
        two_wall = time.perf_counter() - start
    if args.plot is not None:
        title = (f"{system.name}, T = {system.period:.4g}, custom model" if system is scene
                 else f"{scene.name}, $T/T_{{Ax}}$ = {scene.excitation.period_ratio:g}, "
                 f"{system.model_name} model")
        _lyapunov_save_plot(spectrum, two, args.plot, title)
    document = _lyapunov_document(scene, system, spectrum, wall, two, two_system, two_wall)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_lyapunov_report(scene, system, spectrum, document, args.plot))
    return EXIT_OK


def _lyapunov_save_plot(spectrum, two, path: str, scene: str) -> None:
    """Write the convergence figure atomically; file errors become CliError."""
    from chaospound.plot import plot_lyapunov_convergence, save

    fig = plot_lyapunov_convergence(spectrum, two, scene=scene)
    check_figure_path(path)
    try:
        save(fig, path)
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None


def _lyapunov_document(scene, system, spectrum, wall, two, two_system, two_wall) -> dict:
    total = float(spectrum.exponents.sum())
    document = {
        "model": system.model_name,
        "state_dim": system.dim,
        "k": int(spectrum.exponents.size),
        "full_spectrum": bool(spectrum.exponents.size == system.dim),
        "period": spectrum.period,
        "transient_cycles": spectrum.transient,
        "tangent_transient_cycles": spectrum.tangent_transient,
        "cycles": spectrum.cycles,
        "blocks": int(spectrum.block_means.shape[0]),
        "exponents": spectrum.exponents.tolist(),
        "errors": spectrum.errors.tolist(),
        "max_exponent": spectrum.max_exponent,
        "max_error": spectrum.max_error,
        "per_cycle": spectrum.per_cycle.tolist(),
        "errors_per_cycle": spectrum.errors_per_cycle.tolist(),
        "sum": total,
        "trace": spectrum.trace,
        "kaplan_yorke": spectrum.kaplan_yorke,
        "work": {"steps": spectrum.steps, "rhs_evals": spectrum.rhs_evals, "wall_s": wall},
    }
    if system is scene:
        document["system"] = _system_document(system)
    else:
        document["scene"] = scene.to_dict()
    _with_units(document)
    if two is not None:
        document["two_trajectory"] = {
            "exponent": two.exponent,
            "error": two.error,
            "per_cycle": two.per_cycle,
            "error_per_cycle": two.error * two.period,
            "separation": two.separation,
            "cycles": two.cycles,
            "rtol": two_system.rtol,
            "atol": two_system.atol,
            "wall_s": two_wall,
        }
    return document


def _lyapunov_report(scene, system, spectrum, document: dict, plot: str | None) -> str:
    """Header, exponent table and summary of one Lyapunov run, as text."""
    cycles = (f"{spectrum.transient} transient + {spectrum.tangent_transient} tangent "
              f"transient + {spectrum.cycles} averaged ({document['blocks']} blocks)")
    if system is scene:
        header = [*_system_header(system), ("cycles", cycles)]
    else:
        header = [
            *_scene_rows(scene, f"{system.model_name} ({system.dim} states: "
                                f"{' '.join(system.state_names)})", spectrum.period),
            ("cycles", cycles),
            ("solver", _solver_text(scene.solver)),
        ]  # fmt: skip
    rows = [
        (
            str(i + 1),
            f"{lam:+.6f}",
            f"{err:.2g}",
            f"{lam_c:+.6f}",
            f"{err_c:.2g}",
        )
        for i, (lam, err, lam_c, err_c) in enumerate(
            zip(spectrum.exponents, spectrum.errors, spectrum.per_cycle,
                spectrum.errors_per_cycle, strict=True)
        )
    ]  # fmt: skip
    columns = ("#", "lambda (per unit t)", "+-", "lambda T (per cycle)", "+-")
    total, trace = document["sum"], document["trace"]
    if trace is None or (isinstance(trace, float) and math.isnan(trace)):
        identity = f"{total:.6g} (no trace identity: the Jacobian's trace is not known)"
    elif document["full_spectrum"]:
        identity = f"{total:.6g} (trace identity {trace:.6g}, difference {total - trace:.2g})"
    else:
        identity = (
            f"{total:.6g} (of {document['k']} exponents; the trace identity "
            f"{trace:.6g} holds for all {system.dim})"
        )
    summary = [
        ("sum", identity),
        ("Kaplan-Yorke dimension", f"{document['kaplan_yorke']:.4g}"
         + ("" if document["full_spectrum"] else f" (from {document['k']} exponents)")),
    ]  # fmt: skip
    two = document.get("two_trajectory")
    if two is not None:
        summary.append((
            "two trajectories",
            f"lambda_1 = {two['exponent']:+.6f} +- {two['error']:.2g} per unit t, "
            f"{two['per_cycle']:+.6f} +- {two['error_per_cycle']:.2g} per cycle "
            f"(separation {two['separation']:g}, rtol {two['rtol']:g}, {two['wall_s']:.3g} s)",
        ))  # fmt: skip
    work = document["work"]
    summary.append(("work", f"{work['steps']} steps, {work['rhs_evals']} rhs evaluations, "
                            f"{work['wall_s']:.3g} s; {_command_seconds():.3g} s the whole "
                            "command"))  # fmt: skip
    if plot is not None:
        summary.append(("wrote", plot))
    blocks = [
        _table(None, header, "ll"),
        _table(columns, rows, "rrrrr"),
        _table(None, summary, "ll"),
    ]
    return "\n\n".join(blocks) + "\n"


# ============================================================= classify
#: dense samples per cycle of the phase diagrams: a contact lasts about 0.2 of the
#: normalised time (5 % of a period), so 200 drew each impact's turn as 10 straight
#: segments; 2000 draws it smoothly
PHASE_PLOT_SAMPLES = 2000

def _add_classify(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "classify",
        help="classify a scene's steady response: none, periodic n-P, group-periodic n-P, "
        "quasi-periodic, chaotic",
        description="Classify the steady response (docs/classification.md): adaptive transient "
        "(from --transient cycles, the minimum, to --max-transient), period and impacts per "
        "period from the stroboscopic section and the impacts, else the largest Lyapunov "
        "exponent and the 0-1 test. Runs with rtol <= 1e-8.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("classification")
    group.add_argument(
        "--max-transient",
        type=_count0,
        default=2000,
        metavar="N",
        help="longest transient in cycles (2000); --transient is the shortest (40)",
    )
    group.add_argument(
        "--max-period", type=_count0, default=16, metavar="P", help="longest period searched (16)"
    )
    group.add_argument(
        "--window",
        type=_count0,
        default=None,
        metavar="N",
        help="record window in cycles (default max(4 max-period, 32))",
    )
    group.add_argument(
        "--lyapunov-cycles",
        type=_count0,
        default=200,
        metavar="N",
        help="cycles averaged for the largest exponent when there is no period (200)",
    )
    group.add_argument("--no-01", action="store_true", help="skip the 0-1 test for chaos")
    add_output_options(parser, plot_help="write phase diagrams of the steady state (.png, "
                       ".pdf or .svg; an existing figure is redrawn)", quiet_help="progress")
    parser.set_defaults(func=_cmd_classify)


def _cmd_classify(args: argparse.Namespace) -> int:
    from chaospound.dynamics.classify import classify

    if args.record is not None:
        raise CliError(f"--record {args.record}: not used by classify (use --window N)")
    scene = target_from_args(args)
    system = scene if _is_system(scene) else None
    shortest = system.transient if system is not None else scene.run.transient
    if shortest < 1:
        raise CliError(f"--transient {shortest}: the shortest transient must be >= 1 cycle")
    if args.max_transient < shortest:
        raise CliError(
            f"--max-transient {args.max_transient}: must be >= the shortest transient "
            f"{shortest} (--transient)"
        )
    if args.max_period < 1:
        raise CliError(f"--max-period {args.max_period}: must be an integer >= 1")
    if args.plot is not None:
        check_figure_path(args.plot)
    _load_kernels(args.quiet, warm=_system_warm(scene), engine=_engine_of(scene))
    with _Status(f"classifying {scene.name}", quiet=args.quiet) as status:
        regime = classify(
            scene,
            min_transient=shortest,
            max_transient=args.max_transient,
            window=args.window,
            max_period=args.max_period,
            lyapunov_cycles=args.lyapunov_cycles,
            test01=not args.no_01,
            progress=lambda text: status.set(f"classifying {scene.name}: {text}"),
        )
        if args.plot is not None:
            status.set(f"classified {regime.label}: drawing the phase diagrams")
            _classify_save_plot(scene, regime, args.plot)
    document = regime.to_json_dict()
    document["model"] = regime.evidence.get("model")
    if system is not None:
        document["system"] = _system_document(system)
    else:
        document["scene"] = scene.to_dict()
    _with_units(document)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_classify_report(scene, regime, args.plot))
    return EXIT_OK


def _classify_save_plot(scene: Scene, regime, path: str) -> None:
    """Phase diagrams of the classified steady state (rerun at the classification's tolerances)."""
    from chaospound.plot import plot_phase_diagrams, save
    from chaospound.simulate import simulate

    rtol, atol = regime.evidence.get("rtol"), regime.evidence.get("atol")
    method = scene.method if _is_system(scene) else scene.solver.method
    if method != "rk4" and rtol is not None and math.isfinite(atol):
        scene = (scene.with_solver(rtol=rtol, atol=atol) if _is_system(scene)
                 else scene.with_params(rtol=rtol, atol=atol))
    record = max(2 * regime.period_cycles, 4) if regime.period_cycles else 8
    run = simulate(scene, transient=regime.transient_used, record=record,
                   samples_per_cycle=PHASE_PLOT_SAMPLES)
    fig = plot_phase_diagrams(run)
    fig.suptitle(f"{fig.get_suptitle()}: {regime.label}")
    check_figure_path(path)
    try:
        save(fig, path)
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None


def _classify_report(scene: Scene, regime, plot: str | None) -> str:
    """The classification as an aligned text report."""
    evidence = regime.evidence
    cycles = regime.period_cycles
    period = "-" if cycles is None else f"{cycles} cycle{'' if cycles == 1 else 's'}"
    impacts = "-" if regime.impacts_per_period is None else str(regime.impacts_per_period)
    if regime.max_exponent is None:
        exponent = "- (not needed: a period was found)" if regime.period_cycles else "-"
    else:
        period_t = scene.period
        exponent = (
            f"{regime.max_exponent:+.5f} +- {regime.max_exponent_error:.2g} per unit t, "
            f"{regime.max_exponent * period_t:+.5f} +- {regime.max_exponent_error * period_t:.2g}"
            " per cycle"
        )
    zero_one = "-" if regime.zero_one is None else f"{regime.zero_one:.3f}"
    solver = scene if _is_system(scene) else scene.solver
    accuracy = (
        f"{solver.steps_per_cycle} steps per cycle"
        if solver.method == "rk4"
        else f"rtol {evidence.get('rtol'):g}, atol {evidence.get('atol'):g}"
    )
    if _is_system(scene):
        head = [row for row in _system_header(scene) if row[0] != "solver"]
    else:
        head = _scene_rows(scene, str(evidence.get("model")), scene.period)
    rows = [
        *head,
        ("regime", regime.label),
        ("period", period),
        ("impacts per period", impacts),
        ("corner sequence", " ".join(regime.corner_sequence) or "-"),
        ("strobe mismatch", f"{regime.strobe_mismatch:.3g} (tol {evidence.get('tol'):g}, "
                            f"at P = {evidence.get('best_period')})"),
        ("largest exponent", exponent),
        ("0-1 test K", zero_one),
        ("confidence", f"{regime.confidence:.2f}"),
        ("transient used", f"{regime.transient_used} cycles, then a {evidence.get('window_cycles')}"
                           "-cycle window"),
        ("solver", f"{solver.method}, {accuracy}"),
        ("wall time", f"{_command_seconds():.3g} s the whole command"),
    ]  # fmt: skip
    if plot is not None:
        rows.append(("wrote", plot))
    return _table(None, rows, "ll") + "\n"


# ================================================================ sweep
SWEEP_CONTINUATIONS = ("none", "forward", "backward", "both")  #: as chaospound.sweep.CONTINUATIONS
SWEEP_CLASSIFY = ("window", "full")  #: as chaospound.sweep.CLASSIFY_MODES


def _add_sweep(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "sweep",
        help="bifurcation scan over one or two parameters, streamed to an HDF5 file",
        description="Run every point of a grid over one or two scene parameters to steady "
        "state and store its impacts, stroboscopic points and regime (optionally Lyapunov "
        "exponents) in an HDF5 file, written as the points finish; an interrupted file is "
        "finished with --resume. Without --param the scene's [sweep] table is used "
        "(presets fig4, fig4-translational, fig5). Read the file with "
        "chaospound.open_sweep, draw it with 'chaospound plot'.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("sweep")
    group.add_argument(
        "--param",
        dest="params",
        action="append",
        default=[],
        metavar="NAME=GRID",
        help="swept parameter, once or twice (the last one is the continuation direction); "
        "GRID is start:stop:step, start:stop#count or v1,v2,... "
        "(e.g. period_ratio=0.3:2.0:0.005)",
    )
    group.add_argument(
        "--continuation",
        choices=SWEEP_CONTINUATIONS,
        default="none",
        help="none: every point from the scene's initial state; forward/backward: each point "
        "from the previous point's last section (up/down the last axis); both: the two "
        "branches side by side (hysteresis)",
    )
    group.add_argument(
        "--lyapunov",
        nargs="?",
        const=1,
        default=0,
        type=_exponent_count,
        metavar="K",
        help="also the K largest Lyapunov exponents per point (K omitted: 1, 'all': the "
        "full spectrum); put it after the scene file",
    )
    group.add_argument(
        "--lyapunov-cycles",
        type=_count,
        default=100,
        metavar="N",
        help="excitation cycles averaged for the exponents (100)",
    )
    group.add_argument(
        "--classify",
        choices=SWEEP_CLASSIFY,
        default="window",
        help="window: the regime from each point's own record window (fast); full: the "
        "adaptive classifier per point (converged transient, slower)",
    )
    group.add_argument(
        "--window-tol",
        type=float,
        default=1e-2,
        metavar="TOL",
        help="relative stroboscopic mismatch accepted as periodic by --classify window (0.01)",
    )
    out = parser.add_argument_group("output and execution")
    out.add_argument("-o", "--output", required=True, metavar="FILE.h5", help="the sweep file")
    out.add_argument("--resume", action="store_true",
                     help="finish an interrupted file of the same sweep (a missing file "
                     "is started)")
    out.add_argument("--overwrite", action="store_true", help="replace an existing file")
    out.add_argument("--workers", type=_count, default=1, metavar="N",
                     help="worker processes (1); results do not depend on it")
    out.add_argument("--chunk", type=_count, default=None, metavar="N",
                     help="points per task (default: sized from the grid and the workers)")
    out.add_argument("--quiet", action="store_true", help="no progress bar")
    out.add_argument("--scheduler", metavar="ADDRESS",
                     help="run the tasks on Dask: tcp://HOST:PORT of a running scheduler, or "
                     "'local' to start a cluster of --workers processes on this machine "
                     "(needs chaospound[dask]; docs/distributed.md)")
    parser.set_defaults(func=_cmd_sweep)


def _cmd_sweep(args: argparse.Namespace) -> int:
    from chaospound.store import StoreWriteError
    from chaospound.sweep import SweepInterrupted, SweepSpec, axes_from_scene, parse_axes, run_sweep

    if args.resume and args.overwrite:
        raise CliError("give --resume or --overwrite, not both")
    if args.chunk is not None and args.chunk < 1:
        raise CliError(f"--chunk {args.chunk}: must be an integer >= 1")
    scene = target_from_args(args)
    if args.params:
        axes = parse_axes(args.params, scene)
    elif _is_system(scene):
        raise CliError(f"nothing to sweep: give --param NAME=GRID (system "
                       f"{shorten(scene.name, quote=True)} has: "
                       f"{', '.join(scene.parameter_names) or 'no named parameters'})")
    elif scene.sweep:
        try:
            axes = axes_from_scene(scene)
        except ValueError as exc:  # name where the grid came from
            source = f"preset {args.preset}" if args.preset else _path(args.scene_file)
            raise CliError(f"{source}: [sweep] {exc}") from None
    else:
        raise CliError(
            "nothing to sweep: give --param NAME=GRID (scene "
            f"{shorten(scene.name, quote=True)} has no [sweep] table)"
        )
    spec = SweepSpec(
        tuple(axes),
        continuation=args.continuation,
        lyapunov=args.lyapunov,
        lyapunov_cycles=args.lyapunov_cycles,
        classify=args.classify,
        window_tol=args.window_tol,
    )
    _check_sweep_output(args.output, resume=args.resume, overwrite=args.overwrite)
    note_sweep_overrides(args, None if _is_system(scene) else scene)  # after every check
    from chaospound.distributed import ClusterUnavailable, connect, disconnect

    client = cluster = None
    if args.scheduler is not None:  # a malformed address is a ValueError: exit 2
        try:
            client, cluster = connect(args.scheduler, args.workers)
        except ClusterUnavailable as exc:
            return _fail(str(exc), EXIT_FAILURE)
    try:
        summary = run_sweep(
            scene,
            spec,
            args.output,
            workers=args.workers,
            resume=args.resume,
            overwrite=args.overwrite,
            progress=not args.quiet,
            chunk=args.chunk,
            client=client,
        )
    except SweepInterrupted as exc:
        return _fail(str(exc), EXIT_INTERRUPTED)
    except ClusterUnavailable as exc:
        return _fail(f"{exc}; the points written so far are kept: finish with "
                     f"chaospound sweep ... -o {args.output} --resume", EXIT_FAILURE)
    except StoreWriteError as exc:  # full disk, I/O error: committed points are kept
        return _fail(str(exc), EXIT_FAILURE)
    except OSError as exc:
        raise CliError(f"cannot write {_path(args.output)}: {exc.strerror or exc}") from None
    finally:
        if client is not None:
            disconnect(client, cluster)
    _emit(summary.format())
    return EXIT_OK


def _exponent_count(text: str) -> int:
    """argparse type of --lyapunov: an integer >= 1, or 'all' (-1: the full spectrum)."""
    if text.strip().lower() == "all":
        return -1
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(
            f"{shorten(text, quote=True)}: must be an integer >= 1 or 'all'")
    return value


def _check_sweep_output(path: str, *, resume: bool, overwrite: bool) -> None:
    """Refuse a sweep file before any work: a directory, a missing folder, an existing
    file without --resume or --overwrite (run_sweep checks a file to resume, read-only)."""
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise CliError(f"output {_path(path)} is a directory")
    if not os.path.isdir(folder):
        raise CliError(f"output {_path(path)}: folder {_path(folder)} does not exist")
    from chaospound.lock import holder

    running = holder(path)
    if running is not None:
        raise CliError(f"output {_path(path)}: a running sweep ({running}) is writing it; wait for "
                       "it to finish or stop it first")
    if resume or overwrite:
        return
    if os.path.exists(path + ".journal"):
        raise CliError(f"output {_path(path)}: an interrupted sweep's journal exists (use --resume "
                       "to finish it or --overwrite to replace it)")
    if os.path.exists(path):
        raise CliError(f"output {_path(path)} exists (use --resume to finish it or --overwrite "
                       "to replace it)")


# ================================================================= plot
def _add_plot(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "plot",
        help="bifurcation diagram or regime map of a sweep file",
        description="Draw a sweep file: for one swept parameter the bifurcation diagram "
        "(impact velocity against the parameter, coloured by regime; a second panel with "
        "the largest Lyapunov exponent and its error bars when the sweep has exponents; with "
        "--orbit STATE the orbit diagram of that state at the stroboscopic section beside "
        "it), for two a regime map (beside it the largest exponent as a colour map, blue "
        "negative, red positive, grey without an exponent, when the sweep has exponents); "
        "forward and backward continuation overlaid on one axis (hysteresis), other "
        "branches side by side. A file still being written shows its finished points. "
        "The format follows the output's extension: .png (raster, see --dpi), .pdf or .svg "
        "(vector, for papers); an existing figure is redrawn.",
    )
    parser.add_argument("sweep_file", metavar="SWEEP.h5",
                        help="a file of 'chaospound sweep', or a branch file of 'chaospound "
                        "continue' (then the branches' bifurcation diagram beside their "
                        "Floquet multipliers)")
    parser.add_argument("-o", "--output", metavar="FILE",
                        help="the figure: FILE.png, FILE.pdf or FILE.svg (default: the sweep "
                        "file with .png)")
    parser.add_argument("--branch", metavar="NAME",
                        help="only this branch (forward or backward of a continuation; "
                        "default: all)")
    parser.add_argument("--dpi", type=_positive_float, default=150.0, metavar="DPI",
                        help="resolution of raster output such as .png, dots per inch (150)")
    parser.add_argument("--size", type=_float_pair, metavar="W,H",
                        help="figure size in inches, e.g. 7,4.5 (default: from the panels)")
    parser.add_argument("--xlim", type=_float_pair, metavar="MIN,MAX",
                        help="x range: the (first) swept parameter (--xlim=-1,2 for a "
                        "negative start)")
    parser.add_argument("--ylim", type=_float_pair, metavar="MIN,MAX",
                        help="y range: the impact velocity, or the second parameter of a "
                        "regime map")
    parser.add_argument("--orbit", metavar="STATE",
                        help="also the orbit diagram of this state component (e.g. X_A; any "
                        "state of the sweep's model) at the stroboscopic section against the "
                        "swept parameter, beside the impact velocities (one-parameter sweeps)")
    parser.add_argument("--over", metavar="SWEEP.h5",
                        help="with a branch file of 'chaospound continue': draw the branches "
                        "over this sweep's impact velocities (a brute-force scan of the same "
                        "parameter)")
    parser.add_argument("--overwrite", action="store_true", help=argparse.SUPPRESS)  # not needed
    parser.set_defaults(func=_cmd_plot)


def _cmd_plot(args: argparse.Namespace) -> int:
    from chaospound.plot import save
    from chaospound.store import open_sweep

    if os.path.isfile(args.sweep_file) and _is_branch_file(args.sweep_file):
        return _plot_branch_file(args)
    if args.over is not None:
        raise CliError(f"--over: {_path(args.sweep_file)} is not a branch file of "
                       "'chaospound continue'")
    sweep = open_sweep(args.sweep_file)
    if args.branch is not None and args.branch not in sweep.branches:
        raise CliError(f"--branch {args.branch}: the file has {', '.join(sweep.branches)}")
    output = args.output or os.path.splitext(args.sweep_file)[0] + ".png"
    if os.path.abspath(output) == os.path.abspath(args.sweep_file):
        raise CliError(f"output {_path(output)} is the sweep file itself")
    check_figure_path(output)
    for option in ("xlim", "ylim"):
        pair = getattr(args, option)
        if pair is not None and not pair[0] < pair[1]:
            raise CliError(f"--{option} {pair[0]:g},{pair[1]:g}: need MIN < MAX")
    if args.size is not None and min(args.size) <= 0:
        raise CliError(f"--size {args.size[0]:g},{args.size[1]:g}: need W > 0 and H > 0")
    if args.orbit is not None:
        if args.orbit not in sweep.state_names:
            raise CliError(f"--orbit {args.orbit}: not a state of the {sweep.meta['model']} "
                           f"model; choose one of {', '.join(sweep.state_names)}")
        if len(sweep.parameters) != 1:
            raise CliError(f"--orbit: needs a sweep over one parameter, this one is over "
                           f"{' x '.join(sweep.parameters)}")
    branches = [args.branch] if args.branch is not None else list(sweep.branches)
    fig = _sweep_figure(sweep, branches, args.orbit)
    if args.size is not None:
        fig.set_size_inches(*args.size)
    for text in [fig.get_suptitle() and fig._suptitle, *(ax.title for ax in fig.axes)]:
        if text:
            text.set_wrap(True)  # a long title breaks into lines instead of running off
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            continue
        if args.xlim is not None:
            ax.set_xlim(*args.xlim)
        if args.ylim is not None and ax.get_label() == _MAIN_PANEL:
            ax.set_ylim(*args.ylim)
    check_figure_path(output)
    try:
        save(fig, output, dpi=args.dpi)
    except OSError as exc:
        raise CliError(f"cannot write {_path(output)}: {exc.strerror or exc}") from None
    kind = "bifurcation diagram" if len(sweep.parameters) == 1 else "regime map"
    if args.orbit is not None:
        kind += f" and orbit diagram of {args.orbit}"
    elif len(sweep.parameters) == 2 and _has_exponents(sweep, branches):
        kind += " and exponent map"
    _emit(f"wrote {output}: {kind} of {' x '.join(sweep.parameters)}, "
          f"branch {', '.join(branches)}")
    return EXIT_OK


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


#: label of the panels that --ylim applies to (impact velocity, regime map)
_MAIN_PANEL = "main"
#: label of the exponent panels (1 parameter: lambda against it; 2: the exponent map)
_EXPONENT_PANEL = "exponents"
#: label of the orbit-diagram panels (plot --orbit)
_ORBIT_PANEL = "orbit"


#: map colour of each stored regime code (chaospound.store.REGIMES); the regimes
#: shared with the bifurcation diagram take chaospound.plot.REGIME_COLORS
_MAP_EXTRA_COLORS = {"pending": "white", "unresolved": "C4", "failed": "black"}


def _sweep_figure(sweep, branches: Sequence[str], orbit: str | None = None):
    """The figure of ``chaospound plot``.

    One parameter: :func:`chaospound.plot.plot_bifurcation` per branch, one column each
    (two rows when the sweep has Lyapunov exponents, with error bars, in every
    classification mode), except forward and backward together, which
    :func:`chaospound.plot.plot_hysteresis` overlays on one axis; with ``orbit`` (a
    state name) the orbit diagram of that component at the stroboscopic section
    beside it (:func:`chaospound.plot.plot_orbit_diagram`). Two parameters: a regime
    map per branch, each with the largest exponent's colour map beside it when the
    sweep has exponents (:func:`chaospound.plot.plot_exponent_map`). Axes are
    labelled with symbols and units (:func:`chaospound.plot.parameter_label`).
    """
    from matplotlib.figure import Figure

    from chaospound.plot import parameter_label

    name = _scene_name(sweep)
    labels = [parameter_label(p) for p in sweep.parameters]
    with_exponents = _has_exponents(sweep, branches)
    if len(sweep.parameters) == 2:
        return _map_figure(sweep, branches, with_exponents, name, labels)
    title = f"{name}: impact velocity against {labels[0]} ({sweep.meta['model']} model)"
    if orbit is None:
        fig = _spectrum_figure(None, sweep, branches, with_exponents, labels)
        fig.suptitle(title)
        return fig
    hysteresis = sorted(branches) == ["backward", "forward"]
    cols = 1 if hysteresis else len(branches)
    fig = Figure(figsize=(2 * (9.0 if hysteresis else 8.0 * cols), 7.0 if with_exponents
                          else 5.0), layout="constrained")
    left, right = fig.subfigures(1, 2, wspace=0.02)
    _spectrum_figure(left, sweep, branches, with_exponents, labels)
    _orbit_panels(right, sweep, branches, orbit, labels[0], hysteresis)
    left.suptitle("impact velocity spectrum")
    right.suptitle(f"orbit diagram: {orbit} at the stroboscopic section")
    fig.suptitle(f"{name}: impact velocity and {orbit} against {labels[0]} "
                 f"({sweep.meta['model']} model)")
    return fig


def _has_exponents(sweep, branches: Sequence[str]) -> bool:
    """The sweep computed Lyapunov exponents (--lyapunov), or a classification stored some."""
    import numpy as np

    if int(sweep.sweep.get("lyapunov", 0)) != 0:
        return True
    return any(np.isfinite(sweep.array("max_exponent", b)).any() for b in branches)


def _map_figure(sweep, branches, with_exponents: bool, name: str, labels: list[str]):
    """Two parameters: a regime map per branch, the exponent map beside each."""
    import numpy as np
    from matplotlib.figure import Figure

    from chaospound.plot import plot_exponent_map

    done = {b: sum(s != "pending" for s in sweep.status(b)) for b in branches}
    total = int(math.prod(sweep.shape))
    per_branch = 2 if with_exponents else 1
    cols = per_branch * len(branches)
    fig = Figure(figsize=(6.0 * cols + 1.5, 5.0), layout="constrained")
    axes = fig.subplots(1, cols, squeeze=False, sharex=True, sharey=True)[0]
    first, second = sweep.parameters
    for j, branch in enumerate(branches):
        ax = axes[per_branch * j]
        ax.set_label(_MAIN_PANEL)
        _regime_map(ax, sweep, branch)
        ax.set_title(_branch_title(branch, done[branch], total))
        if with_exponents:
            lam_ax = axes[per_branch * j + 1]
            lam_ax.set_label(_EXPONENT_PANEL)
            status = np.asarray(sweep.status(branch), dtype=object).reshape(sweep.shape)
            plot_exponent_map(
                sweep.grid[first], sweep.grid[second],
                np.asarray(sweep.array("max_exponent", branch), dtype=float)
                .reshape(sweep.shape),
                ax=lam_ax, missing=(status == "failed") | (status == "pending"),
                x_label=labels[0], y_label=labels[1])
            lam_ax.tick_params(labelleft=True)
    what = "regimes and largest Lyapunov exponent" if with_exponents else "regimes"
    fig.suptitle(f"{name}: {what} over {labels[0]} and {labels[1]} "
                 f"({sweep.meta['model']} model)")
    return fig


def _spectrum_figure(fig, sweep, branches, with_exponents: bool, labels: list[str]):
    """One parameter: the impact-velocity diagram of each branch (into ``fig`` or a new one)."""
    from matplotlib.figure import Figure

    from chaospound import plot
    done = {b: sum(s != "pending" for s in sweep.status(b)) for b in branches}
    total = int(math.prod(sweep.shape))
    values = sweep.grid[sweep.parameters[0]]
    rows = 2 if with_exponents else 1
    ratios = (3, 1) if with_exponents else None
    if sorted(branches) == ["backward", "forward"]:  # hysteresis: one axis, both ways
        if fig is None:
            fig = Figure(figsize=(9.0, 7.0 if with_exponents else 5.0), layout="constrained")
        axes = list(fig.subplots(rows, 1, sharex=True, squeeze=False,
                                 height_ratios=ratios)[:, 0])
        axes[0].set_label(_MAIN_PANEL)
        order = ["forward", "backward"]
        plot.plot_hysteresis(
            values,
            {b: sweep.impact_velocities(b) for b in order},
            exponents={b: sweep.array("max_exponent", b) for b in order}
            if with_exponents else None,
            exponent_errors={b: sweep.array("max_exponent_error", b) for b in order}
            if with_exponents else None,
            ax=axes,
            parameter_label=labels[0],
        )
        axes[0].set_title(", ".join(f"{b} {done[b]}/{total}" for b in order) + " points")
        return fig
    cols = len(branches)
    if fig is None:
        fig = Figure(figsize=(8.0 * cols, 7.0 if with_exponents else 5.0), layout="constrained")
    grid = fig.subplots(rows, cols, squeeze=False, sharex=True, sharey="row",
                        height_ratios=ratios)
    for j, branch in enumerate(branches):
        grid[0, j].set_label(_MAIN_PANEL)
        plot.plot_bifurcation(
            values,
            sweep.impact_velocities(branch),
            regimes=sweep.regimes(branch),
            exponents=sweep.array("max_exponent", branch) if with_exponents else None,
            exponent_errors=sweep.array("max_exponent_error", branch)
            if with_exponents else None,
            ax=list(grid[:, j]),
            parameter_label=labels[0],
        )
        if with_exponents:
            grid[1, j].set_label(_EXPONENT_PANEL)
        grid[0, j].set_title(_branch_title(branch, done[branch], total))
    return fig


def _orbit_panels(fig, sweep, branches, state: str, label: str, hysteresis: bool) -> None:
    """The orbit diagram of one state component at the stroboscopic section: one axis
    per branch, or forward and backward overlaid (hysteresis)."""
    from chaospound.plot import BRANCH_STYLES, axis_label, plot_orbit_diagram

    k = sweep.state_names.index(state)
    values = sweep.grid[sweep.parameters[0]]
    n = len(values)

    def component(branch):
        return [sweep.strobe(i, branch)[:, k] for i in range(n)]

    if hysteresis:
        ax = fig.add_subplot()
        ax.set_label(_ORBIT_PANEL)
        for branch in ("forward", "backward"):
            style = BRANCH_STYLES[branch]
            plot_orbit_diagram(values, component(branch), ax=ax, parameter_label=label,
                               state_label=axis_label(state), color=style["color"],
                               marker=style["marker"], label=f"{branch} {style['arrow']}")
        ax.legend(fontsize="small", frameon=False)
        return
    axes = fig.subplots(1, len(branches), squeeze=False, sharey=True)[0]
    for ax, branch in zip(axes, branches, strict=True):
        ax.set_label(_ORBIT_PANEL)
        plot_orbit_diagram(values, component(branch), ax=ax, regimes=sweep.regimes(branch),
                           parameter_label=label, state_label=axis_label(state))
        if branch != "fresh":
            ax.set_title(f"{branch} continuation")


def _branch_title(branch: str, done: int, total: int) -> str:
    """Panel title: points done, with the continuation direction ("fresh" is internal:
    each point from the scene's initial state, so no name)."""
    points = f"{done} of {total} points"
    if branch == "fresh":
        return points
    return f"{branch} continuation: {points}"


def _regime_map(ax, sweep, branch: str) -> None:
    """Regime codes over two parameters (first on x, second on y), with a legend."""
    import numpy as np
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    from chaospound.plot import REGIME_COLORS, cell_edges, parameter_label
    from chaospound.store import REGIMES

    colors = [REGIME_COLORS.get(r) or _MAP_EXTRA_COLORS.get(r, "0.3") for r in REGIMES]
    codes = np.asarray(sweep.array("regime", branch)).reshape(sweep.shape)
    first, second = sweep.parameters
    ax.pcolormesh(cell_edges(sweep.grid[first]), cell_edges(sweep.grid[second]), codes.T,
                  cmap=ListedColormap(colors), vmin=-0.5, vmax=len(REGIMES) - 0.5,
                  edgecolors="face")
    present = [(code, int(np.count_nonzero(codes == code))) for code in range(len(REGIMES))]
    handles = [Patch(facecolor=colors[code], edgecolor="0.5", label=f"{REGIMES[code]} ({n})")
               for code, n in present if n]
    ax.legend(handles=handles, fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0),
              frameon=False)
    ax.set_xlabel(parameter_label(first))
    ax.set_ylabel(parameter_label(second))


def _scene_name(sweep) -> str:
    """The scene's name, from the resolved scene stored in the file (a system's name)."""
    if "system" in sweep.meta and "name" in sweep.meta:
        return str(sweep.meta["name"])
    try:
        return str(json.loads(sweep.meta["scene_resolved"])["name"])
    except (KeyError, TypeError, ValueError):
        return os.path.basename(str(sweep.path))


# =============================================================== status
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


def _load_kernels(quiet: bool, warm=None, engine=None) -> None:
    """Load the engine of the work before the work, outside its timing: from numba's
    disk cache (well under a second), or by compiling it (the first run of a
    composition after installing or editing, about :data:`COMPILE_ESTIMATE_S` s),
    which is announced at once on a terminal. ``engine`` is the engine the work runs
    (default: the default scene's); ``warm`` the call that loads it (default: one
    tiny cycle of ``engine``)."""
    from chaospound.simulate import kernels_cached, warm_up

    if engine is None:
        from chaospound.engine.compose import engine_for
        from chaospound.simulate import DEFAULT_COMPOSITION

        engine = engine_for(DEFAULT_COMPOSITION)
    if warm is None:
        def warm() -> None:
            warm_up(engine)
    cached = kernels_cached(engine.composition)
    if cached is False:
        text, delay = f"compiling kernels, first run only, about {COMPILE_ESTIMATE_S} s", 0.0
    else:
        text, delay = "loading the compiled kernels", None
    with _Status(text, quiet=quiet, delay=delay):
        warm()


def _engine_of(scene):
    """The engine a scene's (or a System's) runs use (its composition's)."""
    from chaospound.dynamics.system import System

    return (scene if isinstance(scene, System) else System.from_scene(scene)).engine()


def _system_warm(target):
    """The call that loads a user System's engine (one period), or None for a scene."""
    if not _is_system(target):
        return None

    def warm() -> None:
        from chaospound.dynamics.system import advance

        advance(target, target.initial_state, 1, from_time_zero=True)
    return warm


def _orbit_warm(smap):
    """The call that loads the two engines of orbit work: the map and its monodromy."""
    def warm() -> None:
        from chaospound.dynamics.system import advance, monodromy

        advance(smap.system, smap.system.initial_state, 1)
        monodromy(smap.system, smap.system.initial_state, 1)
    return warm


def _command_seconds() -> float:
    """Seconds since the command started (:func:`main`): parsing, loading or compiling
    the kernels, the work and the reports."""
    return time.perf_counter() - _COMMAND_START


# ======================================================= orbit, continue
ORBIT_RTOL_TEXT = "1e-12"  #: orbit work's default tolerance, as shown in help texts


def _is_branch_file(path: str) -> bool:
    from chaospound.orbits.store import is_branch_file

    return is_branch_file(path)


def _orbit_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("orbit")
    group.add_argument("--period", type=_count, default=1, metavar="K",
                       help="period of the orbit in forcing cycles (1)")
    group.add_argument("--tol", type=_positive_float, default=1e-10, metavar="TOL",
                       help="Newton's residual |P^K(x) - x| relative to max(1, |x|) (1e-10)")


def _orbit_map(args: argparse.Namespace, scene: Scene, parameter: str | None = None):
    """The scene's stroboscopic map: rtol 1e-12, atol 1e-14, dop853 unless --rtol,
    --atol or --method say otherwise."""
    from chaospound.orbits.maps import ORBIT_ATOL, ORBIT_METHOD, ORBIT_RTOL, StroboscopicMap

    rtol = scene.solver.rtol if args.rtol is not None else ORBIT_RTOL
    atol = scene.solver.atol if (args.rtol is not None or args.atol is not None) else ORBIT_ATOL
    method = scene.solver.method if args.method is not None else ORBIT_METHOD
    return StroboscopicMap.of(scene, parameter=parameter, rtol=rtol, atol=atol, method=method)


def _add_orbit(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "orbit",
        help="a periodic orbit by Newton shooting: Floquet multipliers, impacts, stability",
        description="Find a period-K orbit of the scene (the fixed point of the K-fold "
        "stroboscopic map) by Newton's method from the state after the transient, with the "
        "monodromy matrix by finite differences; report its section state, Floquet "
        "multipliers and exponents, stability and impacts per period. Integrations use "
        f"dop853 at rtol {ORBIT_RTOL_TEXT}, atol 1e-14 unless --method/--rtol/--atol are "
        "given (docs/orbits.md).",
    )
    add_scene_options(parser)
    _orbit_options(parser)
    out = parser.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print one JSON document only")
    out.add_argument("--quiet", action="store_true", help="no status line on stderr")
    parser.set_defaults(func=_cmd_orbit)


def _cmd_orbit(args: argparse.Namespace) -> int:
    from chaospound.orbits.shooting import find_orbit

    scene = scene_from_args(args)
    smap = _orbit_map(args, scene)
    _load_kernels(args.quiet, _orbit_warm(smap), smap.system.engine("propagator"))
    start = time.perf_counter()
    with _Status(f"period-{args.period} orbit of {scene.name}: {smap.system.transient} "
                 "transient cycles, then Newton", quiet=args.quiet):
        orbit = find_orbit(smap, period=args.period, tol=args.tol)
    wall = time.perf_counter() - start
    document = {"scene": scene.to_dict(), "model": smap.system.model_name,
                "solver": {"method": smap.system.method, "rtol": smap.system.rtol,
                           "atol": smap.system.atol},
                "transient_cycles": smap.system.transient, **orbit.to_json_dict(),
                "wall_s": wall}
    if args.json:
        _emit(_json_text(_with_units(document)))
        return EXIT_OK
    lines = [f"{scene.name}: period-{orbit.period} orbit, {smap.system.model_name} model, "
             f"T/T_Ax = {scene.excitation.period_ratio:g}",
             f"  {orbit.label}: {orbit.impacts_per_period} impacts per period"
             + (f", corners {' '.join(orbit.corners)}" if orbit.corners else ""),
             f"  {'stable' if orbit.stable else 'unstable'}: largest |mu| = "
             f"{abs(orbit.multipliers[0]):.10g}",
             f"  Newton: {orbit.iterations} iterations, relative residual {orbit.residual:.2e} "
             f"({smap.system.method}, rtol {smap.system.rtol:g}, {smap.system.transient} "
             "transient cycles)", ""]
    rows = [(name, f"{value:.12g}") for name, value in zip(orbit.state_names, orbit.state,
                                                           strict=True)]
    lines += ["section state (t = t0 + j T):", _table(None, rows, "lr"), ""]
    rows = [(f"{z.real:.10g}", f"{z.imag:.10g}", f"{abs(z):.10g}", f"{e:.8g}")
            for z, e in zip(orbit.multipliers, orbit.exponents, strict=True)]
    lines += ["Floquet multipliers and exponents (log|mu| / (K T), per unit t):",
              _table(("Re mu", "Im mu", "|mu|", "exponent"), rows, "rrrr"), ""]
    if orbit.impacts_per_period:
        rows = [(str(i + 1), str(int(c)), f"{ph:.6f}", f"{v:.10g}", corner)
                for i, (c, ph, v, corner) in enumerate(zip(
                    orbit.impact_cycle, orbit.impact_phase, orbit.impact_velocity,
                    orbit.corners, strict=True))]
        lines += ["impacts in one period:",
                  _table(("#", "cycle", "phase", "velocity", "corner"), rows, "rrrrl"), ""]
    lines.append(f"time: {wall:.2f} s work, {_command_seconds():.2f} s command")
    _emit("\n".join(lines))
    return EXIT_OK


def _add_continue(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "continue",
        help="continue a periodic orbit in a parameter: folds, period doublings, grazing",
        description="Find a period-K orbit at START and follow it by pseudo-arclength "
        "continuation within [START, STOP], both ways, passing folds; detect and locate "
        "folds, period doublings, Neimark-Sacker points and grazings (a change of the "
        "impacts per period) to 1e-9 in the parameter; with --switch also follow the "
        "period-2K branch born at each period doubling. Writes the branches to an HDF5 "
        "file (docs/orbits.md); 'chaospound plot' draws it.",
    )
    add_scene_options(parser)
    _orbit_options(parser)
    group = parser.add_argument_group("continuation")
    group.add_argument("--param", required=True, metavar="NAME=START:STOP",
                       help="the parameter and its interval, e.g. period_ratio=0.45:1.0")
    group.add_argument("--max-steps", type=_count, default=400, metavar="N",
                       help="points per direction (400)")
    group.add_argument("--ds-max", type=_positive_float, default=None, metavar="DS",
                       help="largest pseudo-arclength step (default from the interval)")
    group.add_argument("--switch", action="store_true",
                       help="also continue the period-2K branch of every period doubling")
    out = parser.add_argument_group("output")
    out.add_argument("-o", "--output", required=True, metavar="BRANCH.h5",
                     help="the branch file (HDF5)")
    out.add_argument("--overwrite", action="store_true", help="replace an existing output")
    out.add_argument("--json", action="store_true", help="print one JSON summary only")
    out.add_argument("--quiet", action="store_true", help="no status line on stderr")
    parser.set_defaults(func=_cmd_continue)


def _parse_interval(text: str, scene: Scene) -> tuple[str, float, float]:
    name, sep, rest = text.partition("=")
    start, colon, stop = rest.partition(":")
    name = name.strip()
    if not sep or not colon or not name:
        raise CliError(f"--param {shorten(text, quote=True)}: expected NAME=START:STOP")
    try:
        a, b = float(start), float(stop)
    except ValueError:
        raise CliError(f"--param {shorten(text, quote=True)}: START and STOP must be "
                       "numbers") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a == b:
        raise CliError(f"--param {shorten(text, quote=True)}: need finite START != STOP")
    values = scene.to_dict()
    if name not in values:
        from chaospound.scene import SceneError

        raise SceneError(f"--param: unknown parameter {shorten(name, quote=True)} (see "
                         "'chaospound params')")
    if isinstance(values[name], bool) or not isinstance(values[name], int | float):
        raise CliError(f"--param {shorten(name)}: not a numerical parameter")
    scene.with_params(**{name: a}), scene.with_params(**{name: b})  # both ends valid
    return name, a, b


def _cmd_continue(args: argparse.Namespace) -> int:
    from chaospound.orbits.continuation import continue_branch, switch_period_doubling
    from chaospound.orbits.store import write_branches

    scene = scene_from_args(args)
    name, a, b = _parse_interval(args.param, scene)
    check_output_path(args.output, overwrite=args.overwrite)
    scene = scene.with_params(**{name: a})
    smap = _orbit_map(args, scene, parameter=name)
    _load_kernels(args.quiet, _orbit_warm(smap), smap.system.engine("propagator"))
    start = time.perf_counter()
    options = {"max_steps": args.max_steps, "tol": args.tol}
    if args.ds_max is not None:
        options["ds_max"] = args.ds_max
    with _Status(f"continuing the period-{args.period} orbit in {name} over [{a:g}, {b:g}]",
                 quiet=args.quiet) as status:
        options["progress"] = status.set
        branch = continue_branch(smap, name, a, b, period=args.period, **options)
        branches = [branch]
        if args.switch:
            lo, hi = min(a, b), max(a, b)
            for sp in branch.of_kind("period-doubling"):
                try:
                    branches.append(switch_period_doubling(smap, sp, lo, hi, **options))
                except RuntimeError as exc:
                    if not _is_simulation_error(exc):
                        raise
                    _note(f"no period-{2 * args.period} branch off the period doubling at "
                          f"{name} = {sp.value:.10g}: {exc}")
    wall = time.perf_counter() - start
    try:
        write_branches(args.output, branches, scene_toml=scene.to_toml(),
                       model=smap.system.model_name, system=scene.name,
                       state_names=tuple(smap.system.state_names))
    except OSError as exc:  # a full disk: the work is lost, nothing half-written is left
        return _fail(f"cannot write {_path(args.output)}: {exc.strerror or exc}", EXIT_FAILURE)
    summary = {"output": args.output, "parameter": name, "interval": [a, b], "wall_s": wall,
               "branches": [{"name": br.name, "period_cycles": br.period, "points": len(br),
                             "stable_points": int(br.stable.sum()),
                             "stop_reasons": br.stop_reasons,
                             "special": [{"kind": sp.kind, "value": sp.value,
                                          "bracket": sp.bracket, "note": sp.note,
                                          "multipliers_abs": [abs(z) for z in
                                                              sp.orbit.multipliers]}
                                         for sp in br.special]}
                            for br in branches]}
    if args.json:
        _emit(_json_text(summary))
        return EXIT_OK
    lines = [f"{scene.name}: {smap.system.model_name} model, {name} over [{a:g}, {b:g}]"]
    for br in branches:
        lines.append(f"  {br.name}: {len(br)} points ({int(br.stable.sum())} stable); "
                     f"stopped: {'; '.join(br.stop_reasons)}")
        rows = [(sp.kind, f"{sp.value:.10f}", f"{sp.bracket:.1e}",
                 f"{abs(sp.orbit.multipliers[0]):.6g}", sp.orbit.label, sp.note)
                for sp in br.special]
        if rows:
            lines.append(_table(("    point", name, "bracket", "max |mu|", "orbit", "note"),
                                [("    " + r[0], *r[1:]) for r in rows], "lrrrll"))
    lines.append(f"wrote {args.output}; time: {wall:.2f} s work, {_command_seconds():.2f} s "
                 "command")
    _emit("\n".join(lines))
    return EXIT_OK


def _plot_branch_file(args: argparse.Namespace) -> int:
    from matplotlib.figure import Figure

    from chaospound.orbits.store import open_branches
    from chaospound.plot import plot_branches, plot_multipliers, save
    from chaospound.store import open_sweep

    if args.orbit is not None:
        raise CliError("--orbit draws a sweep file's orbit diagram; a branch file's diagram "
                       "has the impact velocities (or the first state) of every orbit")
    data = open_branches(args.sweep_file)
    output = args.output or os.path.splitext(args.sweep_file)[0] + ".png"
    if os.path.abspath(output) == os.path.abspath(args.sweep_file):
        raise CliError(f"output {_path(output)} is the branch file itself")
    check_figure_path(output)
    over = None
    if args.over is not None:
        if not os.path.exists(args.over):
            raise CliError(f"--over {_path(args.over)} not found")
        over = open_sweep(args.over)
        if over.parameters[0] != data.parameter or len(over.parameters) != 1:
            raise CliError(f"--over: the sweep is over {' x '.join(over.parameters)}, the "
                           f"branches over {data.parameter}")
    branches = data.branches
    if args.branch is not None:
        names = [br.name for br in branches]
        if args.branch not in names:
            raise CliError(f"--branch {args.branch}: the file has {', '.join(names)}")
        branches = [br for br in branches if br.name == args.branch]
    fig = Figure(figsize=tuple(args.size) if args.size else (13.0, 5.0), layout="constrained")
    left, right = fig.subplots(1, 2, width_ratios=(2, 1))
    plot_branches(branches, left, over=over)
    plot_multipliers(branches, right)
    fig.suptitle(f"{data.system}: {data.model} model, continued in {data.parameter}")
    if args.xlim is not None:
        left.set_xlim(*args.xlim)
    if args.ylim is not None:
        left.set_ylim(*args.ylim)
    try:
        save(fig, output, dpi=args.dpi)
    except OSError as exc:
        raise CliError(f"cannot write {_path(output)}: {exc.strerror or exc}") from None
    _emit(f"wrote {output}: bifurcation diagram of {len(branches)} continued branch(es) in "
          f"{data.parameter}" + (f" over {args.over}" if over is not None else "")
          + " and their Floquet multipliers")
    return EXIT_OK


# ============================================================== helpers
class _ParserExit(Exception):
    """argparse finished early (--help, --version) with this exit status."""

    def __init__(self, status: int) -> None:
        super().__init__(status)
        self.status = status


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are exceptions, so :func:`main` returns codes."""

    def error(self, message: str) -> NoReturn:
        raise CliError(_shorten_words(message))

    def exit(self, status: int = 0, message: str | None = None) -> NoReturn:
        if message:
            sys.stderr.write(message)
        raise _ParserExit(status)


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


def _is_simulation_error(exc: BaseException) -> bool:
    """True for chaospound.simulate.SimulationError (without importing the kernels)."""
    module = sys.modules.get("chaospound.dynamics.system")  # defines SimulationError
    return module is not None and isinstance(exc, module.SimulationError)


def _shorten_words(message: str) -> str:
    """argparse's message with every long word (an argument it quotes whole) cut short."""
    words = []
    for word in message.split(" "):
        if len(word) > QUOTE_LIMIT and word[0] == word[-1] and word[0] in "'\"":
            word = shorten(word[1:-1], quote=True)
        elif len(word) > QUOTE_LIMIT:
            word = shorten(word)
        words.append(word)
    return " ".join(words)


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


if __name__ == "__main__":
    raise SystemExit(main())
