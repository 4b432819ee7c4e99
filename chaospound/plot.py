"""Figures built from results objects: phase diagrams, sections, impact maps,
Lyapunov convergence and bifurcation diagrams.

Every function takes results (a :class:`~chaospound.simulate.Simulation`, a
:class:`~chaospound.dynamics.poincare.Section`, an
:class:`~chaospound.dynamics.impact_map.ImpactMap`, a
:class:`~chaospound.dynamics.lyapunov.Spectrum`, plain arrays of a sweep) and
optionally the Figure or Axes to draw into, and returns the Figure. Nothing
is shown or written except by :func:`save`. Figures are made with
:class:`matplotlib.figure.Figure` directly, never through pyplot, so no
backend or global state is touched (safe under Agg, in workers, in tests).

Axes carry physical labels in the normalised units of docs/model.md section 2:
lengths over A_g, time times omega_Ax, velocities over A_g omega_Ax,
rotations in radians.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from collections.abc import Sequence
from typing import TYPE_CHECKING

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

if TYPE_CHECKING:
    from .dynamics.impact_map import ImpactMap
    from .dynamics.lyapunov import LargestExponent, Spectrum
    from .dynamics.poincare import Section
    from .simulate import ContactHistory, Simulation

__all__ = [
    "CORNER_COLORS",
    "REGIME_COLORS",
    "axis_label",
    "parameter_label",
    "plot_hysteresis",
    "phase_panels",
    "plot_bifurcation",
    "plot_branches",
    "plot_multipliers",
    "plot_exponent_map",
    "plot_impact_map",
    "plot_lyapunov_convergence",
    "plot_orbit_diagram",
    "plot_phase_diagrams",
    "plot_run",
    "plot_strobe",
    "plot_time_histories",
    "save",
]

#: colour of each corner label (impact sections, impact maps)
CORNER_COLORS = {"A+": "C0", "A-": "C1", "B+": "C2", "B-": "C3", "face": "C7"}
#: colour of each regime category (first word of a regime label)
REGIME_COLORS = {
    "none": "0.6",
    "periodic": "C0",
    "group-periodic": "C2",
    "quasi-periodic": "C1",
    "chaotic": "C3",
    "unresolved": "C4",
    "failed": "k",
}
#: colours of the Lyapunov exponents: matplotlib's ten, then six more distinct ones
EXPONENT_COLORS = (*(f"C{i}" for i in range(10)), "#000080", "#b8860b", "#00a0a0", "#e000e0",
                   "#556b2f", "#8b0000")
VELOCITY_LABEL = r"$V/(A_g\,\omega_{Ax})$"
PHASE_LABEL = r"phase $(t\ \mathrm{mod}\ T)/T$"
EXPONENT_LABEL = r"$\lambda/\omega_{Ax}$ (per unit $t = \tau\omega_{Ax}$)"
PERIOD_RATIO_LABEL = r"$T/T_{Ax}$"
TIME_LABEL = r"normalised time $t = \tau\,\omega_{Ax}$"
CLEARANCE_LABEL = r"clearance $-d_{max}/A_g$"
FORCE_LABEL = r"contact force $F/(A_g\,k_{Ax})$"
#: axes labels (Axes.get_label) of the time-history panels, for tests and callers
HISTORY_PANELS = ("X", "Y", "th", "clearance", "force")
_HISTORY_SYMBOLS = {"X": "$X_{}$", "Y": "$Y_{}$", "th": r"$\theta_{}$"}
_HISTORY_UNITS = {"X": r"$X/A_g$", "Y": r"$Y/A_g$", "th": r"$\theta$ (rad)"}
#: axis label of each sweep parameter: symbol and unit (docs/model.md section 3), never the
#: raw flat name; see :func:`parameter_label`
PARAMETER_LABELS = {
    "period_ratio": PERIOD_RATIO_LABEL,
    "freq_ratio": r"$\Omega = T_{Ax}/T_{Bx}$",
    "mass_ratio": r"$m = m_A/m_B$",
    "gap": r"$a/A_g$",
    "offset_y": r"$y_{off}/A_g$",
    "beta": r"$\beta$ (Hertz stiffness)",
    "chi": r"$\chi$ (Hertz exponent)",
    "restitution": r"$e$ (coefficient of restitution)",
    "ground_scale": r"record scale factor",
    "ground_dt": r"$\Delta t_g$ [s]",
    "length_unit": r"$A_g$ [m]",
    "tower_period": r"$T_{Ax}$ [s]",
    "tower_mass": r"$m_A$ [kg]",
    "ground_seed": "stochastic motion seed",
    "ground_duration": "motion duration [s]",
    "ground_omega_g": r"$\omega_g$ [rad/s]",
    "ground_zeta_g": r"$\zeta_g$",
    "ground_omega_f": r"$\omega_f$ [rad/s]",
    "ground_zeta_f": r"$\zeta_f$",
    "ground_intensity": r"$S_0$ [m$^2$/s$^3$]",
    "ground_pga": "PGA [g]",
    "ground_t_rise": r"$t_{rise}$ [s]",
    "ground_t_plateau": r"$t_{plateau}$ [s]",
    "ground_decay": "envelope decay [1/s]",
    "ground_sh_b": r"Saragoni-Hart $b$",
    "ground_sh_c": r"Saragoni-Hart $c$ [1/s]",
    "ground_components": "ground components",
    "ground_y_ratio": r"$u_{gy}/u_{gx}$ (y amplitude ratio)",
    "ground_y_phase": r"$\varphi_y$ [rad] (y phase lead)",
    "rtol": "relative tolerance rtol",
    "atol": "absolute tolerance atol",
    "phase": r"section phase $t_0/T$",
    "transient": "transient cycles",
    "record": "recorded cycles",
    "steps_per_cycle": "rk4 steps per cycle",
}
_TOWER_LABELS = {
    "length": r"$l_{T}/A_g$",
    "width": r"$w_{T}/A_g$",
    "width_ratio": r"$w_{T}/l_{T}$",
    "ecc_x": r"$e_{Tx}/A_g$",
    "ecc_x_ratio": r"$e_{Tx}/l_{T}$",
    "ecc_y": r"$e_{Ty}/A_g$",
    "ecc_y_ratio": r"$e_{Ty}/l_{T}$",
    "gyration": r"$\rho_{T}/A_g$",
    "zeta_x": r"$\zeta_{Tx}$",
    "zeta_y": r"$\zeta_{Ty}$",
    "zeta_t": r"$\zeta_{T\theta}$",
}
PARAMETER_LABELS.update({
    f"{name}_{tower}": label.replace("{T", "{" + tower).replace("_{T}", "_" + tower)
    for name, label in _TOWER_LABELS.items() for tower in "AB"
})
_TOWER_PANELS = (
    ("Tower A, translation", "X_A", "dX_A"),
    ("Tower A, rotation", "th_A", "dth_A"),
    ("Tower B, translation", "X_B", "dX_B"),
    ("Tower B, rotation", "th_B", "dth_B"),
)
_STATE_NAME = re.compile(r"(d?)(X|Y|th)_([AB])")
_ANNOTATION_OFFSET = 20.0  #: points between an impact marker and its number


# ============================================================ phase diagrams
def plot_phase_diagrams(simulation: Simulation, *, fig: Figure | None = None) -> Figure:
    """Phase diagrams of the record window, impacts of the last cycle numbered.

    One panel per degree of freedom that moves: for the towers model 2 x 2
    (tower A: X vs X', theta vs theta'; tower B: the same), for the reduced
    models fewer (pair: X_A, X_B; tower-wall: X_A, theta_A; wall: X_A). The
    trajectory of the whole record window is drawn thin, its last cycle
    bold; the impacts whose onset lies in the last cycle are marked at their
    onset state and numbered 1, 2, 3, ... in time order, as in the paper's
    Fig. 3, and listed with their corner labels under the panels.

    Parameters
    ----------
    simulation : Simulation
        A run with a dense trajectory (``simulate(..., samples_per_cycle=N)``,
        a few hundred samples per cycle).
    fig : Figure, optional
        An empty figure to draw into.

    Returns
    -------
    Figure
    """
    traj = _trajectory(simulation, "phase diagrams")
    panels = phase_panels(simulation.state_names)
    fig, axes = _panel_figure(fig, len(panels))
    period = simulation.period
    last_cycle = simulation.transient + simulation.record - 1
    in_last = traj.time >= simulation.strobe.time[-2] - 1e-9 * period
    imp = simulation.impacts
    numbered = np.nonzero(imp.cycle == last_cycle)[0]
    labels = imp.labels
    names = simulation.state_names
    for ax, (title, position, rate) in zip(axes, panels, strict=True):
        i, j = names.index(position), names.index(rate)
        ax.plot(
            traj.state[:, i],
            traj.state[:, j],
            color="0.7",
            lw=0.6,
            label=f"cycles {simulation.transient}-{last_cycle}",
        )
        ax.plot(
            traj.state[in_last, i],
            traj.state[in_last, j],
            color="C0",
            lw=1.2,
            label=f"cycle {last_cycle}",
        )
        _number_impacts(ax, imp.state[numbered, i], imp.state[numbered, j], traj.state[:, [i, j]])
        ax.margins(0.12)  # room for the numbers, which point away from the orbit
        _style_panel(ax, title, position, rate)
    axes[0].legend(loc="upper left", fontsize="small", frameon=False)
    scene = simulation.scene
    forcing = (f"$T/T_{{Ax}}$ = {scene.excitation.period_ratio:g}" if scene is not None
               else f"T = {simulation.period:.4g}")  # a user's system: its own period
    fig.suptitle(
        f"{scene.name if scene is not None else simulation.name}: {forcing}, "
        f"{simulation.model} model, cycles {simulation.transient}-{last_cycle}"
    )
    if numbered.size:
        key = "; ".join(
            f"({n + 1}) {labels[k]} at phase {imp.phase[k]:.3f}, V = {imp.velocity[k]:.3g}"
            for n, k in enumerate(numbered)
        )
        caption = f"impacts in cycle {last_cycle}: {key}"
    else:
        caption = f"no impact in cycle {last_cycle}"
    fig.supxlabel(caption, fontsize="small")  # constrained layout keeps room for it
    return fig


def _number_impacts(ax: Axes, xs: np.ndarray, vs: np.ndarray, cloud: np.ndarray) -> None:
    """Mark impact onsets and number them 1, 2, ..., pointing away from the orbit's centre."""
    if xs.size == 0:
        return
    ax.plot(xs, vs, "o", mfc="none", mec="C3", ms=7, mew=1.2)
    centre = 0.5 * (cloud.max(axis=0) + cloud.min(axis=0))
    scale = np.maximum(cloud.max(axis=0) - cloud.min(axis=0), 1e-300)
    for n, (x, v) in enumerate(zip(xs, vs, strict=True)):
        direction = (np.array([x, v]) - centre) / scale
        norm = float(np.hypot(*direction))
        direction = direction / norm if norm > 1e-6 else np.array([0.0, 1.0])
        ax.annotate(
            str(n + 1),
            xy=(x, v),
            xytext=tuple(_ANNOTATION_OFFSET * direction),
            textcoords="offset points",
            ha="center",
            va="center",
            color="C3",
            fontsize="small",
            fontweight="bold",
            bbox={"boxstyle": "circle,pad=0.2", "fc": "white", "ec": "C3", "lw": 0.8},
            arrowprops={"arrowstyle": "-", "color": "C3", "lw": 0.6},
            gid=f"impact-{n + 1}",
        )


