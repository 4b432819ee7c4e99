"""The basin map: initial conditions coloured by the attractor they reach.

One categorical colour per attractor (:class:`chaospound.basins.Attractor`,
numbered by basin size), grey for failed points and white for pending ones;
the legend names each attractor (regime n-P and corners, its first section
state) with its share; the title gives the basin entropy S_b and the boundary
basin entropy S_bb. The attractors' section states are marked on the map when
they lie in it (a periodic attractor's P points, as crosses). Like
:mod:`chaospound.plot`, the figure is made without pyplot and written by
:func:`chaospound.plot.save`.
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from .basins import FAILED, PENDING, BasinMap, box_text
from .plot import MISSING_COLOR, axis_label, cell_edges

__all__ = ["BASIN_COLORS", "plot_basins"]

#: attractor colours, by number: matplotlib's ten, then ten lighter ones
BASIN_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                "#e377c2", "#bcbd22", "#17becf", "#7f7f7f", "#aec7e8", "#ffbb78",
                "#98df8a", "#ff9896", "#c5b0d5", "#c49c94", "#f7b6d2", "#dbdb8d",
                "#9edae5", "#393b79")
FAILED_COLOR = MISSING_COLOR
PENDING_COLOR = "white"
SHOWN = len(BASIN_COLORS)  #: attractors with a colour of their own; the rest share "other"


def plot_basins(result: BasinMap, *, state_names=None, fig: Figure | None = None) -> Figure:
    """Draw a basin map (1 or 2 initial-condition axes: the first across, the second up).

    Parameters
    ----------
    result : BasinMap
        From :func:`chaospound.basins.basins` or :func:`~chaospound.basins.open_basins`.
    state_names : sequence of str, optional
        Names of the state components, in order: the attractors' section states
        are marked on the map when both axes are state components.
    fig : Figure, optional
        Figure to draw into.

    Returns
    -------
    Figure
    """
    if fig is None:
        fig = Figure(figsize=(7.5, 5.0), layout="constrained")
    ax = fig.add_subplot()
    labels = np.asarray(result.labels)
    shown = min(len(result.attractors), SHOWN)
    # colour index: 0 pending, 1 failed, 2 + k attractor k (the rest: "other", the last)
    index = np.where(labels == PENDING, 0, np.where(labels == FAILED, 1,
                                                    2 + np.minimum(labels, shown)))
    colors = [PENDING_COLOR, FAILED_COLOR, *BASIN_COLORS[:shown], "black"]
    cmap = ListedColormap(colors)
    x_name = result.axes[0]  # the first axis across, the second up (a phase plane)
    x_edges = cell_edges(result.grid[x_name])
    if labels.ndim == 2:
        y_name = result.axes[1]
        y_edges = cell_edges(result.grid[y_name])
        index = index.T
    else:
        index = index[None, :]
        y_name, y_edges = None, np.array([0.0, 1.0])
    ax.pcolormesh(x_edges, y_edges, index, cmap=cmap, vmin=-0.5, vmax=len(colors) - 0.5,
                  shading="flat", rasterized=True)
    ax.set_xlabel(_label(x_name))
    if y_name is not None:
        ax.set_ylabel(_label(y_name))
    else:
        ax.set_yticks([])
    _mark_attractors(ax, result, state_names, x_name, y_name)
    handles = []
    for a in result.attractors[:shown]:
        where = _where(a, state_names)
        handles.append(Patch(color=BASIN_COLORS[a.number],
                             label=f"#{a.number} {a.label}{where}: {100 * a.share:.1f} %"))
    if len(result.attractors) > shown:
        rest = sum(a.share for a in result.attractors[shown:])
        handles.append(Patch(color="black", label=f"{len(result.attractors) - shown} more: "
                                                   f"{100 * rest:.1f} %"))
    if result.failed:
        computed = max(1, int(np.sum(labels != PENDING)))
        handles.append(Patch(color=FAILED_COLOR,
                             label=f"failed: {100 * result.failed / computed:.1f} %"))
    if np.any(labels == PENDING):
        handles.append(Patch(facecolor=PENDING_COLOR, edgecolor="0.5", label="pending"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8,
              frameon=False)
    entropy = (f"basin entropy $S_b$ = {result.entropy:.3f}, $S_{{bb}}$ = "
               f"{result.boundary_entropy:.3f} (boxes of "
               f"{box_text(result.labels.shape, result.box)})"
               if result.boxes else f"no basin entropy (grid smaller than a {result.box}-cell box)")
    ax.set_title(f"{len(result.attractors)} attractor(s); {entropy}", fontsize=9)
    return fig


def _label(name: str) -> str:
    if name == "initial_phase":
        return "initial phase (fraction of T)"
    return axis_label(name)


def _where(attractor, state_names) -> str:
    """" at X_A=..., dX_A=..." (its first section state) for a periodic attractor."""
    if state_names is None or attractor.period_cycles <= 0 or attractor.sections.size == 0:
        return ""
    state = attractor.sections[0]
    shown = ", ".join(f"{n}={v:.3g}" for n, v in list(zip(state_names, state, strict=False))[:3])
    return f" at {shown}"


def _mark_attractors(ax, result: BasinMap, state_names, x_name: str, y_name) -> None:
    """Crosses at the periodic attractors' section states when both axes are states."""
    if state_names is None or y_name is None:
        return
    names = list(state_names)
    if x_name not in names or y_name not in names:
        return
    ix, iy = names.index(x_name), names.index(y_name)
    for a in result.attractors[:SHOWN]:
        if a.period_cycles <= 0:
            continue
        ax.plot(a.sections[:, ix], a.sections[:, iy], "x", color="black", ms=7, mew=2.2)
        ax.plot(a.sections[:, ix], a.sections[:, iy], "x", color=BASIN_COLORS[a.number],
                ms=6, mew=1.2)
