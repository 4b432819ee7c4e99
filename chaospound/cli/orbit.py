"""``chaospound orbit`` (a periodic orbit by Newton shooting) and ``chaospound
continue`` (its branch in a parameter), and the figure of a branch file."""

from __future__ import annotations

import argparse
import math
import os
import time
from typing import TYPE_CHECKING

from chaospound.cli.files import check_figure_path, check_output_path
from chaospound.cli.options import _count, _positive_float, add_scene_options, scene_from_args
from chaospound.cli.output import (
    EXIT_FAILURE,
    EXIT_OK,
    CliError,
    _emit,
    _fail,
    _is_simulation_error,
    _json_text,
    _note,
    _path,
    _table,
    _with_units,
)
from chaospound.cli.status import _command_seconds, _load_kernels, _Status
from chaospound.messages import shorten

if TYPE_CHECKING:
    from chaospound.scene import Scene


def _orbit_warm(smap):
    """The call that loads the two engines of orbit work: the map and its monodromy."""
    def warm() -> None:
        from chaospound.dynamics.system import evolve, monodromy

        evolve(smap.system, smap.system.initial_state, cycles=1)
        monodromy(smap.system, smap.system.initial_state, 1)
    return warm


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
    from chaospound.orbits.shooting import find_orbit, minimal_period

    scene = scene_from_args(args)
    smap = _orbit_map(args, scene)
    _load_kernels(args.quiet, _orbit_warm(smap), smap.system.engine("propagator"))
    start = time.perf_counter()
    with _Status(f"period-{args.period} orbit of {scene.name}: {smap.system.transient} "
                 "transient cycles, then Newton", quiet=args.quiet):
        orbit = find_orbit(smap, period=args.period, tol=args.tol)
        shortest = minimal_period(smap, orbit.state, orbit.period)
    wall = time.perf_counter() - start
    document = {"scene": scene.to_dict(), "model": smap.system.model_name,
                "solver": {"method": smap.system.method, "rtol": smap.system.rtol,
                           "atol": smap.system.atol},
                "transient_cycles": smap.system.transient, **orbit.to_json_dict(),
                "minimal_period": shortest, "wall_s": wall}
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
    if shortest < orbit.period:
        lines[-1:-1] = [f"  note: the orbit repeats after {shortest} cycle"
                        f"{'' if shortest == 1 else 's'}: Newton on the {orbit.period}-fold map "
                        f"converges to any orbit whose period divides {orbit.period}; this is "
                        f"the period-{shortest} orbit"]
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
                       help="largest pseudo-arclength step (default: a tenth of the interval "
                            "per unit of each point's state scale)")
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
    except ValueError as exc:  # a raster image too large for memory
        raise CliError(f"{_path(output)}: {exc}") from None
    _emit(f"wrote {output}: bifurcation diagram of {len(branches)} continued branch(es) in "
          f"{data.parameter}" + (f" over {args.over}" if over is not None else "")
          + " and their Floquet multipliers")
    return EXIT_OK


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``orbit`` and ``continue`` to the subcommands."""
    _add_orbit(commands)
    _add_continue(commands)
