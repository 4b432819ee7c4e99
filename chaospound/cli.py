"""The ``chaospound`` command line.

Commands::

    chaospound presets [NAME]            table of presets, or one preset's TOML
    chaospound params [NAME ...]         flat parameter names, meaning and range
    chaospound simulate (--preset NAME | SCENE.toml) [--set k=v ...] [--json] ...

Every command that runs a scene takes the same scene options, added by
:func:`add_scene_options` and turned into a validated
:class:`~chaospound.scene.Scene` by :func:`scene_from_args`; later commands
(lyapunov, classify, sweep, plot, bench) reuse both.

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
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, NoReturn

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
    "scene_from_args",
    "write_json_file",
]

PROG = "chaospound"
EXIT_OK = 0
EXIT_FAILURE = 1  #: a numerical failure (SimulationError)
EXIT_USAGE = 2  #: bad input: usage, scene, files
EXIT_INTERRUPTED = 130  #: Ctrl-C (128 + SIGINT)
EXIT_BROKEN_PIPE = 141  #: stdout closed early (128 + SIGPIPE), e.g. ``| head``

#: run and solver options applied as scene overrides (option dest = flat parameter name)
RUN_OVERRIDES = ("transient", "record", "method", "rtol", "atol", "phase")
#: columns of the readable impact table
IMPACT_COLUMNS = ("#", "cycle", "phase", "velocity", "corner", "peak pen", "peak force", "duration")


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
    for add in (_add_presets, _add_params, _add_simulate, _add_lyapunov, _add_bench):
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
        "scene_file", nargs="?", metavar="SCENE.toml", help="scene file (see 'chaospound presets')"
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

    preset, path = args.preset, args.scene_file
    if preset is not None and path is not None:
        raise CliError(f"give --preset {preset} or the scene file {path!r}, not both")
    if preset is None and path is None:
        raise CliError("no scene: give --preset NAME or a scene file (see 'chaospound presets')")
    if path is not None and not os.path.exists(path):
        raise CliError(f"scene file {path!r} not found")
    scene = load_preset(preset) if preset is not None else load_scene(path)
    overrides = [
        f"{name}={getattr(args, name)}"
        for name in RUN_OVERRIDES
        if getattr(args, name, None) is not None
    ]
    assignments = list(args.assignments) + overrides
    return scene.with_assignments(assignments) if assignments else scene


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
        raise CliError(f"cannot write {path!r}: {exc.strerror or exc}") from None
    try:
        with handle:
            handle.write(text)
        check_output_path(path, overwrite=overwrite)
        os.replace(handle.name, path)
    except BaseException as exc:
        os.unlink(handle.name)
        if isinstance(exc, OSError):
            raise CliError(f"cannot write {path!r}: {exc.strerror or exc}") from None
        raise


def check_output_path(path: str, *, overwrite: bool) -> None:
    """Raise :class:`CliError` unless ``path`` can be written (before any work)."""
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise CliError(f"output {path!r} is a directory")
    if os.path.exists(path) and not overwrite:
        raise CliError(f"output {path!r} exists (use --overwrite to replace it)")
    if not os.path.isdir(folder):
        raise CliError(f"output {path!r}: folder {folder!r} does not exist")


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
            raise CliError(f"unknown parameter {name!r} (see 'chaospound params')")
    names = args.names or list(described)
    _emit(_table(("parameter", "meaning"), [(n, described[n]) for n in names], "ll"))
    return EXIT_OK


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
        type=_count,
        default=0,
        metavar="N",
        help="dense samples per cycle over the record window (JSON 'trajectory')",
    )
    out.add_argument("--output", metavar="FILE.json", help="also write the JSON to this file")
    out.add_argument("--overwrite", action="store_true", help="replace an existing --output")
    parser.set_defaults(func=_cmd_simulate)


def _cmd_simulate(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    if args.output is not None:
        check_output_path(args.output, overwrite=args.overwrite)
    sim = _run_simulation(scene, args.trajectory)
    document = _simulation_document(sim)
    if args.output is not None:
        write_json_file(document, args.output, overwrite=args.overwrite)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_simulation_report(sim, args.trajectory, args.output))
    return EXIT_OK


def _run_simulation(scene: Scene, samples_per_cycle: int) -> Simulation:
    """Warm the jitted kernels up on one cycle, then run (so wall_s excludes JIT loading)."""
    from chaospound.simulate import simulate

    simulate(scene, transient=0, record=1)
    return simulate(scene, samples_per_cycle=samples_per_cycle)


def _simulation_document(sim: Simulation) -> dict:
    document = sim.to_json_dict()
    if sim.trajectory is not None:
        document["trajectory"] = {
            "time": sim.trajectory.time.tolist(),
            "state": sim.trajectory.state.tolist(),
        }
    return document


def _simulation_report(sim: Simulation, samples_per_cycle: int, output: str | None) -> str:
    """Header, impact table and summary of one run, as text."""
    scene, imp = sim.scene, sim.impacts
    solver = scene.solver
    accuracy = (
        f"{solver.steps_per_cycle} steps per cycle"
        if solver.method == "rk4"
        else f"rtol {solver.rtol:g}, atol {solver.atol:g}"
    )
    header = [
        ("scene", f"{scene.name}: {scene.description}" if scene.description else scene.name),
        ("model", f"{sim.model} ({len(sim.state_names)} states: {' '.join(sim.state_names)})"),
        ("period ratio", f"T/T_Ax = {scene.excitation.period_ratio:g} (T = {sim.period:.6g})"),
        ("cycles", f"{sim.transient} transient + {sim.record} recorded, "
                   f"section phase {scene.run.phase:g}"),
        ("solver", f"{solver.method}, {accuracy}"),
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
        blocks.append(_table(IMPACT_COLUMNS, rows, "rrrrlrrr"))
    else:
        blocks.append("no impacts in the record window")
    blocks.append(_table(None, _summary(sim, samples_per_cycle, output), "ll"))
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
            f"min {imp.velocity.min():.6g}, max {imp.velocity.max():.6g}" if len(imp) else "-",
        ),
        (f"corners, cycle {last_cycle}", " ".join(last) if last else "none"),
        (
            "steps",
            f"{stats.steps} accepted, {stats.rejected} rejected, "
            f"{stats.rhs_evals} rhs evaluations, {stats.events} events",
        ),
        ("wall time", f"{stats.wall_s:.4g} s ({per_step:.3g} us per accepted step)"),
    ]
    if samples_per_cycle:
        rows.append(("trajectory", f"{samples_per_cycle} samples per cycle (JSON 'trajectory')"))
    if output is not None:
        rows.append(("wrote", output))
    return rows


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
        "--repeats", type=_count, default=5, metavar="N", help="timed runs each, best counts (5)"
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
    _emit(_json_text(result) if args.json else format_benchmark(result))
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
        "--k", type=_count, default=None, metavar="K", help="number of exponents (default: all)"
    )
    group.add_argument(
        "--cycles", type=_count, default=400, metavar="N", help="excitation cycles averaged (400)"
    )
    group.add_argument(
        "--tangent-transient",
        type=_count,
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
    out = parser.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print one JSON document only")
    out.add_argument("--plot", metavar="FILE.png", help="write the convergence figure")
    out.add_argument("--overwrite", action="store_true", help="replace an existing --plot file")
    parser.set_defaults(func=_cmd_lyapunov)


def _cmd_lyapunov(args: argparse.Namespace) -> int:
    import time

    from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
    from chaospound.dynamics.system import System

    scene = scene_from_args(args)
    system = System.from_scene(scene)
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
        check_output_path(args.plot, overwrite=args.overwrite)
    # warm the jitted kernels up, so that the reported wall time is the work's
    lyapunov_spectrum(system, k=args.k, transient=0, tangent_transient=0, cycles=2, n_blocks=2)
    start = time.perf_counter()
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
        two = largest_exponent_two_trajectory(
            two_system,
            cycles=args.cycles,
            separation=LYAPUNOV_SEPARATION,
            n_blocks=LYAPUNOV_BLOCKS,
        )
        two_wall = time.perf_counter() - start
    if args.plot is not None:
        _lyapunov_save_plot(spectrum, two, args.plot, overwrite=args.overwrite)
    document = _lyapunov_document(scene, system, spectrum, wall, two, two_system, two_wall)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_lyapunov_report(scene, system, spectrum, document, args.plot))
    return EXIT_OK


def _lyapunov_save_plot(spectrum, two, path: str, *, overwrite: bool) -> None:
    """Write the convergence figure atomically; file errors become CliError."""
    from chaospound.plot import plot_lyapunov_convergence, save

    fig = plot_lyapunov_convergence(spectrum, two)
    check_output_path(path, overwrite=overwrite)
    try:
        save(fig, path)
    except OSError as exc:
        raise CliError(f"cannot write {path!r}: {exc.strerror or exc}") from None


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
        "scene": scene.to_dict(),
    }
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
    solver = scene.solver
    accuracy = (
        f"{solver.steps_per_cycle} steps per cycle"
        if solver.method == "rk4"
        else f"rtol {solver.rtol:g}, atol {solver.atol:g}"
    )
    header = [
        ("scene", f"{scene.name}: {scene.description}" if scene.description else scene.name),
        ("model", f"{system.model_name} ({system.dim} states: {' '.join(system.state_names)})"),
        ("period ratio", f"T/T_Ax = {scene.excitation.period_ratio:g} (T = {spectrum.period:.6g})"),
        ("cycles", f"{spectrum.transient} transient + {spectrum.tangent_transient} tangent "
                   f"transient + {spectrum.cycles} averaged ({document['blocks']} blocks)"),
        ("solver", f"{solver.method}, {accuracy}"),
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
    if document["full_spectrum"]:
        identity = f"{total:.6g} (trace identity {trace:.6g}, difference {total - trace:.2g})"
    else:
        identity = (f"{total:.6g} (of {document['k']} exponents; the trace identity "
                    f"{trace:.6g} holds for all {system.dim})")
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
                            f"{work['wall_s']:.3g} s"))  # fmt: skip
    if plot is not None:
        summary.append(("wrote", plot))
    blocks = [
        _table(None, header, "ll"),
        _table(columns, rows, "rrrrr"),
        _table(None, summary, "ll"),
    ]
    return "\n\n".join(blocks) + "\n"


# ============================================================== helpers
class _ParserExit(Exception):
    """argparse finished early (--help, --version) with this exit status."""

    def __init__(self, status: int) -> None:
        super().__init__(status)
        self.status = status


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are exceptions, so :func:`main` returns codes."""

    def error(self, message: str) -> NoReturn:
        raise CliError(message)

    def exit(self, status: int = 0, message: str | None = None) -> NoReturn:
        if message:
            sys.stderr.write(message)
        raise _ParserExit(status)


def _count(text: str) -> int:
    """argparse type: an integer >= 0."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be an integer >= 0")
    return value


def _is_simulation_error(exc: BaseException) -> bool:
    """True for chaospound.simulate.SimulationError (without importing the kernels)."""
    module = sys.modules.get("chaospound.simulate")
    return module is not None and isinstance(exc, module.SimulationError)


def _fail(message: str, code: int) -> int:
    """Report one line on stderr and return ``code``."""
    sys.stderr.write(f"{PROG}: error: {' '.join(message.split())}\n")
    sys.stderr.flush()
    return code


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