# ============================================================ time histories
def plot_time_histories(
    simulation: Simulation, contact: ContactHistory, *, fig: Figure | None = None
) -> Figure:
    """Time histories of a run's record window: displacements, clearance, contact force.

    One panel per kind of displacement the model has (X_A and X_B; Y_A and Y_B and
    the rotations theta_A, theta_B for the torsional models), then the clearance
    -d_max (the gap left at the contact line's closer end, 0 at contact) with every
    impact's onset marked by its corner, then the resultant contact force. The
    panels share the time axis (normalised time; excitation cycles on top). Each
    panel's Axes is labelled (``Axes.get_label``) with its entry of
    :data:`HISTORY_PANELS`.

    Parameters
    ----------
    simulation : Simulation
        A run with a dense trajectory.
    contact : ContactHistory
        :func:`chaospound.simulate.contact_history` of the same run.
    fig : Figure or SubFigure, optional
        An empty figure to draw into.

    Returns
    -------
    Figure
    """
    traj = _trajectory(simulation, "time histories")
    names = simulation.state_names
    groups = [(kind, [n for n in (f"{kind}_A", f"{kind}_B") if n in names])
              for kind in HISTORY_PANELS[:3]]
    groups = [(kind, present) for kind, present in groups if present]
    n_panels = len(groups) + 2
    if fig is None:
        fig = Figure(figsize=(9.0, 1.9 * n_panels + 1.2), layout="constrained")
    elif fig.axes:
        raise ValueError("the figure already has axes: pass an empty Figure")
    axes = list(fig.subplots(n_panels, 1, sharex=True, squeeze=False)[:, 0])
    t = traj.time
    titles = {"X": "displacements along x", "Y": "displacements along y", "th": "rotations"}
    for ax, (kind, present) in zip(axes, groups, strict=False):
        ax.set_label(kind)
        for name, color in zip(present, ("C0", "C3"), strict=False):
            tower = name[-1]
            ax.plot(t, traj.state[:, names.index(name)], color=color, lw=0.9,
                    label=f"tower {tower}: " + _HISTORY_SYMBOLS[kind].format(tower))
        ax.set_ylabel(_HISTORY_UNITS[kind])
        ax.legend(fontsize="small", frameon=False, loc="upper left", bbox_to_anchor=(1.0, 1.0),
                  title=titles[kind], title_fontsize="small", alignment="left")
    gap_ax, force_ax = axes[-2], axes[-1]
    gap_ax.set_label("clearance")
    gap_ax.plot(contact.time, contact.clearance, color="0.25", lw=0.9,
                label=r"$-d_{max}$")
    gap_ax.axhline(0.0, color="k", lw=0.5)
    imp = simulation.impacts
    in_window = (imp.time >= t[0]) & (imp.time <= t[-1])
    labels = np.asarray(imp.labels, dtype=object)
    for label, color in CORNER_COLORS.items():
        mask = in_window & (labels == label)
        if np.any(mask):
            gap_ax.plot(imp.time[mask], np.zeros(int(mask.sum())), ls="none", marker="v",
                        ms=6, color=color, label=f"impact {label}")
    gap_ax.set_ylabel(CLEARANCE_LABEL)
    gap_ax.set_title(f"clearance at the contact line, {int(in_window.sum())} impact onsets "
                     "marked", fontsize="medium", loc="left")
    gap_ax.legend(fontsize="small", frameon=False, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    force_ax.set_label("force")
    force_ax.plot(contact.time, contact.force, color="C2", lw=0.9, label="contact force")
    force_ax.set_ylabel(FORCE_LABEL)
    force_ax.set_title(f"contact force, peak {float(np.max(contact.force, initial=0.0)):.4g}",
                       fontsize="medium", loc="left")
    force_ax.set_xlabel(TIME_LABEL)
    force_ax.set_xlim(t[0], t[-1])
    period = simulation.period
    top = axes[0].secondary_xaxis("top", functions=(lambda x: x / period,
                                                    lambda k: k * period))
    top.set_xlabel("excitation cycles $t/T$")
    return fig


def plot_run(simulation: Simulation, contact: ContactHistory, *,
             fig: Figure | None = None) -> Figure:
    """A run at a glance: :func:`plot_time_histories` beside :func:`plot_phase_diagrams`.

    Parameters
    ----------
    simulation : Simulation
        A run of a scene with a dense trajectory.
    contact : ContactHistory
        :func:`chaospound.simulate.contact_history` of the same run.
    fig : Figure, optional
        An empty figure to draw into.

    Returns
    -------
    Figure
        With two subfigures: time histories (left) and phase diagrams (right).
    """
    panels = len(phase_panels(simulation.state_names))
    rows = 2 if panels == 4 else 1
    cols = 2 if panels == 4 else panels
    histories = 2 + sum(any(f"{k}_{w}" in simulation.state_names for w in "AB")
                        for k in HISTORY_PANELS[:3])
    if fig is None:
        height = max(1.9 * histories + 1.2, 4.3 * rows + 1.2)
        fig = Figure(figsize=(9.0 + 4.6 * cols, height), layout="constrained")
    elif fig.axes:
        raise ValueError("the figure already has axes: pass an empty Figure")
    left, right = fig.subfigures(1, 2, width_ratios=(9.0, 4.6 * cols), wspace=0.02)
    plot_time_histories(simulation, contact, fig=left)
    plot_phase_diagrams(simulation, fig=right)
    scene = simulation.scene
    left.suptitle(f"{scene.name}: time histories, cycles {simulation.transient}-"
                  f"{simulation.transient + simulation.record - 1}")
    right.suptitle("phase diagrams")
    return fig


# ================================================================ sections
def plot_strobe(section: Section, *, fig: Figure | None = None) -> Figure:
    """Points of a Poincare section in the panels of :func:`plot_phase_diagrams`.

    Stroboscopic sections are drawn in one colour; impact sections are
    coloured by corner label.

    Parameters
    ----------
    section : Section
        From :func:`~chaospound.dynamics.poincare.stroboscopic_section` or
        :func:`~chaospound.dynamics.poincare.impact_section`.
    fig : Figure, optional
        An empty figure to draw into.

    Returns
    -------
    Figure
    """
    panels = phase_panels(section.state_names)
    fig, axes = _panel_figure(fig, len(panels))
    names = section.state_names
    for ax, (title, position, rate) in zip(axes, panels, strict=True):
        x = section.states[:, names.index(position)]
        v = section.states[:, names.index(rate)]
        if section.labels is None:
            ax.scatter(x, v, s=10, color="C0", linewidths=0)
        else:
            _scatter_by_corner(ax, x, v, section.labels)
        _style_panel(ax, title, position, rate)
        _keep_visible_span(ax, x, v)
    if section.labels is not None and len(section):
        axes[0].legend(title="corner", fontsize="small", frameon=False)
    if section.kind == "stroboscopic":
        what = f"stroboscopic section at phase {section.phase:g} (t = (phase + k) T)"
    else:
        what = "impact section (state at onset)"
    span = f", cycles {int(section.cycles[0])}-{int(section.cycles[-1])}" if len(section) else ""
    fig.suptitle(f"{what}: {len(section)} points{span}, {section.model} model")
    return fig


# ============================================================== impact map
def plot_impact_map(impact_map: ImpactMap, *, fig: Figure | None = None) -> Figure:
    """The impact sequence (phase_n, V_n) and the return maps of velocity and phase.

    Left: every impact at its phase and velocity, coloured by corner. Middle:
    the pairs (V_n, V_{n+1}) coloured by the corner of impact n, with the
    diagonal V_{n+1} = V_n (a period-1 impact sequence sits on it). Right: the
    pairs (phase_n, phase_{n+1}), same colours.

    Parameters
    ----------
    impact_map : ImpactMap
    fig : Figure, optional
        An empty figure to draw into.

    Returns
    -------
    Figure
    """
    fig, axes = _panel_figure(fig, 3)
    sequence, ret, phase_ret = axes
    labels = impact_map.labels
    _scatter_by_corner(sequence, impact_map.phase, impact_map.velocity, labels)
    sequence.set_xlim(0.0, 1.0)
    sequence.set_xlabel(PHASE_LABEL)
    sequence.set_ylabel(VELOCITY_LABEL)
    sequence.set_title(f"impact sequence ({len(impact_map)} impacts)")
    pairs = impact_map.velocity_pairs
    _scatter_by_corner(ret, pairs[:, 0], pairs[:, 1], labels[: pairs.shape[0]])
    if pairs.shape[0]:
        low, high = float(pairs.min()), float(pairs.max())
        pad = 0.05 * max(high - low, 1e-3 * max(abs(high), 1.0))
        ret.plot(
            [low - pad, high + pad],
            [low - pad, high + pad],
            ls="--",
            color="0.5",
            lw=0.8,
            label="$V_{n+1} = V_n$",
        )
    ret.set_xlabel(r"$V_n/(A_g\,\omega_{Ax})$")
    ret.set_ylabel(r"$V_{n+1}/(A_g\,\omega_{Ax})$")
    ret.set_title(r"return map $V_n \to V_{n+1}$ (colour: corner $n$)")
    phase_pairs = impact_map.phase_pairs
    _scatter_by_corner(phase_ret, phase_pairs[:, 0], phase_pairs[:, 1],
                       labels[: phase_pairs.shape[0]])
    phase_ret.plot([0.0, 1.0], [0.0, 1.0], ls="--", color="0.5", lw=0.8,
                   label=r"$\varphi_{n+1} = \varphi_n$")
    phase_ret.set_xlim(0.0, 1.0)
    phase_ret.set_ylim(0.0, 1.0)
    phase_ret.set_aspect("equal")
    phase_ret.set_xlabel(r"phase $\varphi_n$ of impact $n$ (fraction of $T$)")
    phase_ret.set_ylabel(r"phase $\varphi_{n+1}$ (fraction of $T$)")
    phase_ret.set_title(r"return map $\varphi_n \to \varphi_{n+1}$")
    for ax in axes:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="small", frameon=False)
    if not len(impact_map):
        for ax in axes:
            ax.text(0.5, 0.5, "no impacts", transform=ax.transAxes, ha="center", va="center")
    fig.suptitle(f"impact map, {impact_map.model} model")
    return fig


