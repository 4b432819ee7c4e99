"""``chaospound basins``: basins of attraction over one or two initial conditions,
streamed to a sweep store (:mod:`chaospound.basins`)."""

from __future__ import annotations

import argparse

from chaospound.cli.files import check_figure_path
from chaospound.cli.options import _count, add_scene_options, target_from_args
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
from chaospound.cli.sweep import _check_sweep_output, _exponent_count


def add_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "basins",
        help="basins of attraction over one or two initial conditions, to an HDF5 file",
        description="Run every initial condition of a grid over one or two state components "
        "(X_A, dX_A, ... of the scene's model, or a system's states) or the initial forcing "
        "phase (initial_phase, a fraction of the period) for the scene's transient and record "
        "windows, classify it, identify the attractors (same regime, n-P, corners and "
        "section states up to a cyclic shift) and report each one's share of the grid and "
        "the basin entropy. The points go into a sweep store written as they finish "
        "(--resume finishes an interrupted file); the attractors into its /basins group "
        "(docs/basins.md).",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("basins")
    group.add_argument(
        "--grid",
        dest="grids",
        action="append",
        default=[],
        metavar="NAME=GRID",
        help="initial condition scanned, once or twice: a state component or initial_phase; "
        "GRID is start:stop:step, start:stop#count or v1,v2,... (e.g. X_A=-8:4#101)",
    )
    group.add_argument("--lyapunov", nargs="?", const=1, default=0, type=_exponent_count,
                       metavar="K", help="also the K largest Lyapunov exponents per point "
                       "(names aperiodic attractors chaotic or quasi-periodic)")
    group.add_argument("--window-tol", type=float, default=1e-2, metavar="TOL",
                       help="relative stroboscopic mismatch accepted as periodic (0.01)")
    group.add_argument("--tol", type=float, default=0.05, metavar="TOL",
                       help="relative distance of section states within which two points "
                       "reach the same attractor (0.05)")
    group.add_argument("--box", type=_count, default=5, metavar="N",
                       help="box side of the basin entropy, in grid cells (5)")
    group.add_argument("--plot", metavar="FILE", help="draw the basin map (.png, .pdf, .svg)")
    out = parser.add_argument_group("output and execution")
    out.add_argument("-o", "--output", required=True, metavar="FILE.h5", help="the scan's file")
    out.add_argument("--resume", action="store_true",
                     help="finish an interrupted file of the same scan (a missing file is "
                     "started; a finished one is identified and drawn again)")
    out.add_argument("--overwrite", action="store_true", help="replace an existing file")
    out.add_argument("--workers", type=_count, default=1, metavar="N",
                     help="worker processes (1); results do not depend on it")
    out.add_argument("--chunk", type=_count, default=None, metavar="N",
                     help="points per task (default: sized from the grid and the workers)")
    out.add_argument("--quiet", action="store_true", help="no progress bar")
    out.add_argument("--scheduler", metavar="ADDRESS",
                     help="run the tasks on Dask: tcp://HOST:PORT or 'local' "
                     "(docs/distributed.md)")
    parser.set_defaults(func=_cmd_basins)


def _cmd_basins(args: argparse.Namespace) -> int:
    from chaospound.basins import basins
    from chaospound.grid import initial_axis
    from chaospound.store import StoreWriteError
    from chaospound.sweep import SweepInterrupted

    if args.resume and args.overwrite:
        raise CliError("give --resume or --overwrite, not both")
    target = target_from_args(args)
    if not args.grids:
        raise CliError("nothing to scan: give --grid NAME=GRID once or twice, e.g. "
                       "--grid X_A=-8:4#101 --grid dX_A=-12:12#101")
    if len(args.grids) > 2:
        raise CliError(f"{len(args.grids)} --grid options: give one or two")
    axes = [initial_axis(text, target) for text in args.grids]
    if len({a.name for a in axes}) != len(axes):
        raise CliError(f"--grid {axes[0].name} given twice")
    if not 0.0 < args.tol < 1.0:
        raise CliError(f"--tol {args.tol}: must be in (0, 1)")
    if not 0.0 < args.window_tol < 1.0:
        raise CliError(f"--window-tol {args.window_tol}: must be in (0, 1)")
    if args.plot is not None:
        check_figure_path(args.plot)
    _check_sweep_output(args.output, resume=args.resume, overwrite=args.overwrite)
    from chaospound.distributed import ClusterUnavailable, connect, disconnect

    client = cluster = None
    if args.scheduler is not None:
        try:
            client, cluster = connect(args.scheduler, args.workers)
        except ClusterUnavailable as exc:
            return _fail(str(exc), EXIT_FAILURE)
    try:
        summary, result = basins(
            target, axes, args.output, workers=args.workers, resume=args.resume,
            overwrite=args.overwrite, progress=not args.quiet, chunk=args.chunk,
            client=client, lyapunov=args.lyapunov, window_tol=args.window_tol,
            tol=args.tol, box=args.box)
    except SweepInterrupted as exc:
        return _fail(str(exc).replace("chaospound sweep", "chaospound basins"),
                     EXIT_INTERRUPTED)
    except ClusterUnavailable as exc:
        return _fail(f"{exc}; the points written so far are kept: finish with "
                     f"chaospound basins ... -o {args.output} --resume", EXIT_FAILURE)
    except StoreWriteError as exc:
        return _fail(str(exc), EXIT_FAILURE)
    except OSError as exc:
        raise CliError(f"cannot write {_path(args.output)}: {exc.strerror or exc}") from None
    finally:
        if client is not None:
            disconnect(client, cluster)
    _emit(summary.format())
    if summary.all_failed:  # a numerical failure: no attractor to map
        return _fail(f"every initial state of {args.output} failed"
                     + (f" (the first: {summary.messages[0]})" if summary.messages else ""),
                     EXIT_FAILURE)
    _emit(result.format())
    if not args.lyapunov and any(a.regime == "unresolved" for a in result.attractors):
        _note("'unresolved' here: no period within the record window after the scene's "
              "transient (the window classification of a sweep point); --lyapunov names an "
              "aperiodic attractor chaotic or quasi-periodic, a longer --set transient=N "
              "lets slow starts settle")
    if args.plot is not None:
        from chaospound.plot import save
        from chaospound.plot_basins import plot_basins
        from chaospound.store import open_sweep

        save(plot_basins(result, state_names=open_sweep(args.output).state_names), args.plot)
        _emit(f"basin map: {args.plot}")
    return EXIT_OK
