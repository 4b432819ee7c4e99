"""Stability at extreme parameters: a finite, consistent result or one clear error.

The grid of the issue: Hertz stiffness beta from 1 to 1e8, exponent chi in
{1, 1.5, 2, 3}, all six damping ratios 0 or 1, gap 0 (touching at rest),
T/T_Ax from 0.05 to 20 and e_Ay up to 0.5 l, on the presets fig3a (towers),
fig4-translational (pair), tower-wall and wall. Every steady run (40 + 8
cycles) must either

* return finite sections, final state and impact records that are
  consistent with docs/model.md section 8 (onset states on the contact surface
  with an end moving in, positive durations, non-negative peak penetrations
  and forces, episodes that do not overlap, impact times inside the record
  window with their phase and cycle), or
* raise :class:`SimulationError` with a one-line message carrying the
  numbers (the command line then exits with code 1 and that one line).

Invariants at the extremes: energy is conserved without damping and ground
motion for beta from 1 to 1e8; penetration follows the Hertz energy balance
at beta = 1e8; the forcing phase is exact after 1e4 (default) and 1e5 (slow)
impacting cycles. Invalid edge values are rejected with a one-line
:class:`SceneError` naming the parameter.

Default run (~20 s of CPU): each axis's extremes one at a time on every
preset, the corners of the grid (all extremes at once) except the slow
rattling ones, and cheap reproductions of the failures the full grid found
(section 5: they fail until the simulator is fixed). ``-m slow``: the full
factorial grid (``full_grid``), the energy sweep over beta and chi and the
1e5-cycle run. ``analysis/extremes.py`` runs the same cases (it imports the
definitions below) and writes results/extremes.md and .json.
"""

from __future__ import annotations

import functools
import itertools
import math
import os
import re
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from kernels_by_name import models

from chaospound.cli import main
from chaospound.engine.events import TIME_TOL
from chaospound.scene import SceneError, load_preset
from chaospound.simulate import Simulation, SimulationError, simulate

ROOT = Path(__file__).resolve().parents[1]

# ================================================================== the grid
#: preset -> model it runs with its own eccentricity
PRESETS = {"fig3a": "towers", "fig4-translational": "pair", "tower-wall": "tower-wall",
           "wall": "wall"}
BETAS = (1.0, 1e2, 1e4, 1e6, 1e8)
CHIS = (1.0, 1.5, 2.0, 3.0)
ZETAS = (0.0, 0.03, 1.0)  #: all six damping ratios; 0.03 is the presets' value
GAPS = (0.0, 1.0)  #: 1 is the presets' value
PERIOD_RATIOS = (0.05, 0.3, 0.7, 1.0, 2.0, 5.0, 20.0)
ECC_Y_RATIO = 0.5  #: e_Ay = 0.5 l, the largest eccentricity of the issue
GRID_KEYS = ("beta", "chi", "zeta", "gap", "period_ratio", "ecc_y_ratio_A")

#: one parameter at a time from each preset (the study's table)
ONE_AT_A_TIME = {
    "beta": BETAS,
    "chi": CHIS,
    "zeta": (0.0, 1.0),
    "gap": (0.0,),
    "period_ratio": (0.05, 0.3, 2.0, 5.0, 20.0),
    "ecc_y_ratio_A": (0.25, ECC_Y_RATIO),
}
#: the extremes of each axis (default run, one at a time)
EXTREMES = {
    "beta": (1.0, 1e8),
    "chi": (1.0, 3.0),
    "zeta": (0.0, 1.0),
    "gap": (0.0,),
    "period_ratio": (0.05, 20.0),
    "ecc_y_ratio_A": (ECC_Y_RATIO,),
}
#: corners of the grid: gap 0 and every other axis at an extreme
CORNERS = {"beta": (1.0, 1e8), "chi": (1.0, 3.0), "zeta": (0.0, 1.0),
           "period_ratio": (0.05, 20.0)}


def preset_grid_values(preset: str) -> dict[str, float]:
    """The grid parameters of a preset as it is shipped."""
    scene = load_preset(preset)
    return {
        "beta": scene.contact.beta,
        "chi": scene.contact.chi,
        "zeta": scene.tower_A.zeta_x,
        "gap": scene.gap,
        "period_ratio": scene.excitation.period_ratio,
        "ecc_y_ratio_A": scene.tower_A.ecc_y_ratio,  # the presets give e_Ay / l
    }


#: presets whose e_Ay = 0.5 l scenes are exactly another preset's (same packed
#: parameters: the presets differ only in e_Ay and T/T_Ax, which the grid sets)
SAME_AT_HALF_ECC = {"fig4-translational": "fig3a", "wall": "tower-wall"}