# ================================================================ lyapunov
def plot_lyapunov_convergence(
    spectrum: Spectrum,
    two_trajectory: LargestExponent | None = None,
    *,
    ax: Axes | None = None,
    scene: str | None = None,
) -> Figure:
    """Running Lyapunov estimates against the number of cycles averaged.

    Each exponent's running estimate (``spectrum.history``) is drawn with its
    final value (dotted) and a band of +- one standard error, each in its own
    colour (:data:`EXPONENT_COLORS`, 16 distinct); the right axis gives the same
    values per excitation cycle (times T). The two-trajectory estimate of the
    largest exponent, if given, is drawn dashed in black. On a new figure the
    legend goes under the axes, in columns, so that the curves take the width.

    Parameters
    ----------
    spectrum : Spectrum
    two_trajectory : LargestExponent, optional
    ax : Axes, optional
    scene : str, optional
        What was run (e.g. ``"fig4, T/T_Ax = 0.9, towers model"``), named in the title.

    Returns
    -------
    Figure
    """
    own_figure = ax is None
    fig, ax = _single_axes(ax)
    period = spectrum.period
    cycles = np.arange(1, spectrum.history.shape[0] + 1)
    for i, (value, error) in enumerate(zip(spectrum.exponents, spectrum.errors, strict=True)):
        color = EXPONENT_COLORS[i % len(EXPONENT_COLORS)]
        ax.plot(
            cycles,
            spectrum.history[:, i],
            color=color,
            lw=1.0,
            label=rf"$\lambda_{{{i + 1}}}$ = {value:.4g} $\pm$ {error:.2g}",
        )
        ax.axhline(value, color=color, ls=":", lw=0.8)
        ax.axhspan(value - error, value + error, color=color, alpha=0.15, lw=0)
    if two_trajectory is not None:
        steps = np.arange(1, two_trajectory.history.shape[0] + 1)
        ax.plot(
            steps,
            two_trajectory.history,
            color="k",
            ls="--",
            lw=1.0,
            label=f"two trajectories: {two_trajectory.exponent:.4g} "
            rf"$\pm$ {two_trajectory.error:.2g}",
        )
        ax.axhspan(
            two_trajectory.exponent - two_trajectory.error,
            two_trajectory.exponent + two_trajectory.error,
            color="k",
            alpha=0.1,
            lw=0,
        )
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlim(1, max(int(cycles[-1]) if cycles.size else 1, 2))
    ax.set_xlabel(
        f"excitation cycles averaged (after {spectrum.transient} + "
        f"{spectrum.tangent_transient} transient)"
    )
    ax.set_ylabel(EXPONENT_LABEL)
    right = ax.secondary_yaxis(
        "right", functions=(lambda lam: lam * period, lambda lam: lam / period)
    )
    right.set_ylabel(r"$\lambda T$ (per excitation cycle)")
    ax.set_ylim(*_converged_range(spectrum, two_trajectory))
    entries = len(ax.get_legend_handles_labels()[0])
    if own_figure:
        fig.legend(fontsize="small", loc="outside lower center", ncols=min(entries, 4),
                   frameon=False)
    else:
        ax.legend(fontsize="x-small", loc="best", frameon=False)
    total = float(spectrum.exponents.sum())
    what = f"{scene}: " if scene else ""
    ax.set_title(
        f"{what}Lyapunov exponents (band: $\\pm$1 s.e.), sum {total:.4g}, "
        f"trace {spectrum.trace:.4g}",
        fontsize="medium",
    )
    return fig


