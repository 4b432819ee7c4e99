"""``chaospound sweep``: a bifurcation scan over one or two parameters, streamed
to an HDF5 file."""

from __future__ import annotations

import argparse
import os
from typing import TYPE_CHECKING

from chaospound.cli.options import (
    RUN_OVERRIDES,
    _count,
    _is_system,
    add_scene_options,
    target_from_args,
)
from chaospound.cli.output import (
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_OK,
    CliError,
    _emit,
    _fail,
    _note,
    _path,
)
from chaospound.messages import shorten

if TYPE_CHECKING:
    from chaospound.scene import Scene


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


SWEEP_CONTINUATIONS = ("none", "forward", "backward", "both")  #: as chaospound.sweep.CONTINUATIONS
SWEEP_CLASSIFY = ("converged", "paper", "window", "full")  #: as chaospound.sweep.CLASSIFY_MODES


def add_parser(commands: argparse._SubParsersAction) -> None:
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
        default="converged",
        help="converged (default): every point run to its attractor from the "
        "scene's initial state, periods confirmed by Newton and Floquet multipliers, "
        "exponents until the 3-sigma decision; paper (or window): the regime from each "
        "point's own record window, the paper's transient + record (aperiodic points "
        "unresolved without --lyapunov); full: the careful adaptive classifier per point "
        "(slow)",
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
    if summary.all_failed:  # a numerical failure, however many points
        return _fail(f"every point of {args.output} failed"
                     + (f" (the first: {summary.messages[0]})" if summary.messages else ""),
                     EXIT_FAILURE)
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
    if os.path.exists(path):
        from chaospound.store import check_replaceable

        check_replaceable(path)  # not a store: never resumed, never replaced
    if resume or overwrite:
        return
    if os.path.exists(path + ".journal"):
        raise CliError(f"output {_path(path)}: an interrupted sweep's journal exists (use --resume "
                       "to finish it or --overwrite to replace it)")
    if os.path.exists(path):
        raise CliError(f"output {_path(path)} exists (use --resume to finish it or --overwrite "
                       "to replace it)")