def full_grid(preset: str) -> list[dict[str, float]]:
    """The full factorial grid on one preset: 5 x 4 x 3 x 2 x 7 = 840 scenes per e_Ay.

    Eccentricity: the preset's own and 0.5 l, except for the presets of
    :data:`SAME_AT_HALF_ECC` (their e_Ay = 0.5 l scenes are run on the other
    preset): 1680 scenes for fig3a and tower-wall, 840 for the others.
    """
    eccs = [preset_grid_values(preset)["ecc_y_ratio_A"]]
    if preset not in SAME_AT_HALF_ECC:
        eccs = sorted(set(eccs) | {ECC_Y_RATIO})
    axes = (BETAS, CHIS, ZETAS, GAPS, PERIOD_RATIOS, eccs)
    return [dict(zip(GRID_KEYS, values, strict=True)) for values in itertools.product(*axes)]


def corner_grid() -> list[dict[str, float]]:
    """gap = 0 with beta, chi, zeta, T/T_Ax at their extremes (16 scenes)."""
    return [
        dict(zip(CORNERS, values, strict=True), gap=0.0)
        for values in itertools.product(*CORNERS.values())
    ]


def is_chatter_scene(flat: dict[str, float]) -> bool:
    """Stiff linear contact, touching at rest, quasi-static forcing.

    gap = 0, chi = 1, beta >= 1e6, T/T_Ax >= 5, damped: the towers lean on the
    contact with a static penetration far below atol and rattle on it (1e4 to
    1.3e5 impacts in 48 cycles); each such run takes 5 to 80 s of CPU.
    """
    return (flat.get("gap") == 0.0 and flat.get("chi") == 1.0 and flat.get("beta", 0.0) >= 1e6
            and flat.get("period_ratio", 0.0) >= 5.0 and flat.get("zeta", 0.03) > 0.0)


# ============================================================ one run, judged
@dataclass
class Outcome:
    """One run at extreme parameters and its verdict.

    ``status``: "finite" (result returned and consistent), "clear error" (a
    one-line SimulationError with numbers) or "FAIL" (anything else; the
    reasons are in ``problems``).
    """

    preset: str
    flat: dict
    model: str = ""
    status: str = ""
    problems: list = field(default_factory=list)
    message: str = ""
    impacts: int = 0
    steps: int = 0
    wall_s: float = 0.0
    cpu_s: float = 0.0  #: process CPU time (the cores are shared: wall time varies)
    max_abs_state: float = math.nan
    max_onset_gap: float = math.nan  #: max |d_max| over the onset states
    onset_gap_ratio: float = math.nan  #: the same in the units of ONSET_GAP_TOL
    min_velocity: float = math.nan  #: smallest recorded impact velocity V
    min_onset_rate: float = math.nan  #: smallest max rate of the ends at the surface
    min_peak_penetration: float = math.nan
    min_duration: float = math.nan
    cut_episodes: int = 0  #: impacts with NaN duration (cut by the end)

    def summary(self) -> str:
        """One line: preset, parameters, verdict."""
        flat = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                         for k, v in self.flat.items())
        text = f"{self.preset} [{flat}] ({self.model}): {self.status}"
        if self.message:
            text += f": {self.message}"
        if self.problems:
            text += " -- " + "; ".join(self.problems)
        return text


def run_case(preset: str, flat: dict, transient: int | None = None,
             record: int | None = None) -> Outcome:
    """Run one scene and judge the result (never raises for a numerical failure)."""
    out = Outcome(preset=preset, flat=dict(flat))
    scene = load_preset(preset).with_params(**flat)
    out.model = scene.model_name
    transient = scene.run.transient if transient is None else transient
    record = scene.run.record if record is None else record
    start, cpu = time.perf_counter(), time.process_time()
    try:
        sim = simulate(scene, transient=transient, record=record)
    except SimulationError as exc:
        out.wall_s = time.perf_counter() - start
        out.cpu_s = time.process_time() - cpu
        out.message = str(exc)
        out.problems = error_problems(str(exc), transient + record)
        out.status = "FAIL" if out.problems else "clear error"
        return out
    except Exception as exc:  # noqa: BLE001 - anything else is a failure to report
        out.wall_s = time.perf_counter() - start
        out.cpu_s = time.process_time() - cpu
        out.message = f"{type(exc).__name__}: {exc}"
        out.problems = ["raised " + type(exc).__name__ + " instead of SimulationError"]
        out.status = "FAIL"
        return out
    out.wall_s = time.perf_counter() - start
    out.cpu_s = time.process_time() - cpu
    out.problems = simulation_problems(sim, transient, record, out)
    out.status = "FAIL" if out.problems else "finite"
    return out


#: |d_max| allowed at a recorded onset, in units of (rtol + TIME_TOL) S + atol with
#: S = max(1, |state|): the onset is located on the step's interpolant to TIME_TOL
#: in time (times a velocity <= S) and the step is then redone to land on it, so
#: the landed state misses the surface by about the local error
#: (measured up to 2.4 units at rtol 1e-6; <= 3e-11 absolute at rtol 1e-10)
ONSET_GAP_TOL = 10.0