def _converged_range(spectrum: Spectrum, two: LargestExponent | None) -> tuple[float, float]:
    """y-range showing the last 80 % of the running estimates, the bands and zero."""
    skip = spectrum.history.shape[0] // 5
    values = [
        spectrum.history[skip:].ravel(),
        spectrum.exponents - spectrum.errors,
        spectrum.exponents + spectrum.errors,
        np.zeros(1),
    ]
    if two is not None:
        values += [
            two.history[two.history.shape[0] // 5 :],
            np.array([two.exponent - two.error, two.exponent + two.error]),
        ]
    finite = np.concatenate(values)
    finite = finite[np.isfinite(finite)]
    low, high = float(finite.min()), float(finite.max())
    pad = 0.08 * max(high - low, 1e-12)
    return low - pad, high + pad


# ============================================================ bifurcation
def plot_bifurcation(
    parameter_values: Sequence[float] | np.ndarray,
    impact_velocities_per_point: Sequence[Sequence[float] | np.ndarray],
    regimes: Sequence[str] | None = None,
    exponents: Sequence[float] | np.ndarray | None = None,
    ax: Axes | Sequence[Axes] | None = None,
    *,
    parameter_label: str = PERIOD_RATIO_LABEL,
    exponent_errors: Sequence[float] | np.ndarray | None = None,
) -> Figure:
    """Impact velocity against a swept parameter (the paper's Figs. 4 and 5).

    Parameters
    ----------
    parameter_values : sequence of float (m,)
        The swept parameter at each point (e.g. T/T_Ax).
    impact_velocities_per_point : sequence of m sequences
        The impact velocities of each point's record window (any length,
        empty for no impact).
    regimes : sequence of m str, optional
        Regime label of each point ("periodic 1-1", "chaotic", ...); points
        are coloured by the label's first word (:data:`REGIME_COLORS`).
    exponents : sequence of m float, optional
        Largest Lyapunov exponent of each point (per unit normalised time;
        NaN: unknown): drawn in a second panel below.
    ax : Axes, or a pair of Axes with ``exponents``, optional
    parameter_label : str
        Label of the swept parameter's axis.
    exponent_errors : sequence of m float, optional
        Standard error of each exponent: error bars on the exponent panel.

    Returns
    -------
    Figure
    """
    values = np.asarray(parameter_values, dtype=float).reshape(-1)
    m = values.size
    if len(impact_velocities_per_point) != m:
        raise ValueError(
            f"impact_velocities_per_point has {len(impact_velocities_per_point)} "
            f"entries for {m} parameter values"
        )
    if regimes is not None and len(regimes) != m:
        raise ValueError(f"regimes has {len(regimes)} entries for {m} parameter values")
    lam = None
    if exponents is not None:
        lam = np.asarray(exponents, dtype=float).reshape(-1)
        if lam.size != m:
            raise ValueError(f"exponents has {lam.size} entries for {m} parameter values")
    fig, axes = _bifurcation_axes(ax, lam is not None)
    top = axes[0]
    categories = (
        ["all"] * m
        if regimes is None
        else [str(r).split()[0] if str(r).split() else "unknown" for r in regimes]
    )
    colors = _category_colors(categories)
    for category in dict.fromkeys(categories):
        xs, vs = [], []
        for value, velocities, cat in zip(
            values, impact_velocities_per_point, categories, strict=True
        ):
            if cat == category:
                v = np.asarray(velocities, dtype=float).reshape(-1)
                xs.append(np.full(v.size, value))
                vs.append(v)
        x, v = np.concatenate(xs), np.concatenate(vs)
        if x.size == 0:
            continue  # e.g. "none": no impact to draw (its rug below)
        top.scatter(
            x,
            v,
            s=9,
            marker=".",
            linewidths=0,
            color=colors[category],
            label=None if regimes is None else category,
        )
    silent = values[[np.asarray(v).size == 0 for v in impact_velocities_per_point]]
    if silent.size:  # points without an impact: a rug on the axis, so none goes unseen
        top.plot(silent, np.full(silent.size, 0.02), ls="none", marker="|", ms=8, mew=1,
                 color=colors.get("none", "0.5"), transform=top.get_xaxis_transform(),
                 label=f"no impact ({silent.size} points)")
    _full_range(top, values)
    top.set_ylabel(VELOCITY_LABEL)
    top.set_xlabel(parameter_label)
    if regimes is not None or silent.size:
        top.legend(fontsize="small", markerscale=3, frameon=False)
    if lam is not None:
        bottom = axes[1]
        _full_range(bottom, values)
        point_colors = [colors[c] for c in categories]
        finite = np.isfinite(lam)
        bottom.plot(values[finite], lam[finite], color="0.6", lw=0.6)
        bottom.scatter(
            values[finite],
            lam[finite],
            s=10,
            linewidths=0,
            c=[point_colors[i] for i in np.nonzero(finite)[0]],
        )
        _exponent_error_bars(bottom, values, lam, exponent_errors, color="0.35")
        bottom.axhline(0.0, color="k", lw=0.5)
        bottom.set_ylabel(r"$\lambda_1/\omega_{Ax}$")
        bottom.set_xlabel(parameter_label)
        top.set_xlabel("")
    return fig


def _full_range(ax: Axes, values: np.ndarray) -> None:
    """The x axis spans every swept value (the points without impacts too), with a 2 % margin."""
    finite = values[np.isfinite(values)]
    if finite.size and finite.max() > finite.min():
        pad = 0.02 * (finite.max() - finite.min())
        ax.set_xlim(finite.min() - pad, finite.max() + pad)


# ============================================================= hysteresis
#: marker and colour of each continuation branch: the marker points the way it went
BRANCH_STYLES = {
    "forward": {"marker": ">", "color": "C0", "arrow": "\u2192", "way": "increasing"},
    "backward": {"marker": "<", "color": "C3", "arrow": "\u2190", "way": "decreasing"},
}


def plot_hysteresis(
    parameter_values: Sequence[float] | np.ndarray,
    branches: dict[str, Sequence[Sequence[float] | np.ndarray]],
    exponents: dict[str, Sequence[float] | np.ndarray] | None = None,
    ax: Axes | Sequence[Axes] | None = None,
    *,
    parameter_label: str = PERIOD_RATIO_LABEL,
    exponent_errors: dict[str, Sequence[float] | np.ndarray] | None = None,
) -> Figure:
    """Forward and backward continuation overlaid on one axis (coexisting responses).

    Each branch's impact velocities are drawn with a triangle pointing the way
    the continuation went (forward ``>`` in blue, backward ``<`` in red), so
    where the branches differ the response is hysteretic. Points of a branch
    without an impact are marked as a rug of ticks at the bottom of the axis,
    one row per branch, instead of leaving the axis empty there.

    Parameters
    ----------
    parameter_values : sequence of float (m,)
    branches : dict
        ``{"forward": velocities per point, "backward": ...}`` (m entries each).
    exponents : dict, optional
        The largest exponent per point of each branch: a second panel below.
    ax : Axes, or a pair of Axes with ``exponents``, optional
    parameter_label : str
    exponent_errors : dict, optional
        The standard error of each branch's exponents: error bars.

    Returns
    -------
    Figure
    """
    values = np.asarray(parameter_values, dtype=float).reshape(-1)
    for name, per_point in branches.items():
        if name not in BRANCH_STYLES:
            raise ValueError(f"branch {name!r}: expected forward or backward")
        if len(per_point) != values.size:
            raise ValueError(f"branch {name}: {len(per_point)} entries for {values.size} "
                             "parameter values")
    fig, axes = _bifurcation_axes(ax, exponents is not None)
    top = axes[0]
    rug = top.get_xaxis_transform()  # x in data, y in axes fraction
    for row, (name, per_point) in enumerate(branches.items()):
        style = BRANCH_STYLES[name]
        counts = np.array([np.asarray(v).size for v in per_point])
        x = np.repeat(values, counts)
        v = (np.concatenate([np.asarray(p, dtype=float).reshape(-1) for p in per_point])
             if counts.sum() else np.zeros(0))
        top.scatter(x, v, s=16, marker=style["marker"], color=style["color"], alpha=0.75,
                    linewidths=0,
                    label=f"{name} {style['arrow']} ({style['way']} {parameter_label})")
        silent = values[counts == 0]
        if silent.size:
            top.plot(silent, np.full(silent.size, 0.02 + 0.035 * row), ls="none",
                     marker="|", ms=8, mew=1.5, color=style["color"], transform=rug,
                     label=f"{name}: no impact ({silent.size} points)")
    top.set_ylabel(VELOCITY_LABEL)
    top.set_xlabel(parameter_label)
    top.legend(fontsize="small", markerscale=1.5, frameon=False)
    if exponents is not None:
        bottom = axes[1]
        for name, lam in exponents.items():
            style = BRANCH_STYLES[name]
            lam = np.asarray(lam, dtype=float).reshape(-1)
            finite = np.isfinite(lam)
            bottom.plot(values[finite], lam[finite], color=style["color"], lw=0.7,
                        marker=style["marker"], ms=4, label=name)
            _exponent_error_bars(bottom, values, lam, (exponent_errors or {}).get(name),
                                 color=style["color"])
        bottom.axhline(0.0, color="k", lw=0.5)
        bottom.set_ylabel(r"$\lambda_1/\omega_{Ax}$")
        bottom.set_xlabel(parameter_label)
        top.set_xlabel("")
    return fig


# ========================================================= exponent map
#: colour of the points of an exponent map without an exponent (failed, pending)
MISSING_COLOR = "0.75"


def plot_exponent_map(
    x_values: Sequence[float] | np.ndarray,
    y_values: Sequence[float] | np.ndarray,
    exponents: np.ndarray,
    ax: Axes | None = None,
    *,
    missing: np.ndarray | None = None,
    x_label: str = PERIOD_RATIO_LABEL,
    y_label: str = "",
    colorbar: bool = True,
) -> Figure:
    """The largest Lyapunov exponent over two parameters, as a colour map.

    A diverging colour map centred on zero (``RdBu_r`` with a
    :class:`~matplotlib.colors.TwoSlopeNorm`: blue negative, white zero, red
    positive, symmetric about zero up to the largest |lambda|); points without an exponent
    (NaN, or ``missing``: failed or pending) are masked and drawn grey
    (:data:`MISSING_COLOR`). The mesh's array (``ax.collections[0].get_array()``)
    is the masked ``exponents.T`` (rows: the second parameter).

    Parameters
    ----------
    x_values : sequence of float (nx,)
        The first parameter (x axis).
    y_values : sequence of float (ny,)
        The second parameter (y axis).
    exponents : array (nx, ny)
        Largest exponent per point, per unit normalised time ``t = tau omega_Ax``.
    ax : Axes, optional
    missing : bool array (nx, ny), optional
        Points to mask besides the NaN ones.
    x_label, y_label : str
    colorbar : bool
        Draw a colour bar labelled with the exponent's unit.

    Returns
    -------
    Figure
    """
    from matplotlib.colors import TwoSlopeNorm

    x = np.asarray(x_values, dtype=float).reshape(-1)
    y = np.asarray(y_values, dtype=float).reshape(-1)
    lam = np.asarray(exponents, dtype=float)
    if lam.shape != (x.size, y.size):
        raise ValueError(f"exponents has shape {lam.shape}, expected {(x.size, y.size)}")
    mask = ~np.isfinite(lam)
    if missing is not None:
        mask |= np.asarray(missing, dtype=bool).reshape(lam.shape)
    data = np.ma.masked_array(np.where(mask, 0.0, lam), mask=mask)
    fig, ax = _single_axes(ax)
    shown = data.compressed()
    low = float(shown.min()) if shown.size else -1.0
    high = float(shown.max()) if shown.size else 1.0
    scale = max(abs(low), abs(high), 1e-12)
    # symmetric: the same |lambda| has the same strength of colour on both sides, so a
    # barely positive exponent is never drawn as deep red
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-scale, vmax=scale)
    cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad=MISSING_COLOR)
    mesh = ax.pcolormesh(cell_edges(x), cell_edges(y), data.T, cmap=cmap, norm=norm,
                         edgecolors="face")
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)
    if colorbar:
        bar = ax.figure.colorbar(mesh, ax=ax)
        bar.set_label(EXPONENT_LABEL)
    n_missing = int(mask.sum())
    ax.set_title("largest Lyapunov exponent" + (f" ({n_missing} points without, grey)"
                                                if n_missing else ""), fontsize="medium")
    return fig


