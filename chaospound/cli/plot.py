"""``chaospound plot``: the figure of a sweep file (bifurcation diagram, regime
map, exponents, orbit diagram); a branch file is drawn by
:func:`chaospound.cli.orbit._plot_branch_file`."""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Sequence

from chaospound.cli.files import check_figure_path
from chaospound.cli.options import _float_pair, _positive_float
from chaospound.cli.orbit import _is_branch_file, _plot_branch_file
from chaospound.cli.output import EXIT_OK, CliError, _emit, _path


def add_parser(commands: argparse._SubParsersAction) -> None:
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
    basin = "axis_kinds" in sweep.sweep and args.orbit is None  # chaospound basins' file
    if basin:
        from chaospound.basins import open_basins
        from chaospound.plot_basins import plot_basins

        fig = plot_basins(open_basins(args.sweep_file), state_names=sweep.state_names)
    else:
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
    except ValueError as exc:  # a raster image too large for memory
        raise CliError(f"{_path(output)}: {exc}") from None
    kind = "bifurcation diagram" if len(sweep.parameters) == 1 else "regime map"
    kind = "basin map" if basin else kind
    if args.orbit is not None:
        kind += f" and orbit diagram of {args.orbit}"
    elif len(sweep.parameters) == 2 and _has_exponents(sweep, branches):
        kind += " and exponent map"
    _emit(f"wrote {output}: {kind} of {' x '.join(sweep.parameters)}, "
          f"branch {', '.join(branches)}")
    return EXIT_OK


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