def onset_tolerance(scene, states: np.ndarray) -> float:
    """Allowed |d_max| at the recorded onsets of a run."""
    solver = scene.solver
    size = max(1.0, float(np.max(np.abs(states)))) if states.size else 1.0
    return ONSET_GAP_TOL * ((solver.rtol + TIME_TOL) * size + solver.atol)


def simulation_problems(sim: Simulation, transient: int, record: int,
                        out: Outcome | None = None) -> list[str]:
    """What is wrong with a returned run (empty: finite and consistent)."""
    problems: list[str] = []
    scene = sim.scene
    imp = sim.impacts
    period = scene.period
    t0 = scene.run.phase * period
    n = len(imp)
    states = [sim.strobe.state, sim.final_state[None, :]]
    if n:
        states.append(imp.state)
    stacked = np.vstack(states)
    finite_state = bool(np.all(np.isfinite(stacked)))
    if out is not None:
        out.impacts = n
        out.steps = sim.stats.steps
        out.max_abs_state = float(np.max(np.abs(stacked))) if finite_state else math.inf
    if not finite_state:
        problems.append("non-finite section, final or onset state")
    if sim.strobe.state.shape[0] != record + 1:
        problems.append(f"{sim.strobe.state.shape[0]} sections for {record} cycles")
    expected = t0 + np.arange(transient, transient + record + 1) * period
    if not np.array_equal(sim.strobe.time, expected):
        problems.append("section times are not phase T + k T")
    if n == 0:
        return problems
    for name in ("time", "phase", "velocity", "contact_y", "peak_penetration", "peak_force"):
        values = getattr(imp, name)
        if not np.all(np.isfinite(values)):
            problems.append(f"non-finite impact {name}: {values[~np.isfinite(values)][:3]}")
    duration = imp.duration
    cut = np.isnan(duration)
    if np.any(cut[:-1]):
        rows = np.flatnonzero(cut[:-1])[:5]
        problems.append(f"NaN duration before the last impact (rows {rows})")
    done = duration[~cut]
    if np.any(~np.isfinite(done)) or np.any(done <= 0.0):
        rows = np.flatnonzero(~cut & ~(duration > 0.0))
        problems.append(f"{len(rows)} impacts with duration <= 0 or inf (rows {rows[:5]}, "
                        f"durations {duration[rows[:3]]}, peak penetrations "
                        f"{imp.peak_penetration[rows[:3]]})")
    if np.any(imp.peak_penetration < 0.0) or np.any(imp.peak_force < 0.0):
        problems.append("negative peak penetration or force")
    # onset states lie on the contact surface
    mid, p = scene.model_id(), scene.pack()
    ends = np.empty(4)
    d_on = np.empty(n)
    rate_on = np.empty(n)  # fastest penetration rate among the ends at the surface
    on_tol = onset_tolerance(scene, imp.state)
    for i in range(n):
        models.contact_ends(mid, imp.time[i] - imp.cycle[i] * period, imp.state[i], p, ends)
        d_on[i] = max(ends[0], ends[1])
        at_surface = [ends[2 + e] for e in (0, 1) if ends[e] >= d_on[i] - on_tol]
        rate_on[i] = max(at_surface)
    worst = int(np.argmax(np.abs(d_on)))
    if abs(d_on[worst]) > on_tol:
        bad = np.flatnonzero(np.abs(d_on) > on_tol)
        problems.append(
            f"{len(bad)} impacts recorded off the contact surface (|d_max| > {on_tol:.2g}): "
            f"d_max = {d_on[worst]:.3g} "
            f"at the onset of impact {worst} (t = {imp.time[worst]:.10g}, V = "
            f"{imp.velocity[worst]:.3g}, duration {imp.duration[worst]:.3g}, peak penetration "
            f"{imp.peak_penetration[worst]:.3g})"
        )
    # ... and an end there is moving in: d_max crosses 0 upwards (same slack, per unit time)
    slowest = int(np.argmin(rate_on))
    if rate_on[slowest] < -on_tol:
        bad = np.flatnonzero(rate_on < -on_tol)
        problems.append(
            f"{len(bad)} onsets where no end at the surface moves in: penetration rate "
            f"{rate_on[slowest]:.3g} at the onset of impact {slowest} (t = "
            f"{imp.time[slowest]:.10g}, V = {imp.velocity[slowest]:.3g}, {imp.labels[slowest]})"
        )
    # record window, cycle and phase
    t_first, t_last = t0 + transient * period, t0 + (transient + record) * period
    slack = 1e-9 * max(1.0, t_last)
    if np.any(imp.time < t_first - slack) or np.any(imp.time >= t_last + slack):
        problems.append("impact onset outside the record window")
    into_cycle = (imp.time - t0) / period - imp.cycle  # in [0, 1): onset in cycle k
    if np.any(into_cycle < -1e-9) or np.any(into_cycle > 1.0 + 1e-9):
        problems.append("impact cycle index does not match its time")
    phase_err = np.abs(((imp.time / period) % 1.0) - imp.phase)
    phase_err = np.minimum(phase_err, 1.0 - phase_err)
    if np.any(phase_err > 1e-9) or np.any((imp.phase < 0.0) | (imp.phase >= 1.0)):
        problems.append(f"impact phase is not (t mod T)/T (max error {phase_err.max():.2g})")
    # episodes in time order, each ending before the next begins
    ends_at = imp.time[:-1] + np.where(cut[:-1], 0.0, duration[:-1])
    if np.any(np.diff(imp.time) <= 0.0) or np.any(ends_at > imp.time[1:] + slack):
        problems.append("overlapping or unordered contact episodes")
    if out is not None:
        out.max_onset_gap = float(np.max(np.abs(d_on)))
        out.onset_gap_ratio = float(np.max(np.abs(d_on)) / on_tol * ONSET_GAP_TOL)
        out.min_velocity = float(np.min(imp.velocity))
        out.min_onset_rate = float(rate_on[slowest])
        out.min_peak_penetration = float(np.min(imp.peak_penetration))
        out.min_duration = float(np.min(done)) if len(done) else math.nan
        out.cut_episodes = int(np.sum(cut))
    return problems