# ========================================================== orbit diagram
def plot_orbit_diagram(
    parameter_values: Sequence[float] | np.ndarray,
    states_per_point: Sequence[np.ndarray],
    ax: Axes | None = None,
    *,
    regimes: Sequence[str] | None = None,
    parameter_label: str = PERIOD_RATIO_LABEL,
    state_label: str = "",
    color: str | None = None,
    marker: str = "o",
    label: str | None = None,
) -> Figure:
    """The classical bifurcation (orbit) diagram: a state component at a section
    against the swept parameter.

    Every point's section values (e.g. one component of its stroboscopic states)
    are drawn at its parameter value in one scatter, in point order, so that
    ``ax.collections[-1].get_offsets()[:, 1]`` is the concatenation of
    ``states_per_point``. A periodic response of period k shows k dots, a
    chaotic one a vertical smear.

    Parameters
    ----------
    parameter_values : sequence of float (m,)
    states_per_point : sequence of m 1-d arrays
        The component's values at each point's section crossings (any length).
    ax : Axes, optional
    regimes : sequence of m str, optional
        Colour each point by its regime's first word (:data:`REGIME_COLORS`).
    parameter_label, state_label : str
        Axis labels.
    color : str, optional
        One colour for all points (instead of ``regimes``).
    marker : str
    label : str, optional
        Legend entry of the scatter.

    Returns
    -------
    Figure
    """
    values = np.asarray(parameter_values, dtype=float).reshape(-1)
    if len(states_per_point) != values.size:
        raise ValueError(f"states_per_point has {len(states_per_point)} entries for "
                         f"{values.size} parameter values")
    if regimes is not None and len(regimes) != values.size:
        raise ValueError(f"regimes has {len(regimes)} entries for {values.size} values")
    fig, ax = _single_axes(ax)
    per_point = [np.asarray(v, dtype=float).reshape(-1) for v in states_per_point]
    counts = np.array([v.size for v in per_point], dtype=int)
    x = np.repeat(values, counts)
    y = np.concatenate(per_point) if per_point and counts.sum() else np.zeros(0)
    if color is None and regimes is not None:
        categories = [str(r).split()[0] if str(r).split() else "unknown" for r in regimes]
        colors = _category_colors(categories)
        point_colors = [colors[c] for c, n in zip(categories, counts, strict=True)
                        for _ in range(n)]
    else:
        point_colors = color or "k"
    ax.scatter(x, y, s=8, marker=marker, linewidths=0,
               c=point_colors if len(x) else None, label=label)
    if regimes is not None and color is None:
        from matplotlib.lines import Line2D

        present = dict.fromkeys(c for c, n in zip(categories, counts, strict=True) if n)
        ax.legend(handles=[Line2D([], [], ls="none", marker="o", ms=4, color=colors[c],
                                  label=c) for c in present],
                  fontsize="small", frameon=False)
    _full_range(ax, values)
    ax.set_xlabel(parameter_label)
    ax.set_ylabel(state_label)
    return fig