_CYCLE_IN_MESSAGE = re.compile(r"at cycle (\d+)")


def error_problems(message: str, last_section: int) -> list[str]:
    """What is wrong with a SimulationError message (empty: one clear line)."""
    problems = []
    if "\n" in message or not message.strip():
        problems.append("message is not one line")
    if not re.search(r"\d", message):
        problems.append("message carries no numbers")
    found = _CYCLE_IN_MESSAGE.search(message)
    if "budget" in message and found and int(found.group(1)) > last_section:
        problems.append(
            f"step budget spent at cycle {found.group(1)}, after the run's last section "
            f"{last_section}: a contact episode still running at the end of the record window "
            "was followed without bound"
        )
    if "budget" in message and re.search(r"t = 0 \(", message):
        problems.append("step budget spent without advancing time (zero-length steps)")
    return problems


def assert_outcome(out: Outcome) -> None:
    assert out.status in ("finite", "clear error"), out.summary()


def flat_id(flat: dict) -> str:
    return ",".join(f"{k}={v:g}" for k, v in flat.items())


# ==================================== 1. the grid: finite result or clear error
DEFAULT_CASES = [
    pytest.param(preset, {name: value}, id=f"{preset}-{name}={value:g}")
    for preset in PRESETS
    for name, values in EXTREMES.items()
    for value in values
] + [
    pytest.param(preset, flat, id=f"{preset}-corner-{flat_id(flat)}",
                 marks=[pytest.mark.slow] if is_chatter_scene(flat) else [])
    for preset in PRESETS
    for flat in corner_grid()
] + [
    pytest.param(preset, dict(flat, ecc_y_ratio_A=ECC_Y_RATIO),
                 id=f"{preset}-corner-{flat_id(flat)},e=0.5",
                 marks=[pytest.mark.slow] if is_chatter_scene(flat) else [])
    for preset in ("fig3a", "tower-wall")  # = fig4-translational and wall at e_Ay = 0.5 l
    for flat in corner_grid()
]


@pytest.mark.parametrize(("preset", "flat"), DEFAULT_CASES)
def test_extreme_scene_gives_a_finite_result_or_a_clear_error(preset, flat):
    out = run_case(preset, flat)
    assert_outcome(out)
    if out.status == "finite":
        assert out.max_abs_state < 1e3, out.summary()  # bounded forcing, bounded response


@pytest.mark.slow
@pytest.mark.parametrize("chi", CHIS, ids=[f"chi={c:g}" for c in CHIS])
@pytest.mark.parametrize("beta", BETAS, ids=[f"beta={b:g}" for b in BETAS])
@pytest.mark.parametrize("preset", list(PRESETS))
def test_full_grid_gives_finite_results_or_clear_errors(preset, beta, chi):
    """The full factorial grid, one (preset, beta, chi) block of 84 scenes per test.

    Known and documented (results/extremes.md): the pair at rest on each other (gap 0,
    chi 1, zeta 1, T/T_Ax 5) has a penetration of ~2e-8 that the default rtol does not
    resolve, so an onset may be located on a falling d; only that failure is let pass,
    and only there."""
    failures = []
    for flat in full_grid(preset):
        if flat["beta"] == beta and flat["chi"] == chi:
            out = run_case(preset, flat)
            if out.status == "FAIL" and not _below_resolution(preset, flat, out):
                failures.append(out.summary())
    assert not failures, f"{len(failures)} failures:\n" + "\n".join(failures)