def _exponent_error_bars(ax: Axes, values: np.ndarray, lam: np.ndarray, errors,
                         color: str) -> None:
    """Error bars (+- one standard error) on the finite exponents that have an error."""
    if errors is None:
        return
    err = np.asarray(errors, dtype=float).reshape(-1)
    if err.size != lam.size:
        raise ValueError(f"exponent errors has {err.size} entries for {lam.size} exponents")
    keep = np.isfinite(lam) & np.isfinite(err)
    if np.any(keep):
        ax.errorbar(values[keep], lam[keep], yerr=err[keep], fmt="none", ecolor=color,
                    elinewidth=0.7, capsize=2.0, label="_exponent errors")


def cell_edges(values: np.ndarray) -> np.ndarray:
    """Cell edges around grid values (midpoints; one value: +-5 %)."""
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        half = 0.05 * abs(v[0]) or 0.5
        return np.array([v[0] - half, v[0] + half])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate(([v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]))


# ==================================================================== save
#: the raster formats :func:`save` writes pixel by pixel (matplotlib's Agg backend)
RASTER_FORMATS = ("png", "jpg", "jpeg", "tif", "tiff", "webp", "raw", "rgba")
MAX_RASTER_SIDE = 32768  #: pixels a side at most (Agg refuses 65536)
MAX_RASTER_PIXELS = 2e8  #: pixels in all at most (0.8 GB of RGBA)


def save(fig: Figure, path: str | os.PathLike[str], *, dpi: float = 150) -> None:
    """Write a figure atomically: a temporary file in the same folder, then a rename.

    The format follows the extension (``.png``, ``.pdf``, ``.svg``, ...).
    Nothing is left behind when writing fails.

    Raises
    ------
    FileNotFoundError
        The target's folder does not exist.
    ValueError
        An unknown format (from matplotlib), or a raster image larger than
        :data:`MAX_RASTER_SIDE` pixels on a side or :data:`MAX_RASTER_PIXELS` in all.
    """
    path = os.fspath(path)
    extension = os.path.splitext(path)[1].lstrip(".").lower() or "png"
    if extension in RASTER_FORMATS:
        width, height = (float(v) * float(dpi) for v in fig.get_size_inches())
        if max(width, height) > MAX_RASTER_SIDE or width * height > MAX_RASTER_PIXELS:
            raise ValueError(
                f"a {width:.0f} x {height:.0f} pixel image is too large to write "
                f"(at most {MAX_RASTER_SIDE} pixels a side and {MAX_RASTER_PIXELS:.0e} in "
                f"all): lower the size or the dpi, or write .pdf or .svg")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise FileNotFoundError(f"cannot save figure to {path!r}: folder {folder!r} does not exist")
    if os.path.isdir(path):
        raise IsADirectoryError(f"cannot save figure to {path!r}: it is a directory")
    handle, temporary = tempfile.mkstemp(dir=folder, prefix=".chaospound-", suffix=".tmp")
    try:
        os.chmod(temporary, _new_file_mode())
        with os.fdopen(handle, "wb") as stream:
            fig.savefig(stream, format=extension, dpi=dpi)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


# ======================================================= continued branches
#: marker of each kind of special point on a continued branch (chaospound.orbits)
SPECIAL_MARKERS = {"fold": ("o", "k"), "period-doubling": ("s", "C3"),
                   "neimark-sacker": ("D", "C1"), "grazing": ("^", "C2"),
                   "corner-change": ("v", "C4")}