def _below_resolution(preset: str, flat: dict, out: Outcome) -> bool:
    """The documented resting-contact case, failing only in the documented way."""
    resting = (preset == "fig4-translational" and flat["chi"] == 1.0 and flat["zeta"] == 1.0
               and flat["gap"] == 0.0 and flat["period_ratio"] == 5.0)
    return resting and "no end at the surface moves in" in out.summary()


# ========================================= 2. the named extremes, with physics
@pytest.mark.parametrize("preset", list(PRESETS))
def test_beta_1e8_is_finite_with_the_default_step_budget(preset):
    out = run_case(preset, {"beta": 1e8})
    assert out.status == "finite", out.summary()
    assert out.impacts > 0


def test_beta_1e8_penetration_follows_the_hertz_energy_balance():
    """Rigid-wall limit: V^2 / 2 = beta d^(chi+1) / (chi + 1) at the deepest point.

    The wall's 1-1 orbit; during the short contact (penetration 4e-4 to 2e-2
    for chi = 1 to 3) the structural spring and damping change the energy by
    less than 1e-3 of the impact energy.
    """
    for chi in (1.0, 1.5, 3.0):
        scene = load_preset("wall").with_params(beta=1e8, chi=chi)
        sim = simulate(scene)
        imp = sim.impacts
        assert len(imp) == 8
        expected = ((chi + 1.0) * imp.velocity**2 / (2.0 * 1e8)) ** (1.0 / (chi + 1.0))
        np.testing.assert_allclose(imp.peak_penetration, expected, rtol=2e-3)
        np.testing.assert_allclose(imp.peak_force, 1e8 * imp.peak_penetration**chi, rtol=1e-9)


@pytest.mark.parametrize("preset", list(PRESETS))
def test_gap_zero_touching_at_rest_records_impacts(preset):
    out = run_case(preset, {"gap": 0.0})
    assert out.status == "finite", out.summary()
    assert out.impacts > 0


def test_rattling_at_the_noise_floor_records_no_zero_duration_impacts():
    """gap 0, heavy damping, slow forcing: a tower rattles on the wall with penetrations
    of ~1e-8 (the default atol). An onset and a release located at one instant (a touch at
    round-off level, no contact) used to be recorded as an impact of duration 0; every
    recorded episode now lasts and penetrates."""
    out = run_case("wall", {"beta": 1e6, "chi": 1.0, "zeta": 1.0, "gap": 0.0,
                            "period_ratio": 5.0})
    assert out.status == "finite", out.summary()
    assert out.impacts > 1000


@pytest.mark.parametrize("preset", list(PRESETS))
def test_touching_at_rest_without_forcing(preset):
    """gap 0, no ground motion, no damping: at rest nothing moves (d = 0 is no contact);
    pushed with X_A' = 1e-3 the towers meet at t = 0+ on the whole face at V = 1e-3.
    """
    scene = load_preset(preset).with_params(gap=0.0, ground="none", zeta=0.0)
    rest = simulate(scene, transient=0, record=5)
    assert len(rest.impacts) == 0
    assert np.all(rest.strobe.state == 0.0) and np.all(rest.final_state == 0.0)
    pushed = scene.with_params(initial_state=[0.0, 1e-3] + [0.0] * 10, rtol=1e-10, atol=1e-12)
    sim = simulate(pushed, transient=0, record=5)
    imp = sim.impacts
    assert len(imp) >= 5
    assert 0.0 <= imp.time[0] < 1e-9
    assert imp.velocity[0] == pytest.approx(1e-3, rel=1e-9)
    assert imp.labels[0] == "face"
    assert np.all(imp.duration > 0.0) and np.all(imp.peak_penetration > 0.0)
    if preset == "wall":  # contact, then half a free oscillation in x < 0: exactly periodic
        np.testing.assert_allclose(np.diff(imp.time), imp.duration[:-1] + math.pi, rtol=1e-8)
        np.testing.assert_allclose(imp.velocity, 1e-3, rtol=1e-7)  # energy drift ~6e-8


@pytest.mark.parametrize("preset", list(PRESETS))
def test_slow_forcing_follows_the_ground_quasi_statically(preset):
    """T/T_Ax = 20: tower A's steady contact-free response, closed form at the sections.

    X - u_g = Im[G exp(i w t)], G = w^2 / (1 - w^2 + 2 i zeta w), w = 1/r: at
    phase 0, X = Im G (-7.5e-6) and X' = w (1 + Re G). With e_Ay = 0.1 l the
    torsional coupling changes this by 6e-7 (X) and 4e-6 (X').
    """
    r, zeta = 20.0, 0.03
    scene = load_preset(preset).with_params(period_ratio=r, rtol=1e-9, atol=1e-12)
    sim = simulate(scene)
    assert len(sim.impacts) == 0
    names = sim.state_names
    w = 1.0 / r
    gain = w * w / (1.0 - w * w + 2j * zeta * w)
    x, v = sim.strobe.state[:, names.index("X_A")], sim.strobe.state[:, names.index("dX_A")]
    coupled = scene.tower_A.e_y != 0.0
    np.testing.assert_allclose(x, gain.imag, rtol=0, atol=1e-6 if coupled else 1e-9)
    np.testing.assert_allclose(v, w * (1.0 + gain.real), rtol=0, atol=1e-5 if coupled else 1e-9)