def _runs(stable: np.ndarray, impacts: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of the runs of equal (stability, impacts per period), stops exclusive.

    A run is extended by one point into the next when only the stability changes, so
    that solid and dashed parts join; where the impacts per period change (a grazing)
    the curves are cut, since the impacts' order differs on the two sides.
    """
    key = stable.astype(np.int64) + 2 * impacts.astype(np.int64)
    edges = [0, *(np.nonzero(key[1:] != key[:-1])[0] + 1), key.size]
    runs = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        joined = b < key.size and impacts[b] == impacts[b - 1]
        runs.append((a, b + 1 if joined else b))
    return runs


def plot_branches(branches, ax: Axes | None = None, *, over=None,
                  parameter_label_text: str | None = None) -> Figure:
    """Bifurcation diagram of continued branches: impact velocities against the parameter.

    Every impact of a period (k forcing cycles) is one curve: stable parts
    solid, unstable parts dashed; special points (fold, period doubling,
    Neimark-Sacker, grazing, corner change) marked. A branch without impacts
    draws the first state component at the section instead (right axis label
    says so). Optionally over a brute-force sweep's impact velocities (grey).

    Parameters
    ----------
    branches : sequence of chaospound.orbits.continuation.Branch
    ax : Axes, optional
    over : chaospound.store.SweepFile, optional
        A sweep of the same parameter, drawn underneath (every branch of it).
    parameter_label_text : str, optional
        x label (default: the parameter's symbol).

    Returns
    -------
    Figure
    """
    fig, ax = _single_axes(ax)
    name = branches[0].parameter if branches else ""
    if over is not None:
        grid = over.grid[over.parameters[0]]
        for b, marker in zip(over.branches, ("o", ">", "<"), strict=False):
            vel = over.impact_velocities(b)
            counts = np.array([v.size for v in vel])
            if counts.sum():
                ax.scatter(np.repeat(grid, counts), np.concatenate(vel), s=8, marker=marker,
                           color="0.6", alpha=0.6, linewidths=0, zorder=1,
                           label=f"sweep ({b})")
    any_impacts = any(int(o.impacts_per_period) for br in branches for o in br.orbits)
    for number, br in enumerate(branches):
        color = f"C{number % 10}"
        lam = br.values
        stable = br.stable
        if any_impacts:
            width = max(int(o.impacts_per_period) for o in br.orbits) or 1
            curves = np.full((len(br), width), np.nan)
            for i, o in enumerate(br.orbits):
                curves[i, :o.impacts_per_period] = o.impact_velocity
            _follow_curves(curves)
        else:
            curves = br.states[:, :1]
        labelled = False
        for a, b in _runs(stable, br.impacts_per_period):
            style = "-" if stable[a] else "--"
            for c in range(curves.shape[1]):
                label = None
                if not labelled:
                    label = f"{br.name or f'period-{br.period}'}"
                    labelled = True
                ax.plot(lam[a:b], curves[a:b, c], ls=style, color=color, lw=1.2, zorder=2,
                        label=label)
        for sp in br.special:
            marker, mcolor = SPECIAL_MARKERS.get(sp.kind, ("x", "k"))
            ys = (sp.orbit.impact_velocity if any_impacts else sp.orbit.state[:1])
            ys = ys if np.size(ys) else np.zeros(1)
            ax.scatter(np.full(np.size(ys), sp.value), ys, marker=marker, s=36,
                       facecolors="none", edgecolors=mcolor, linewidths=1.3, zorder=3)
    for kind, (marker, mcolor) in SPECIAL_MARKERS.items():
        if any(sp.kind == kind for br in branches for sp in br.special):
            ax.scatter([], [], marker=marker, s=36, facecolors="none", edgecolors=mcolor,
                       label=kind)
    ax.plot([], [], "k-", lw=1.2, label="stable")
    ax.plot([], [], "k--", lw=1.2, label="unstable")
    ax.set_xlabel(parameter_label_text or parameter_label(name))
    if any_impacts:
        ax.set_ylabel(VELOCITY_LABEL)
    else:
        first = branches[0].orbits[0].state_names[0] if branches else "x"
        ax.set_ylabel(f"{axis_label(first)} at the section")
    ax.legend(fontsize="small", frameon=False)
    ax.set_label("branches")
    return fig


def _follow_curves(curves: np.ndarray) -> None:
    """Reorder each row's impacts to follow the previous row's, in place.

    An orbit lists its impacts in time from the section; where an impact crosses
    the section along the branch, the list rotates and "the j-th impact" jumps
    between two curves (a vertical line across the diagram). Between rows with
    the same number of impacts, the order that moves the values least (an
    assignment on |V_i - V_j|) keeps each curve on its own impact.
    """
    from scipy.optimize import linear_sum_assignment

    for i in range(1, curves.shape[0]):
        prev, row = curves[i - 1], curves[i]
        n = int(np.count_nonzero(~np.isnan(row)))
        if n < 2 or n != np.count_nonzero(~np.isnan(prev)):
            continue
        _, order = linear_sum_assignment(np.abs(prev[:n, None] - row[None, :n]))
        curves[i, :n] = row[:n][order]


def plot_multipliers(branches, ax: Axes | None = None) -> Figure:
    """Floquet multipliers along continued branches in the complex plane, with the unit
    circle; colour runs along each branch (parameter), special points ringed."""
    fig, ax = _single_axes(ax)
    theta = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(np.cos(theta), np.sin(theta), color="k", lw=0.8, label="unit circle")
    for br in branches:
        mu = br.multipliers
        lam = np.repeat(br.values, mu.shape[1])
        points = ax.scatter(mu.real.ravel(), mu.imag.ravel(), c=lam, s=6, cmap="viridis",
                            linewidths=0)
        for sp in br.special:
            marker, mcolor = SPECIAL_MARKERS.get(sp.kind, ("x", "k"))
            m = sp.orbit.multipliers
            ax.scatter(m.real, m.imag, marker=marker, s=36, facecolors="none",
                       edgecolors=mcolor, linewidths=1.2)
    if branches:
        fig.colorbar(points, ax=ax, label=parameter_label(branches[0].parameter))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(r"Re $\mu$")
    ax.set_ylabel(r"Im $\mu$")
    ax.set_title("Floquet multipliers")
    ax.set_label("multipliers")
    return fig


# ================================================================= helpers
def _new_file_mode() -> int:
    """Permissions of a newly created file (0o666 less the umask), not mkstemp's 0o600."""
    umask = os.umask(0o022)
    os.umask(umask)
    return 0o666 & ~umask


def phase_panels(state_names: Sequence[str]) -> list[tuple[str, str, str]]:
    """(title, position, velocity) of each phase-diagram panel of a model.

    The towers model gives four panels (X and theta of each tower), the
    reduced models the ones they have; other systems pair consecutive states.
    """
    names = tuple(state_names)
    panels = [p for p in _TOWER_PANELS if p[1] in names and p[2] in names]
    if panels:
        return panels
    if len(names) < 2:
        raise ValueError(f"need at least two states for a phase diagram, got {names}")
    starts = list(range(0, len(names) - 1, 2))
    if len(names) % 2:
        starts[-1] = len(names) - 2
    return [(f"{names[s]} vs {names[s + 1]}", names[s], names[s + 1]) for s in starts]


def parameter_label(name: str) -> str:
    """Axis label of a swept parameter: its symbol and unit (``"gap"`` -> ``$a/A_g$``);
    a name without an entry in :data:`PARAMETER_LABELS` is returned as is."""
    return PARAMETER_LABELS.get(name, name)


def axis_label(name: str) -> str:
    """Axis label with units for a state name ("X_A" -> "$X_A/A_g$", ...)."""
    match = _STATE_NAME.fullmatch(name)
    if match is None:
        return name
    rate, kind, tower = match.groups()
    if kind == "th":
        if rate:
            return rf"$\dot\theta_{tower}/\omega_{{Ax}}$ (rad)"
        return rf"$\theta_{tower}$ (rad)"
    if rate:
        return rf"$\dot {kind}_{tower}/(A_g\,\omega_{{Ax}})$"
    return rf"${kind}_{tower}/A_g$"


#: least span of a section panel's axis, relative to its values' size: points that
#: coincide to rounding (a periodic orbit's strobe) show as one dot, not as noise
#: magnified to fill the panel
MIN_RELATIVE_SPAN = 0.02


def _keep_visible_span(ax: Axes, x: np.ndarray, v: np.ndarray) -> None:
    """Widen an axis whose points span less than MIN_RELATIVE_SPAN of their size."""
    for values, set_lim, axis in ((x, ax.set_xlim, ax.xaxis), (v, ax.set_ylim, ax.yaxis)):
        values = np.asarray(values, dtype=float)
        values = values[np.isfinite(values)]
        if values.size == 0:
            continue
        low, high = float(values.min()), float(values.max())
        least = MIN_RELATIVE_SPAN * max(abs(low), abs(high), 1e-3)
        if high - low < least:
            centre = 0.5 * (low + high)
            set_lim(centre - least, centre + least)
            axis.get_major_formatter().set_useOffset(False)


def _style_panel(ax: Axes, title: str, position: str, rate: str) -> None:
    ax.set_title(title)
    ax.set_xlabel(axis_label(position))
    ax.set_ylabel(axis_label(rate))
    ax.xaxis.set_major_locator(MaxNLocator(nbins=6))


def _panel_figure(fig: Figure | None, n_panels: int) -> tuple[Figure, list[Axes]]:
    """A figure with n panels (2 x 2 for four, else one row), below a title and above a caption."""
    rows, cols = (2, 2) if n_panels == 4 else (1, n_panels)
    if fig is None:
        fig = Figure(figsize=(5.0 * cols, 4.3 * rows + 0.6), layout="constrained")
    elif fig.axes:
        raise ValueError("the figure already has axes: pass an empty Figure")
    grid = fig.subplots(rows, cols, squeeze=False)
    return fig, list(grid.ravel())


def _single_axes(ax: Axes | None) -> tuple[Figure, Axes]:
    if ax is None:
        fig = Figure(figsize=(10.0, 5.0), layout="constrained")
        return fig, fig.add_subplot()
    return ax.figure, ax


def _bifurcation_axes(ax, with_exponents: bool) -> tuple[Figure, list[Axes]]:
    if ax is None:
        if with_exponents:
            fig = Figure(figsize=(9.0, 7.0), layout="constrained")
            axes = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1))
            return fig, list(axes)
        fig = Figure(figsize=(9.0, 5.0), layout="constrained")
        return fig, [fig.add_subplot()]
    if isinstance(ax, Axes):
        if with_exponents:
            raise ValueError("exponents need a second panel: pass ax=(top, bottom) or no ax")
        return ax.figure, [ax]
    axes = list(ax)
    if len(axes) != (2 if with_exponents else 1):
        raise ValueError(f"ax: got {len(axes)} axes, need {2 if with_exponents else 1}")
    return axes[0].figure, axes


def _scatter_by_corner(ax: Axes, x: np.ndarray, v: np.ndarray, labels: Sequence[str]) -> None:
    labels = np.asarray(labels, dtype=object)
    for label, color in CORNER_COLORS.items():
        mask = labels == label
        if np.any(mask):
            ax.scatter(
                np.asarray(x)[mask],
                np.asarray(v)[mask],
                s=14,
                color=color,
                linewidths=0,
                label=label,
            )


def _category_colors(categories: Sequence[str]) -> dict[str, str]:
    colors: dict[str, str] = {}
    spare = iter(f"C{i}" for i in (4, 5, 6, 8, 9, 7) * 10)
    for category in dict.fromkeys(categories):
        colors[category] = REGIME_COLORS.get(category) or (
            "k" if category == "all" else next(spare)
        )
    return colors


def _trajectory(simulation, purpose: str) -> np.ndarray:
    """The run's dense trajectory, or a ValueError saying how to get one."""
    if simulation.trajectory is None:
        raise ValueError("the simulation has no trajectory: run simulate(scene, "
                         f"samples_per_cycle=N) with N > 0 (a few hundred) for {purpose}")
    return simulation.trajectory