@pytest.mark.parametrize("preset", list(PRESETS))
def test_fast_forcing_leaves_the_towers_nearly_still(preset):
    """T/T_Ax = 0.05: the towers move by O(r^2) plus the decaying start-up."""
    out = run_case(preset, {"period_ratio": 0.05})
    assert out.status == "finite", out.summary()
    assert out.max_abs_state < 1.0


@pytest.mark.parametrize("preset", list(PRESETS))
def test_half_length_eccentricity_runs_the_torsional_model(preset):
    out = run_case(preset, {"ecc_y_ratio_A": ECC_Y_RATIO})
    assert out.status == "finite", out.summary()
    assert out.model == ("towers" if PRESETS[preset] in ("towers", "pair") else "tower-wall")
    assert out.impacts > 0


@pytest.mark.parametrize("zeta", [0.0, 1.0])
@pytest.mark.parametrize("preset", list(PRESETS))
def test_zero_and_critical_damping(preset, zeta):
    out = run_case(preset, {"zeta": zeta})
    assert out.status == "finite", out.summary()
    if zeta == 1.0:  # critically damped towers stay inside the gap of 1
        assert out.impacts == 0
    else:
        assert out.impacts > 0


# ====================================== 3. energy at the extremes of beta and chi
#: initial states with velocity (12 entries; the model takes its own)
ENERGY_INITIAL = {
    "fig3a": [0, 2, 0.5, 0.1, 0.01, -0.005, 0, -2, -0.3, 0.2, -0.01, 0.003],
    "fig4-translational": [0, 2, 0, 0, 0, 0, 0, -2, 0, 0, 0, 0],
    "tower-wall": [0, 2, 0.5, 0.1, 0.01, -0.005] + [0] * 6,
    "wall": [0, 2] + [0] * 10,
}
ENERGY_CYCLES = 100
ENERGY_DRIFT_TOL = 1e-6  #: at rtol 1e-10 (measured 1e-9 .. 8e-8 for beta 1 .. 1e8)


def energy_drift(preset: str, cycles: int = ENERGY_CYCLES, **flat) -> tuple[Simulation, float]:
    """Undamped run without ground motion from ENERGY_INITIAL; max relative drift of E.

    E is evaluated on 20 dense samples per cycle, every section and every
    onset; the reference is E of the initial state.
    """
    scene = load_preset(preset).with_params(
        zeta=0.0, ground="none", rtol=1e-10, atol=1e-12, initial_state=ENERGY_INITIAL[preset],
        **flat,
    )
    sim = simulate(scene, transient=0, record=cycles, samples_per_cycle=20)
    mid, p = scene.model_id(), scene.pack()
    e0 = models.energy(mid, scene.initial_vector(), p)
    states = np.vstack([sim.trajectory.state, sim.strobe.state, sim.impacts.state])
    energies = np.array([models.energy(mid, y, p) for y in states])
    assert np.all(np.isfinite(energies))
    return sim, float(np.max(np.abs(energies - e0)) / e0)


@pytest.mark.parametrize("beta", [1.0, 1e3, 1e6], ids=["beta=1", "beta=1e3", "beta=1e6"])
@pytest.mark.parametrize("preset", list(PRESETS))
def test_undamped_energy_drift_is_bounded_across_beta(preset, beta):
    sim, drift = energy_drift(preset, beta=beta)
    assert len(sim.impacts) >= 50, f"only {len(sim.impacts)} impacts"
    assert drift <= ENERGY_DRIFT_TOL, f"relative energy drift {drift:.2e}"


@pytest.mark.slow
@pytest.mark.parametrize("chi", CHIS, ids=[f"chi={c:g}" for c in CHIS])
@pytest.mark.parametrize("beta", BETAS, ids=[f"beta={b:g}" for b in BETAS])
@pytest.mark.parametrize("preset", list(PRESETS))
def test_undamped_energy_drift_full_sweep(preset, beta, chi):
    for extra in ({}, {"gap": 0.0}, {"ecc_y_ratio_A": ECC_Y_RATIO}):
        sim, drift = energy_drift(preset, beta=beta, chi=chi, **extra)
        assert len(sim.impacts) >= 50, (extra, len(sim.impacts))
        assert drift <= ENERGY_DRIFT_TOL, (extra, f"relative energy drift {drift:.2e}")


# ================================== 4. the forcing phase after many impact cycles
#: the wall preset's 1-1 impact orbit, sections at phase 0.37
LONG_RUN = {"phase": 0.37, "rtol": 1e-8, "atol": 1e-10}


@functools.cache
def wall_orbit() -> tuple:
    """(scene, reference run): 400 cycles settle on the 1-1 orbit; 2 recorded."""
    scene = load_preset("wall").with_params(**LONG_RUN)
    return scene, simulate(scene, transient=400, record=2)


def long_run_check(cycles: int) -> dict:
    """Run ``cycles`` cycles and compare the end with the orbit; returns the errors."""
    scene, ref = wall_orbit()
    period = scene.period
    t0 = scene.run.phase * period
    orbit = ref.strobe.state[-1]
    assert len(ref.impacts) == 2 and np.ptp(ref.impacts.phase) < 1e-9  # a 1-1 orbit
    start = time.perf_counter()
    run = simulate(scene, transient=cycles, record=1)
    wall_s = time.perf_counter() - start
    # the sections are exactly at phase T + k T
    np.testing.assert_array_equal(run.strobe.cycle, [cycles, cycles + 1])
    np.testing.assert_array_equal(run.strobe.time, t0 + np.array([cycles, cycles + 1]) * period)
    # one impact in the last cycle, at the orbit's phase and velocity
    assert len(run.impacts) == 1 and run.impacts.cycle[0] == cycles
    # a short run started on the orbit at the section time
    short = simulate(scene, transient=0, record=1, initial_state=orbit, start_at_section=True)
    errors = {
        "cycles": cycles,
        "period": period,
        "wall_s": wall_s,
        "steps": run.stats.steps,
        "phase_error": float(abs(run.impacts.phase[0] - ref.impacts.phase[-1])),
        "velocity_error": float(abs(run.impacts.velocity[0] - ref.impacts.velocity[-1])),
        "state_error_vs_orbit": float(np.max(np.abs(run.strobe.state - orbit))),
        "state_error_vs_short_run": float(
            np.max(np.abs(run.strobe.state[-1] - short.strobe.state[-1]))),
        "onset_time_error": float(abs(
            run.impacts.time[0] - (cycles + 1 + ref.impacts.phase[-1]) * period)),
    }
    return errors


def assert_long_run(errors: dict) -> None:
    # measured at 1e4 cycles: phase 5e-11, states 1e-8 .. 1e-7 (the tolerance is 1e-8)
    assert errors["phase_error"] < 1e-8, errors
    assert errors["velocity_error"] < 1e-6, errors
    assert errors["state_error_vs_orbit"] < 1e-6, errors
    assert errors["state_error_vs_short_run"] < 1e-6, errors
    # the onset time is (k + 1 + phase) T: the phase error times T plus a few ulps of t
    period, cycles = errors["period"], errors["cycles"]
    assert errors["onset_time_error"] < 1e-8 * period + 1e-14 * cycles * period, errors


def test_forcing_phase_is_exact_after_1e4_impacting_cycles():
    assert_long_run(long_run_check(10_000))


@pytest.mark.slow
def test_forcing_phase_is_exact_after_1e5_impacting_cycles():
    assert_long_run(long_run_check(100_000))


# ====================================== 5. reproductions of the grid's failures
def test_contact_lasting_past_the_record_window_does_not_spend_the_step_budget():
    """gap 0, e_Ay = 0.5 l, T/T_Ax = 20: the faces rock on each other and d_max > 0 always.

    The 48 cycles take ~1.2e4 steps; the episode running at the end of the record
    window never ends, and following it to its end spends any step budget (the
    default 2e7 steps: 36 s or more, then "step budget exhausted at cycle 50503
    ... raise max_steps or loosen rtol", neither of which helps).
    Expected: the run returns, the last episode cut (NaN duration).
    """
    scene = load_preset("fig3a").with_params(
        beta=100.0, chi=1.5, gap=0.0, period_ratio=20.0, ecc_y_ratio_A=0.5, max_steps=1_000_000
    )
    try:
        sim = simulate(scene)
    except SimulationError as exc:
        pytest.fail(f"SimulationError after 48 cycles of ~2e4 steps: {exc}")
    problems = simulation_problems(sim, scene.run.transient, scene.run.record)
    assert not problems, problems
    assert sim.stats.steps < 200_000


@pytest.mark.parametrize("flat", [{"atol": 1e-300}, {"rtol": 1e-200}],
                         ids=["atol=1e-300", "rtol=1e-200"])
def test_zero_length_steps_are_not_taken_until_the_budget_is_spent(flat):
    """atol below ~1e-155 (given, or following rtol as 1e-3 rtol) from rest: in
    the automatic initial step (f0 / atol)^2 overflows, h0 = 0, and every
    zero-length step is accepted (the underflow check only sees rejected steps).
    Default budget: 2e7 steps, 65 s (wall) to 135 s (fig3a), reported as "step
    budget exhausted at cycle 0, t = 0 ... raise max_steps or loosen rtol".
    Expected: a finite run or a step-size error, not a spent budget.
    """
    out = run_case("wall", dict(flat, max_steps=200_000))
    assert out.status in ("finite", "clear error"), out.summary()
    if out.status == "clear error":
        assert "budget" not in out.message, out.summary()


def test_no_impact_is_recorded_without_contact():
    """Pair touching at rest, stiff linear contact, slow forcing: a bounce every 0.1.

    At rtol 1e-6, atol 1e-9 (the solver is pinned: the reproduction depends on
    the step sequence) the step from t = 5451.6073 (h = 0.0789) ends in
    contact; the onset is located on its interpolant at theta = 0.704 and the
    step redone to end there, but the landed state is still outside
    (d = X_A - X_B = -6.7e-7, rate +3.8e-5). It is recorded as an impact
    anyway; the next step "releases" at theta = 7e-12: duration 0, peak
    penetration 0. The true onset follows 0.0138 later.
    """
    out = run_case("fig4-translational",
                   {"beta": 1e4, "chi": 1.0, "gap": 0.0, "period_ratio": 20.0,
                    "rtol": 1e-6, "atol": 1e-9},
                   transient=43, record=1)
    assert out.status == "finite", out.summary()


# ========================================= 6. invalid edge values: one-line errors
INVALID = [
    ("chi", 0.99, "chi"),
    ("beta", 0.0, "beta"),
    ("beta", -1e-300, "beta"),
    ("zeta", -0.01, "zeta"),
    ("zeta_t_B", -0.01, "zeta_t_B"),
    ("period_ratio", 0.0, "period_ratio"),
    ("gap", -1e-12, "gap"),
    ("ecc_y_ratio_A", math.nan, "ecc_y_ratio_A"),
    ("rtol", 0.0, "rtol"),
    ("max_steps", 0, "max_steps"),
] + [
    (name, value, name.removesuffix("_A") if name != "zeta" else "zeta")
    for name in ("beta", "chi", "gap", "period_ratio", "zeta", "ecc_y_ratio_A", "rtol")
    for value in (math.nan, math.inf, -math.inf)
]


@pytest.mark.parametrize(("name", "value", "named"), INVALID,
                         ids=[f"{n}={v!r}" for n, v, _ in INVALID])
def test_invalid_edge_values_are_rejected_naming_the_parameter(name, value, named):
    with pytest.raises(SceneError) as caught:
        load_preset("fig3a").with_params(**{name: value})
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(named), message  # zeta: "zeta_x_A = ..."
    shown = "nan" if value != value else ("inf" if math.isinf(value) else None)
    if shown:
        assert shown in message


@pytest.mark.parametrize("text", ["nan", "inf", "-1e-12", "0.99"])
def test_invalid_values_on_the_command_line_exit_2_with_one_line(capsys, text):
    name = "chi" if text == "0.99" else "gap"
    code = main(["simulate", "--preset", "wall", "--set", f"{name}={text}"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and err.startswith(f"chaospound: error: {name} = ")


def test_an_initial_state_with_nan_is_rejected():
    with pytest.raises(SceneError, match=r"initial_state\[3\]"):
        load_preset("fig3a").with_params(initial_state=[0, 0, 0, math.nan] + [0] * 8)


# ====================================== 7. clear errors, in Python and on the CLI
@pytest.mark.parametrize("preset", list(PRESETS))
def test_a_spent_step_budget_is_one_line_with_the_numbers(preset):
    out = run_case(preset, {"beta": 1e8, "max_steps": 500})
    assert out.status == "clear error", out.summary()
    assert "max_steps = 500" in out.message and "at cycle" in out.message


@pytest.mark.parametrize(("flat", "words"), [
    ({"rtol": 0.9}, ("non-finite", "step size fell below round-off")),
    ({"method": "rk4", "steps_per_cycle": 4, "beta": 1e8}, ("non-finite",)),
])
def test_a_blown_up_run_is_a_clear_error(flat, words):
    """A run that blows up (NaN, or a step driven to round-off) says so with its numbers."""
    out = run_case("fig3a", flat)
    assert out.status == "clear error", out.summary()
    assert any(w in out.message for w in words) and "steps accepted" in out.message


def test_cli_step_budget_exits_1_with_one_line_and_no_traceback():
    env = dict(os.environ,
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run(
        [sys.executable, "-m", "chaospound", "simulate", "--preset", "wall",
         "--set", "beta=1e8", "--set", "gap=0", "--set", "max_steps=100"],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert proc.returncode == 1, proc.stderr
    assert proc.stdout == ""
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("chaospound: error: step budget max_steps = 100 exhausted")
    assert re.search(r"t = [0-9.e+-]+ \(\d+ steps accepted, \d+ rejected\)", lines[0])


def test_cli_blow_up_exits_1_with_one_line(capsys):
    code = main(["simulate", "--preset", "fig3a", "--set", "method=rk4",
                 "--set", "steps_per_cycle=4", "--json"])
    out, err = capsys.readouterr()
    assert code == 1 and out == ""
    assert len(err.splitlines()) == 1 and "state became non-finite at cycle" in err
