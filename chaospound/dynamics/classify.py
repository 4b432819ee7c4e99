"""Regime classification of a steady pounding response (docs/model.md section 12).

A response is one of

* ``none``: no impact in the record window;
* ``periodic n-P``: the stroboscopic section repeats every P excitation cycles
  and so do the n impacts of one period, with n <= P (1-1, 1-2, 2-2, ...);
* ``group-periodic n-P``: the same with n > P, a group of different impacts
  repeating every P cycles (the paper's 3-1 at T/T_Ax = 0.70);
* ``quasi-periodic``: no period up to ``max_period`` cycles, largest Lyapunov
  exponent zero within three standard errors, 0-1 test K below 0.2;
* ``chaotic``: no period, largest exponent above zero by more than three
  standard errors, 0-1 test not against it (K >= 0.2, plain or less the
  means of the attractor's bands);
* ``unresolved``: anything else (the evidence says why).

The rules, in the order :func:`classify` applies them (the same text is in
``docs/classification.md``):

1. Solver. The runs use ``rtol_used = min(rtol, 1e-8)`` and
   ``atol_used = min(atol, 1e-2 rtol_used)``; the stroboscopic tolerance is
   ``tol = 1e3 rtol_used`` (1e-5), relative to the state scale. Converged
   impacting orbits repeat to 2e-8 .. 4e-7 at this setting, a margin of 25
   or more below tol, while the 1 % residue of a 3 %-damped transient after
   40 cycles (docs/model.md 11) is 1000 times above it. Fixed-step rk4 has no rtol:
   tol = 1e-5 and its ``steps_per_cycle`` must be fine enough.
2. State scale. Rotations and their rates are multiplied by the tower's
   radius of gyration rho, so that every component is a length (A_g) or a
   velocity (A_g omega_Ax). The mismatch of a period P over a stretch of
   sections is ``max_k |x_{k+P} - x_k| / scale``, ``scale`` being the largest
   Euclidean norm of the sections compared.
3. Adaptive transient. From the scene's initial state, ``min_transient``
   cycles, then ``chunk`` cycles at a time (each run continuing from the last
   section, ``start_at_section=True``), until the last max(2P, 10)
   section pairs P apart of some P <= max_period repeat within tol / 10, or
   ``max_transient`` cycles have run.
4. Record window of ``window`` cycles (default ``max(4 max_period, 32)``).
   The period P is the smallest P <= max_period whose mismatch over the whole
   window is below tol and whose impacts repeat: impact i + n comes P cycles
   after impact i (within ``10 tol`` cycles), at the same corner, with the
   same velocity (within ``10 tol`` times the largest |V|), n being the number
   of impacts in one period. If the last sections of the window have
   converged (rule 3's test at tol) to another period than the window as a
   whole (a transient still decaying), the window counts as transient and a
   new one is recorded, while the total stays within ``max_transient``.
   ``transient_used`` is the number of cycles run before the final window.
5. No impact in the window: ``none`` (its ``period_cycles`` is the period of
   the motion if found). Period found: ``periodic`` when n <= P,
   ``group-periodic`` when n > P.
6. No period. The record is extended to 1000 sections for the 0-1 test
   (observable: the scaled sections projected on their first principal
   direction; where the sections have bands, the period <= 8 of least
   mismatch, also less its mean in each band: :func:`zero_one_test`), then
   the largest exponent lambda +- sigma is computed
   (:func:`~chaospound.dynamics.lyapunov.lyapunov_spectrum`, k = 1,
   ``lyapunov_cycles`` cycles from the last section, 20 cycles of tangent
   alignment, error of 10 block means). Chaotic when lambda > 3 sigma
   (docs/model.md 12's rule) and K >= 0.2 (K < 0.2 clearly contradicts, unless
   the band-corrected K is >= 0.2; a contradiction stands only over 4000
   sections, :func:`vetoed`: weak chaos's K rises only over many Lyapunov times);
   quasi-periodic when |lambda| <= 3 sigma and the record is regular by the
   0-1 test (K < 0.2) or by the weighted Birkhoff average (at least 5
   digits, :func:`birkhoff_digits`: on a torus the average converges faster
   than any power of the record's length, on a chaotic attractor as its
   inverse square root; docs/classification.md gives the digits measured on
   fig4's chaotic and quasi-periodic points), an exponent
   that is merely consistent with zero not being enough on its own; unresolved
   otherwise, in particular lambda < -3 sigma without a period (a period
   longer than max_period or a transient longer than max_transient). When
   lambda / sigma falls between 1 and 6 (near the 3-sigma line, where a
   200-cycle run decides by chance) the exponent is recomputed over 4 times as
   many cycles. 6b: where that says quasi-periodic or unresolved and the tail
   repeats within ``NEWTON_TRY`` at some P (``floquet=True``), Newton's method
   solves for the period-P orbit from the last section; a stable orbit that
   the record closes in on (:func:`_approached_orbit`) is the attractor, read
   from a window at its state (rules 4, 5 and 8). Without a 0-1 test
   (``test01=False``, or the few sections of a sweep's record window) the
   exponent alone can show chaos but not quasi-periodicity: |lambda| <= 3
   sigma is then unresolved.
7. Without an exponent (:func:`classify_sequence` on bare data) the 0-1 test
   decides: chaotic when K > 0.8, quasi-periodic when K < 0.2, unresolved
   between (and below 100 sections, where no K is computed).
8. Periodic and group-periodic responses (``floquet=True``, the default): the
   orbit is solved by Newton shooting from the last section of the record
   window with period P (:func:`chaospound.orbits.floquet.response_floquet`:
   rtol 1e-12, the response's own scheme, residual 1e-10 of the state scale).
   Its multipliers mu and Floquet exponents log|mu| / (P T) are the response's
   Lyapunov exponents, exact up to the integration tolerance (``floquet_exponents``;
   ``evidence["floquet"]`` says how: the variational monodromy, or, for a law
   whose tangent dynamics the engine refuses, a finite-difference one). The
   orbit confirms the response when Newton stays within 1e-3 of the state scale
   of the start, with the same impacts per period and corners, all |mu| < 1.
   A failed Newton leaves the label as it is and the evidence says why.
   8b: a stable orbit near the start that repeats after fewer cycles than P
   (:func:`chaospound.orbits.shooting.minimal_period`; near a period doubling the
   sections alternate about a period-1 orbit for hundreds of cycles) is the
   attractor, read from a window at its state as in 6b.

Confidence, in [0, 1]: periodic and group-periodic
``log10(tol / mismatch) / 2`` (1 at a mismatch 100 times below tol, 0 at
tol), 1 when the solved orbit confirms the response (rule 8), at most 0.5 when
it contradicts it; ``none`` 1 (0.5 when the motion has no period); chaotic the smaller of
``(lambda / sigma - 3) / 7`` and ``(K - 0.2) / 0.6``; quasi-periodic the
smaller of ``1 - |lambda / sigma| / 3`` and the larger of ``(0.2 - K) / 0.2``
and ``(digits - 5) / 2``; each clipped
to [0, 1], a piece of evidence that was not computed left out; unresolved 0.

Units: exponents per unit normalised time t = tau omega_Ax (times T: per
excitation cycle); periods and transients in excitation cycles.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.fft

from ..kernels.params import CUSTOM
from ..physics.corners import CORNER_LABELS
from ..scene import Scene
from .system import System, as_system

__all__ = [
    "CLASSIFY_RTOL",
    "DEFAULT_TOL",
    "REGIMES",
    "Regime",
    "classify",
    "birkhoff_digits",
    "classify_sequence",
    "length_weights",
    "zero_one_test",
]

#: regime names, in the order of the rules
REGIMES = ("none", "periodic", "group-periodic", "quasi-periodic", "chaotic", "unresolved")
CLASSIFY_RTOL = 1e-8  #: the loosest rtol a classification runs with
TOL_PER_RTOL = 1e3  #: tol = TOL_PER_RTOL * rtol (relative stroboscopic mismatch)
DEFAULT_TOL = TOL_PER_RTOL * CLASSIFY_RTOL  #: 1e-5
TRANSIENT_MARGIN = 0.1  #: the transient ends when the tail repeats within this * tol
TAIL_MIN = 10  #: the convergence test compares at least this many section pairs
ATOL_PER_RTOL = 1e-2  #: atol used <= ATOL_PER_RTOL * rtol used
IMPACT_TOL_FACTOR = 10.0  #: impact times (cycles) and velocities (relative) repeat within this*tol
SIGMAS = 3.0  #: the exponent's evidence rule: lambda beyond 3 standard errors
ZERO_ONE_CHAOTIC = 0.8  #: K above: the 0-1 test alone calls the data chaotic
ZERO_ONE_REGULAR = 0.2  #: K below: regular; vetoes chaos, and quasi-periodicity needs it
ZERO_ONE_CYCLES = 1000  #: sections recorded for the 0-1 test when no period is found
ZERO_ONE_MIN_POINTS = 100  #: fewer points: no 0-1 test (K = None)
ZERO_ONE_C_RANGE = (math.pi / 5, 4 * math.pi / 5)  #: c avoids the resonances at 0 and pi
#: the bands of a banded attractor: the period <= this whose sections move least; the
#: 0-1 test runs on the observable less its mean in each band (:func:`zero_one_test`)
ZERO_ONE_MAX_BANDS = 8
#: weighted Birkhoff average: at least this many digits of agreement between the record's
#: two halves make it regular (a torus); fig4's chaotic records: median 2.4, 95 % below 3.8
BIRKHOFF_DIGITS_REGULAR = 5.0
BIRKHOFF_DECADES = 2.0  #: digits above BIRKHOFF_DIGITS_REGULAR giving full confidence
MISMATCH_DECADES = 2.0  #: a mismatch this many decades below tol gives full confidence
AMBIGUOUS_Z = (1.0, 6.0)  #: lambda / sigma in this range: rerun the exponent LONGER_RUN x longer
LONGER_RUN = 4
Z_FULL_CONFIDENCE = 10.0  #: lambda / sigma giving full confidence in chaos
CONTRADICTED_CONFIDENCE = 0.5  #: at most this when the solved orbit contradicts the response
NEWTON_TRY = 1e-2  #: a tail repeating within this (relative) at some P: Newton is tried at P
NEWTON_TOL = 1e-7  #: Newton's relative residual (100 times below tol)
NEWTON_ITER = 15  #: Newton iterations allowed per attempt
#: an approached orbit: the record's last quarter is at most this times as far from the
#: orbit as its first quarter (rule 6b) ...
APPROACH_RATIO = 0.5
#: ... or at most this times tol from it: the noise floor of a weakly stable orbit's runs
NEAR_ORBIT = 10.0
APPROACH_RTOL = 1e-3  #: rule 6b's Newton and window run at this times the rtol used


@dataclass(frozen=True)
class Regime:
    """The classified regime of a steady response.

    Attributes
    ----------
    regime : str
        One of :data:`REGIMES`.
    impacts_per_period : int or None
        n, impacts per period (0 for ``none``; None without a period).
    period_cycles : int or None
        P, the period in excitation cycles (None when no period was found).
    corner_sequence : list of str
        Corner labels of the n impacts of one period, in time order, starting
        with the first impact after a section of the record window.
    strobe_mismatch : float
        Relative stroboscopic mismatch ``max_k |x_{k+P} - x_k| / scale`` at
        the period found, or at the best candidate P <= max_period.
    max_exponent, max_exponent_error : float or None
        Largest Lyapunov exponent and its standard error (per unit normalised
        time); computed only when no period is found.
    zero_one : float or None
        K of the 0-1 test (about 0 regular, about 1 chaotic); computed only
        when no period is found.
    confidence : float
        In [0, 1], see the module docstring.
    transient_used : int
        Excitation cycles integrated before the record window.
    evidence : dict
        Further numbers: tol, scale, the mismatch of every candidate period,
        the solver tolerances, window lengths, lambda / sigma, ... and, for a
        periodic response, ``floquet``: how its orbit was solved (rule 8).
    floquet_exponents : tuple of float or None
        A periodic response's Floquet exponents log|mu| / (P T) (per unit
        normalised time, descending), from its orbit solved by Newton shooting:
        its Lyapunov exponents (rule 8). None when not computed or Newton failed.
    floquet_multipliers : tuple of complex or None
        The orbit's multipliers mu (eigenvalues of the monodromy of P cycles),
        by decreasing modulus.
    floquet_exact : bool or None
        The exponents are exact: the orbit confirms the response and its
        monodromy is valid (``evidence["floquet"]["note"]`` says otherwise why).
    """

    regime: str
    impacts_per_period: int | None = None
    period_cycles: int | None = None
    corner_sequence: list[str] = field(default_factory=list)
    strobe_mismatch: float = math.nan
    max_exponent: float | None = None
    max_exponent_error: float | None = None
    zero_one: float | None = None
    confidence: float = 0.0
    transient_used: int = 0
    evidence: dict = field(default_factory=dict)
    floquet_exponents: tuple[float, ...] | None = None
    floquet_multipliers: tuple[complex, ...] | None = None
    floquet_exact: bool | None = None

    def __post_init__(self) -> None:
        if self.regime not in REGIMES:
            raise ValueError(f"regime = {self.regime!r}: must be one of {', '.join(REGIMES)}")

    @property
    def label(self) -> str:
        """Short label: "group-periodic 3-1", "periodic 1-2", "chaotic", ... (n-P)."""
        if self.regime in ("periodic", "group-periodic"):
            return f"{self.regime} {self.impacts_per_period}-{self.period_cycles}"
        return self.regime

    def to_json_dict(self) -> dict:
        """JSON-ready dict (non-finite floats are left to the writer)."""
        return {
            "regime": self.regime,
            "label": self.label,
            "impacts_per_period": self.impacts_per_period,
            "period_cycles": self.period_cycles,
            "corner_sequence": list(self.corner_sequence),
            "strobe_mismatch": float(self.strobe_mismatch),
            "max_exponent": self.max_exponent,
            "max_exponent_error": self.max_exponent_error,
            "zero_one": self.zero_one,
            "confidence": float(self.confidence),
            "transient_used": int(self.transient_used),
            "floquet_exponents": (None if self.floquet_exponents is None
                                  else [float(e) for e in self.floquet_exponents]),
            "floquet_exact": self.floquet_exact,
            "evidence": _plain(self.evidence),
        }


# =============================================================== classify
def classify(
    system_or_scene: System | Scene,
    *,
    min_transient: int = 40,
    max_transient: int = 2000,
    chunk: int = 20,
    window: int | None = None,
    max_period: int = 16,
    tol: float | None = None,
    lyapunov_cycles: int = 200,
    test01: bool = True,
    floquet: bool = True,
    progress: Callable[[str], None] | None = None,
) -> Regime:
    """Classify the steady response of a pounding scene.

    Parameters
    ----------
    system_or_scene : System or Scene
        A scene, or a system made from one (:meth:`System.from_scene`; its
        solver settings and initial state are used).
    min_transient, max_transient, chunk : int
        Adaptive transient, in excitation cycles: at least ``min_transient``,
        then ``chunk`` more at a time until the section has converged to a
        period <= ``max_period``, at most ``max_transient``.
    window : int, optional
        Record window in cycles (default ``max(4 max_period, 32)``, at least
        ``2 max_period``).
    max_period : int
        Longest period searched, in cycles.
    tol : float, optional
        Relative stroboscopic mismatch accepted as a repeat (default
        ``1e3 * rtol_used``, 1e-5 for rtol <= 1e-8).
    lyapunov_cycles : int
        Cycles averaged for the largest exponent (only without a period).
    test01 : bool
        Run the 0-1 test (only without a period).
    floquet : bool
        For a periodic or group-periodic response, solve its orbit by Newton
        shooting and report the exact Floquet exponents (rule 8).
    progress : callable, optional
        Called with a short text at each stage ("transient: 400 of at most 2000
        cycles", ...), e.g. to show progress; nothing else depends on it.

    Returns
    -------
    Regime
        With ``transient_used`` and the evidence of every rule applied.

    Raises
    ------
    ValueError
        Bad arguments, or a system without a pounding scene.
    chaospound.simulate.SimulationError
        A run that could not finish.
    """
    from ..simulate import simulate
    from .lyapunov import lyapunov_spectrum

    system = as_system(system_or_scene)
    if system.ground not in ("sine", "none"):
        raise ValueError(f"ground = {system.ground}: regimes (periodic, quasi-periodic, "
                         "chaotic) are defined for periodic forcing; simulate the record and "
                         "read its impacts instead")
    if system.scene is None and not (system.model_id == CUSTOM and system.has_gap):
        raise ValueError(
            f"system {system.name!r} has no impacts to classify: use a pounding scene "
            "(a Scene or System.from_scene) or a custom system with a gap function"
        )
    window = max(4 * max_period, 32) if window is None else int(window)
    _check_arguments(min_transient, max_transient, chunk, window, max_period, lyapunov_cycles)
    # "scene": what simulate runs, the system with the tightened solver settings
    scene, rtol_used, atol_used = _classification_system(system)
    tol = TOL_PER_RTOL * rtol_used if tol is None else _check_tol(tol)
    if system.scene is not None:
        weights = length_weights(system.scene, system.state_names)
        section_phase = system.scene.run.phase
    else:  # a custom system: its own units, sections at t = k T
        weights = np.ones(system.dim)
        section_phase = 0.0
    start = np.asarray(system.initial_state, dtype=float)

    # 1. adaptive transient, 2. record window; a window whose period differs from the
    # one its last sections have converged to was still transient: count it and go on
    def report(text: str) -> None:
        if progress is not None:
            progress(text)

    report(f"transient: 0 of at most {max_transient} cycles")
    run = simulate(scene, transient=0, record=min_transient, initial_state=start)
    sections, done = [run.strobe.state], min_transient
    while True:
        report(f"transient: {done} of at most {max_transient} cycles")
        tail = np.concatenate(sections)[-(_tail_length(max_period)):] * weights
        converged = _converged_period(tail, max_period, TRANSIENT_MARGIN * tol)
        if converged is None and done < max_transient:
            cycles = min(chunk, max_transient - done)
            run = simulate(scene, transient=0, record=cycles, initial_state=sections[-1][-1],
                           start_at_section=True)
            sections.append(run.strobe.state[1:])
            done += cycles
            continue
        report(f"record window: {window} cycles after a {done}-cycle transient")
        record = simulate(scene, transient=0, record=window, initial_state=sections[-1][-1],
                          start_at_section=True)
        imp = record.impacts
        local_phase = _phase_from_section(imp.time, imp.cycle, record.period, section_phase)
        regime = classify_sequence(
            record.strobe.state * weights, imp.cycle, local_phase, imp.velocity, imp.labels,
            max_period=max_period, tol=tol, test01=False,
        )
        at_end = _converged_period(record.strobe.state[-(_tail_length(max_period)):] * weights,
                                   max_period, tol)
        if regime.period_cycles == at_end or done + window > max_transient:
            break
        sections, done = [record.strobe.state], done + window

    evidence = {
        "rtol": rtol_used,
        "atol": atol_used,
        "method": system.method,
        "model": record.model,
        "window_cycles": window,
        "transient_converged_period": converged,
        "window_end_period": at_end,
        "impacts_in_window": len(imp),
        "impacts_per_cycle": len(imp) / window,
    }
    if regime.regime in ("periodic", "group-periodic") and floquet:
        report(f"{regime.label}: solving the orbit for its Floquet exponents")
        regime, orbit = _with_floquet(regime, system, record.strobe.state[-1])
        shorter = _shorter_orbit(orbit)
        if shorter is not None:
            # 8b. Newton's orbit repeats after fewer cycles: the record still approaches it
            report(f"{regime.label}: the orbit repeats after {orbit.minimal_period} cycles")
            reached = _orbit_regime(_orbit_system(scene), system, shorter, window, weights,
                                    max_period, tol, section_phase)
            if reached is not None:
                evidence.update(reached_by="newton", approach={
                    "period": regime.period_cycles, "label": regime.label,
                    "orbit_period": orbit.minimal_period, "distance": orbit.distance,
                    "result": "the record approached a shorter orbit"})
                regime = reached
    if regime.regime != "unresolved" or not len(imp):
        return replace(regime, transient_used=done, evidence={**regime.evidence, **evidence})

    # 3. no period: a longer record for the 0-1 test, then the largest exponent
    states, last = record.strobe.state, record.strobe.state[-1]
    cycles, velocity, labels = imp.cycle, imp.velocity, imp.labels
    if test01 and states.shape[0] < ZERO_ONE_CYCLES + 1:
        report(f"no period: {ZERO_ONE_CYCLES} cycles for the 0-1 test")
        more = simulate(scene, transient=0, record=ZERO_ONE_CYCLES + 1 - states.shape[0],
                        initial_state=last, start_at_section=True)
        states, cycles, local_phase, velocity, labels = _appended(
            (states, cycles, local_phase, velocity, labels), more, section_phase)
        last = states[-1]
    report(f"no period: largest Lyapunov exponent over {lyapunov_cycles} cycles")
    spectrum = lyapunov_spectrum(scene, k=1, transient=0,
                                 cycles=lyapunov_cycles, initial_state=last)
    z = spectrum.max_exponent / max(spectrum.max_error, 1e-300)
    if AMBIGUOUS_Z[0] < abs(z) < AMBIGUOUS_Z[1]:
        # near the 3-sigma line a short run decides by chance: average 4x longer
        lyapunov_cycles = LONGER_RUN * lyapunov_cycles
        report(f"no period: largest Lyapunov exponent over {lyapunov_cycles} cycles (near "
               "the 3-sigma line)")
        spectrum = lyapunov_spectrum(scene, k=1, transient=0,
                                     cycles=lyapunov_cycles, initial_state=last)
    regime = classify_sequence(
        states * weights, cycles, local_phase, velocity, labels,
        max_period=max_period, tol=tol, exponent=spectrum.max_exponent,
        exponent_error=spectrum.max_error, test01=test01,
    )
    if test01 and vetoed(regime):
        # the 0-1 test's veto of a positive exponent: weak chaos needs more Lyapunov
        # times than 1000 sections hold before K rises; LONGER_RUN x the sections
        report(f"no period: {(LONGER_RUN - 1) * ZERO_ONE_CYCLES} more cycles for the 0-1 "
               "test (it vetoes a positive exponent)")
        more = simulate(scene, transient=0, record=(LONGER_RUN - 1) * ZERO_ONE_CYCLES,
                        initial_state=last, start_at_section=True)
        states, cycles, local_phase, velocity, labels = _appended(
            (states, cycles, local_phase, velocity, labels), more, section_phase)
        last = states[-1]
        evidence["zero_one_vetoed"] = regime.zero_one
        regime = classify_sequence(
            states * weights, cycles, local_phase, velocity, labels,
            max_period=max_period, tol=tol, exponent=spectrum.max_exponent,
            exponent_error=spectrum.max_error, test01=test01,
        )
    evidence.update(
        lyapunov_cycles=lyapunov_cycles,
        exponent_per_cycle=spectrum.max_exponent * spectrum.period,
        zero_one_points=int(states.shape[0]) if test01 else 0,
    )
    if floquet and regime.regime in ("quasi-periodic", "unresolved"):
        # 6b. a record that closes in on a stable orbit: a slow approach, not a torus
        tight = _orbit_system(scene)
        state, note = _approached_orbit(tight, states, weights, max_period, tol)
        if state is not None:
            report(f"no period within tol: closing in on a period-{note['period']} orbit")
            reached = _orbit_regime(tight, system, state, window, weights, max_period, tol,
                                    section_phase)
            if reached is not None:
                approach = {**note, "label": regime.label, "exponent": regime.max_exponent,
                            "exponent_error": regime.max_exponent_error,
                            "zero_one": regime.zero_one}
                evidence.update(reached_by="newton", approach=approach)
                return replace(reached, transient_used=done + states.shape[0] - 1,
                               evidence={**reached.evidence, **evidence})
            note["result"] = "approached, but its window did not repeat"
        if note:
            evidence["approach"] = note
    return replace(regime, transient_used=done, evidence={**regime.evidence, **evidence})


def _appended(record: tuple, more, section_phase: float) -> tuple:
    """A record ``(states, cycles, phases, velocities, labels)`` followed by the run
    ``more`` from its last section (its impacts' cycles counted on)."""
    states, cycles, phases, velocity, labels = record
    extra = more.impacts
    return (np.concatenate([states, more.strobe.state[1:]]),
            np.concatenate([cycles, extra.cycle + states.shape[0] - 1]),
            np.concatenate([phases, _phase_from_section(extra.time, extra.cycle,
                                                        more.period, section_phase)]),
            np.concatenate([velocity, extra.velocity]),
            labels + extra.labels)


def with_exponent(regime: Regime, exponent: float, error: float) -> Regime:
    """Rule 6 again on a reading without a period (:func:`classify_sequence` with an
    exponent), with another exponent: the same record's period search, 0-1 tests and
    Birkhoff average, which do not depend on it, are not computed twice."""
    evidence = dict(regime.evidence)
    label, confidence = _aperiodic_regime(exponent, error, regime.zero_one, evidence)
    return replace(regime, regime=label, confidence=confidence,
                   max_exponent=float(exponent), max_exponent_error=float(error),
                   evidence=evidence)


def _orbit_system(scene: System) -> System:
    """The classification's system at :data:`APPROACH_RTOL` times its rtol and atol
    (a fixed-step method unchanged): rule 6b's Newton and window run on it.

    The runs at the classification's rtol repeat a weakly stable orbit only to about
    tol: one section of fig4-translational's period-16 orbit at T/T_Ax 0.7458 (|mu| =
    0.94) is 3e-5 off after a period at rtol 1e-8, the others 1e-7; an orbit solved at
    that rtol is off the tighter runs' by as much, which that section amplifies again.
    """
    if scene.method == "rk4":
        return scene
    return _with_solver(scene, {"rtol": APPROACH_RTOL * scene.rtol,
                                "atol": APPROACH_RTOL * scene.atol})


def _approached_orbit(scene: System, states: np.ndarray, weights: np.ndarray,
                      max_period: int, tol: float) -> tuple[np.ndarray | None, dict]:
    """Rule 6b: the stable period-P orbit a record without a period closes in on.

    ``states`` are the record's consecutive sections (model units). Where their tail
    repeats within :data:`NEWTON_TRY` at some P <= ``max_period`` (the smallest),
    Newton's method (:func:`chaospound.orbits.shooting.newton_fixed_point`, the
    solver settings of ``scene``, :func:`_orbit_system`; residual :data:`NEWTON_TOL`)
    solves for the period-P orbit from the last section. The orbit's state is
    returned only when the orbit is stable (every multiplier of its monodromy inside
    the unit circle) and the record approaches it: the mean distance of its last
    quarter of sections to the orbit's P sections (relative to the state scale) is at
    most :data:`APPROACH_RATIO` times its first quarter's, or at most
    :data:`NEAR_ORBIT` times ``tol`` (where the runs' noise keeps a weakly stable
    orbit's record).

    Returns
    -------
    state : ndarray or None
        The orbit's section state, or None.
    note : dict
        Empty when no period is near; else the period tried and what came of it
        (``result``; residual, iterations, ``max_multiplier`` and the two
        distances as far as they were computed).
    """
    from ..orbits.maps import StroboscopicMap
    from ..simulate import simulate

    scaled = states * weights
    period = _converged_period(scaled[-_tail_length(max_period):], max_period, NEWTON_TRY)
    if period is None or states.shape[0] < 8 * period:
        return None, {}
    note: dict = {"period": period, "sections": int(states.shape[0])}
    smap = StroboscopicMap.of(scene, rtol=scene.rtol, atol=scene.atol, method=None)
    state, found = newton_orbit(smap, states[-1], period)
    note.update(found)
    if state is None:
        note["result"] = "no orbit: " + note["result"]
        return None, note
    if not note["max_multiplier"] < 1.0:
        note["result"] = "unstable orbit"
        return None, note
    orbit = simulate(scene, transient=0, record=period, initial_state=state,
                     start_at_section=True).strobe.state[:period] * weights
    distance = np.min(np.linalg.norm(scaled[:, None, :] - orbit[None, :, :], axis=2),
                      axis=1) / _scale(scaled)
    quarter = max(1, distance.size // 4)
    first, last = float(distance[:quarter].mean()), float(distance[-quarter:].mean())
    note.update(distance_first_quarter=first, distance_last_quarter=last)
    if not (last <= APPROACH_RATIO * first or last <= NEAR_ORBIT * tol):
        note["result"] = "stable orbit, not approached"
        return None, note
    note["result"] = "approached"
    return state, note


def newton_orbit(smap, start: np.ndarray, period: int, *,
                 give_up_early: bool = False) -> tuple[np.ndarray | None, dict]:
    """The period-``period`` orbit of ``smap`` by Newton's method from ``start``
    (residual :data:`NEWTON_TOL`, at most :data:`NEWTON_ITER` iterations, the
    monodromy at the chord iterations' rtol: its stability, not its digits, is asked).

    Returns ``(state, note)``: the orbit's section state and ``{"residual",
    "iterations", "max_multiplier"}``, or ``(None, {"result": why})`` when Newton or
    its runs fail. Rule 6b and the converged classification's step 3 both use it.
    """
    from ..orbits import OrbitNotFound
    from ..orbits.shooting import newton_fixed_point
    from ..simulate import SimulationError

    try:
        state, monodromy, residual, iterations = newton_fixed_point(
            smap, start, period, tol=NEWTON_TOL, max_iter=NEWTON_ITER,
            exact_monodromy=False, give_up_early=give_up_early)
        mu = float(np.max(np.abs(np.linalg.eigvals(monodromy))))
    except (OrbitNotFound, SimulationError, np.linalg.LinAlgError) as exc:
        return None, {"result": str(exc).splitlines()[0][:160]}
    return state, {"residual": residual, "iterations": iterations, "max_multiplier": mu}


def _orbit_regime(scene: System, system: System, state: np.ndarray, window: int,
                  weights: np.ndarray, max_period: int, tol: float,
                  section_phase: float) -> Regime | None:
    """The regime of a record window from an approached orbit's state (rules 4, 5 and
    8; ``scene`` at the orbit's solver settings, :func:`_orbit_system`), or None when
    the window does not repeat at tol."""
    from ..simulate import simulate

    record = simulate(scene, transient=0, record=window, initial_state=state,
                      start_at_section=True)
    imp = record.impacts
    regime = classify_sequence(
        record.strobe.state * weights, imp.cycle,
        _phase_from_section(imp.time, imp.cycle, record.period, section_phase),
        imp.velocity, imp.labels, max_period=max_period, tol=tol, test01=False)
    if regime.regime not in ("periodic", "group-periodic"):
        return None
    return _with_floquet(regime, system, record.strobe.state[-1])[0]


def _shorter_orbit(floquet) -> np.ndarray | None:
    """Rule 8b: the state of a stable orbit near the response that repeats after fewer
    cycles than the response's period, or None. Near a period doubling (a multiplier
    near -1) the sections approach a period-1 orbit alternating about it, and look
    period-2 for hundreds of cycles (fig4 at T/T_Ax 0.4497: |mu| = 0.9946, the period-2
    mismatch below tol after 900 cycles, the period-1 one not before 2000)."""
    from ..orbits.floquet import CONFIRM_DISTANCE

    if (floquet is None or not floquet.found or not floquet.stable
            or not 0 < floquet.minimal_period < floquet.period
            or not floquet.distance <= CONFIRM_DISTANCE):
        return None
    return floquet.orbit.state


def _with_floquet(regime: Regime, system: System, state: np.ndarray):
    """Rule 8: the periodic response's orbit by Newton shooting, its Floquet exponents.

    Newton starts from the last section of the record window (``state``, in the
    model's units) with the response's period; the evidence gets the report
    (:class:`chaospound.orbits.floquet.FloquetReport`). A confirmed orbit (near
    the start, same impacts and corners, all |mu| < 1) raises the confidence to
    1; one that contradicts the response caps it at 0.5; a failed Newton leaves
    it and says why.

    Returns ``(regime, report)``: the report
    (:class:`~chaospound.orbits.floquet.FloquetReport`) is None where the solve raised.
    """
    from ..orbits.floquet import response_floquet
    from .system import SimulationError

    try:
        floquet = response_floquet(system, state, regime.period_cycles,
                                   impacts_per_period=regime.impacts_per_period,
                                   corner_sequence=tuple(regime.corner_sequence))
    except (SimulationError, ValueError, np.linalg.LinAlgError) as exc:
        return replace(regime, evidence={**regime.evidence, "floquet": {
            "found": False, "exact": False, "note": f"no orbit: {exc}"}}), None
    evidence = {**regime.evidence, "floquet": floquet.to_json_dict()}
    if not floquet.found:
        return replace(regime, evidence=evidence), floquet
    confidence = 1.0 if floquet.confirmed else min(regime.confidence, CONTRADICTED_CONFIDENCE)
    return replace(regime, confidence=confidence, evidence=evidence,
                   floquet_exponents=tuple(float(e) for e in floquet.exponents),
                   floquet_multipliers=tuple(complex(z) for z in floquet.multipliers),
                   floquet_exact=floquet.exact), floquet


# ====================================================== classify_sequence
def classify_sequence(
    strobe_states: np.ndarray,
    impact_cycles: Sequence[int],
    impact_phases: Sequence[float],
    impact_velocities: Sequence[float],
    impact_corners: Sequence[str] | Sequence[int],
    *,
    max_period: int = 16,
    tol: float = DEFAULT_TOL,
    exponent: float | None = None,
    exponent_error: float | None = None,
    test01: bool = True,
) -> Regime:
    """Classify a recorded steady response from its sections and impacts.

    The pure-data core of :func:`classify` (rules 2 and 4-7 of the module
    docstring); ``transient_used`` is 0.

    Parameters
    ----------
    strobe_states : ndarray (N + 1, n) or (N + 1,)
        Consecutive stroboscopic states (one per excitation cycle), in
        comparable units (classify scales rotations by rho).
    impact_cycles, impact_phases, impact_velocities, impact_corners : sequences
        One entry per impact of the same window, in time order: cycle index
        k, phase within the cycle in [0, 1) (classify counts it from the
        section; ``Impacts.phase``, (t mod T)/T, also works: only
        differences between impacts P cycles apart matter), relative
        velocity V (A_g omega_Ax) and corner label ("A+", ...) or code
        (:data:`CORNER_LABELS`). ``corner_sequence`` starts with the first
        impact.
    max_period : int
        Longest period searched, in cycles.
    tol : float
        Relative stroboscopic mismatch accepted as a repeat.
    exponent, exponent_error : float, optional
        Largest Lyapunov exponent and its standard error, used when no period
        is found; without them the 0-1 test decides.
    test01 : bool
        Run the 0-1 test on the sections when no period is found.

    Returns
    -------
    Regime
    """
    states = np.asarray(strobe_states, dtype=float)
    if states.ndim == 1:
        states = states[:, None]
    if states.ndim != 2 or states.shape[0] < 3 or not np.all(np.isfinite(states)):
        raise ValueError(
            f"strobe_states has shape {np.shape(strobe_states)}: need at least 3 finite sections"
        )
    if int(max_period) < 1:
        raise ValueError(f"max_period = {max_period}: must be an integer >= 1")
    tol = _check_tol(tol)
    impacts = _impact_table(impact_cycles, impact_phases, impact_velocities, impact_corners)
    max_period = min(int(max_period), (states.shape[0] - 1) // 2)
    scale = _scale(states)
    mismatches = {p: _mismatch(states, p, scale) for p in range(1, max_period + 1)}
    evidence: dict = {
        "tol": tol,
        "scale": scale,
        "sections": int(states.shape[0]),
        "mismatch_by_period": {str(p): m for p, m in mismatches.items()},
    }
    period, group = None, None
    for p in range(1, max_period + 1):
        if mismatches[p] < tol:
            group = _repeating_group(impacts, p, tol, states.shape[0] - 1)
            if group is not None:
                period = p
                break
    best = period if period is not None else min(mismatches, key=mismatches.get)
    mismatch = mismatches[best] if mismatches else math.nan
    evidence["best_period"] = best

    if impacts.n == 0:
        motion = next((p for p in range(1, max_period + 1) if mismatches[p] < tol), None)
        return Regime("none", impacts_per_period=0, period_cycles=motion,
                      strobe_mismatch=mismatches[motion] if motion else mismatch,
                      confidence=1.0 if motion else 0.5, evidence=evidence)
    if period is not None:
        n = len(group)
        return Regime(
            "periodic" if n <= period else "group-periodic",
            impacts_per_period=n,
            period_cycles=period,
            corner_sequence=group,
            strobe_mismatch=mismatch,
            confidence=_mismatch_confidence(mismatch, tol),
            evidence=evidence,
        )
    zero_one = None
    if test01 and states.shape[0] >= ZERO_ONE_MIN_POINTS:
        observable = _principal_component(states)
        zero_one = zero_one_test(observable)
        bands = min(range(1, min(max_period, ZERO_ONE_MAX_BANDS) + 1), key=mismatches.get)
        if bands > 1:
            evidence["zero_one_bands"] = bands
            evidence["zero_one_banded"] = zero_one_test(observable, bands=bands)
        evidence["birkhoff_digits"] = birkhoff_digits(observable)
    regime, confidence = _aperiodic_regime(exponent, exponent_error, zero_one, evidence)
    return Regime(
        regime,
        strobe_mismatch=mismatch,
        max_exponent=None if exponent is None else float(exponent),
        max_exponent_error=None if exponent_error is None else float(exponent_error),
        zero_one=zero_one,
        confidence=confidence,
        evidence=evidence,
    )


# ========================================================== 0-1 test
def zero_one_test(
    observable: Sequence[float],
    *,
    c_values: int | Sequence[float] = 100,
    seed: int = 0,
    bands: int = 1,
) -> float:
    """The 0-1 test for chaos (Gottwald & Melbourne 2004, 2009): K in about [0, 1].

    For each c, the translation variables ``p_c(n) = sum_{j<=n} phi_j cos(j c)``
    and ``q_c(n) = sum_{j<=n} phi_j sin(j c)`` are built; the modified mean
    square displacement ``D_c(n) = M_c(n) - (mean phi)^2 (1 - cos n c) /
    (1 - cos c)``, with ``M_c(n)`` the mean of ``|z(j + n) - z(j)|^2`` over j,
    grows linearly in n for chaotic data and stays bounded for regular data;
    ``K_c`` is the correlation of ``D_c(n)`` with n for n = 1 .. N/10, and K
    the median of ``K_c`` over the c values (Gottwald & Melbourne 2009, SIAM
    J. Appl. Dyn. Syst. 8, 129, "On the implementation of the 0-1 test").

    A banded attractor (chaos visiting ``bands`` regions in turn, as after a
    period-doubling cascade) gives an observable ``phi_j = a_(j mod bands) +
    xi_j``: its band pattern adds to ``M_c(n)`` a bounded oscillation that, over
    a record of 1000 values, can be far larger than the chaotic part's linear
    growth, and K comes out near 0 (fig4 at T/T_Ax 0.98: K = 0.09 against a
    largest exponent 12 standard errors above zero). With ``bands`` > 1 the
    mean of each band (the values ``j mod bands`` apart) is removed first, the
    oscillation term then vanishing: the test sees ``xi``, which is chaotic
    exactly when the attractor is (the bands' return map is the map's
    ``bands``-th iterate) and, in theory, regular when it is, since removing a
    periodic pattern from a periodic or quasi-periodic signal leaves one. Over
    1000 values some of fig4's banded near-tori (exponent within its error of 0)
    give 0.8 - 1, which is why :func:`classify_sequence` uses this K only to
    lift the plain test's veto of a positive exponent.

    Parameters
    ----------
    observable : sequence of float
        A scalar observable sampled once per excitation cycle (or map step),
        at least 20 values.
    c_values : int or sequence of float
        Number of c drawn uniformly from (pi/5, 4 pi/5), or the c values.
    seed : int
        Seed of the random c values (reproducible K).
    bands : int
        Number of bands whose means are removed first (1: the plain test;
        :func:`classify_sequence` passes the period <= 8 whose sections move least).

    Returns
    -------
    float
        K: near 1 for chaotic, near 0 for periodic or quasi-periodic data.
    """
    phi = np.asarray(observable, dtype=float).ravel()
    if phi.size < 20 or not np.all(np.isfinite(phi)):
        raise ValueError(f"observable has {phi.size} values: need at least 20 finite values")
    if not (isinstance(bands, int | np.integer) and 1 <= bands <= phi.size // 10):
        raise ValueError(f"bands = {bands}: need an integer from 1 to a tenth of the "
                         f"{phi.size} values")
    if bands > 1:
        phi = phi.copy()
        for band in range(bands):
            phi[band::bands] -= phi[band::bands].mean()
    if isinstance(c_values, int | np.integer):
        if c_values < 1:
            raise ValueError(f"c_values = {c_values}: must be >= 1")
        c = np.random.default_rng(seed).uniform(*ZERO_ONE_C_RANGE, size=int(c_values))
    else:
        c = np.asarray(c_values, dtype=float).ravel()
        if c.size == 0 or np.any(np.cos(c) >= 1.0 - 1e-12):
            raise ValueError("c_values: need at least one c with cos(c) < 1")
    spread = float(np.ptp(phi))
    if spread == 0.0:
        return 0.0  # a constant signal is regular (and D_c would be 0 / 0)
    n_total = phi.size
    n_cut = max(n_total // 10, 3)
    z = np.cumsum(phi[None, :] * _phases(c, n_total), axis=1)
    lags = np.arange(1, n_cut + 1)
    msd = mean_square_displacement(z, n_cut)
    oscillation = np.mean(phi) ** 2 * (1.0 - np.cos(np.outer(c, lags))) / (1.0 - np.cos(c))[:, None]
    displacement = msd - oscillation
    return float(np.median(_row_correlations(lags, displacement)))


_PHASES: dict = {}  #: exp(i c j) tables of :func:`_phases`, by record length and c


def _phases(c: np.ndarray, n_total: int) -> np.ndarray:
    """``exp(i c j)`` for j = 1 .. n_total, a row per c (read-only).

    Every 0-1 test of a classification draws the same c (the same seed) over records
    of one or two lengths, and the plain and band-corrected tests share them: the
    table is kept (a few, 1.6 MB for 100 c and 1001 values) instead of recomputed,
    half of the test's time.
    """
    key = (n_total, c.tobytes())
    table = _PHASES.get(key)
    if table is None:
        if len(_PHASES) >= 4:
            _PHASES.clear()
        table = np.exp(1j * np.outer(c, np.arange(1, n_total + 1)))
        table.setflags(write=False)
        _PHASES[key] = table
    return table


def birkhoff_digits(observable: Sequence[float]) -> float:
    """Digits to which the weighted Birkhoff averages of the two halves of a record agree.

    ``WB(x_0 .. x_{N-1}) = sum_n w(n / N) x_n / sum_n w(n / N)`` with the bump
    ``w(s) = exp(-1 / (s (1 - s)))``, which vanishes with all its derivatives
    at both ends; the digits are ``-log10(|WB(first half) - WB(second half)|
    / spread)``, the spread being the observable's range. On a quasi-periodic
    orbit (a smooth torus, conjugate to a rotation) the weighted average
    converges faster than any power of N, so the halves agree to many digits,
    up to the integration's accuracy; on a chaotic attractor the error falls
    as N^(-1/2). Das, Saiki, Sander & Yorke, "Quantitative quasiperiodicity",
    Nonlinearity 30, 4111 (2017); Duignan & Meiss, "Distinguishing between
    regular and chaotic orbits of flows by the weighted Birkhoff average",
    Physica D 449, 133749 (2023), whose criterion this is.

    Parameters
    ----------
    observable : sequence of float
        A scalar observable sampled once per excitation cycle, at least 20 values.

    Returns
    -------
    float
        The digits (large: regular; docs/classification.md gives those of the
        records of fig4's scan); inf for a constant signal.
    """
    x = np.asarray(observable, dtype=float).ravel()
    if x.size < 20 or not np.all(np.isfinite(x)):
        raise ValueError(f"observable has {x.size} values: need at least 20 finite values")
    half = x.size // 2
    s = np.arange(1, half + 1) / (half + 1)
    weight = np.exp(-1.0 / (s * (1.0 - s)))
    weight /= weight.sum()
    difference = abs(float(weight @ x[:half]) - float(weight @ x[half:2 * half]))
    spread = float(np.ptp(x))
    if difference == 0.0 or spread == 0.0:
        return math.inf
    return -math.log10(difference / spread)


def mean_square_displacement(z: np.ndarray, n_cut: int) -> np.ndarray:
    """``M(n) = mean_j |z(j + n) - z(j)|^2`` for n = 1 .. n_cut, for each row of z.

    With ``S(n) = sum_{j < N - n} |z(j + n) - z(j)|^2 = sum_{j >= n} |z(j)|^2 +
    sum_{j < N - n} |z(j)|^2 - 2 Re sum_j z(j + n) conj(z(j))``: two prefix sums
    and the autocorrelation, by FFT (zero-padded to at least N + n_cut, so not
    circular at the lags asked for): O(N log N) per row instead of the direct
    O(N n_cut), 20 times faster at N = 1000, n_cut = 100, to about 1e-13 of M
    (the subtraction loses a few digits where |z| is large beside the displacements:
    tests/test_classify.py checks it against the direct sum).

    Parameters
    ----------
    z : ndarray, shape (rows, N)
        Complex series (the 0-1 test's translation variables p + i q).
    n_cut : int
        Largest lag, < N.

    Returns
    -------
    ndarray, shape (rows, n_cut)
    """
    n_total = z.shape[1]
    size = scipy.fft.next_fast_len(n_total + n_cut)  # no wrap-around at lags <= n_cut
    spectrum = scipy.fft.fft(z, size, axis=1)
    spectrum *= np.conj(spectrum)
    auto = scipy.fft.ifft(spectrum, axis=1, overwrite_x=True)[:, 1:n_cut + 1].real
    energy = np.cumsum(np.abs(z) ** 2, axis=1)
    lags = np.arange(1, n_cut + 1)
    tail = energy[:, -1:] - energy[:, lags - 1]  # sum over j >= n
    head = energy[:, n_total - 1 - lags]  # sum over j < N - n
    return (tail + head - 2.0 * auto) / (n_total - lags)


# ================================================================ helpers
def _check_arguments(min_transient, max_transient, chunk, window, max_period, lyapunov_cycles):
    if int(max_period) < 1:
        raise ValueError(f"max_period = {max_period}: must be an integer >= 1")
    if int(min_transient) < 1:
        raise ValueError(f"min_transient = {min_transient}: must be an integer >= 1")
    if int(max_transient) < int(min_transient):
        raise ValueError(
            f"max_transient = {max_transient}: must be >= min_transient = {min_transient}"
        )
    if int(chunk) < 1:
        raise ValueError(f"chunk = {chunk}: must be an integer >= 1")
    if int(window) < 2 * int(max_period):
        raise ValueError(f"window = {window}: must be at least twice max_period ({max_period}): "
                         f">= {2 * int(max_period)}")
    if int(lyapunov_cycles) < 10:
        raise ValueError(f"lyapunov_cycles = {lyapunov_cycles}: must be an integer >= 10")


def _check_tol(tol: float) -> float:
    tol = float(tol)
    if not (math.isfinite(tol) and tol > 0.0):
        raise ValueError(f"tol = {tol}: must be a finite number > 0")
    return tol


def _classification_system(system: System) -> tuple[System, float, float]:
    """The system with its solver settings tightened to rtol <= 1e-8 (rule 1).

    A system made from a scene keeps a scene that carries those settings (what
    the runs report); nothing is packed again.
    """
    settings = {
        "method": system.method,
        "steps_per_cycle": system.steps_per_cycle,
        "max_steps": system.max_steps,
        "restart_at_kinks": system.restart_at_kinks,
    }
    if system.method == "rk4":
        rtol, atol = CLASSIFY_RTOL, math.nan
    else:
        rtol = min(system.rtol, CLASSIFY_RTOL)
        atol = min(system.atol, ATOL_PER_RTOL * rtol)
        settings.update(rtol=rtol, atol=atol)
    return _with_solver(system, settings), rtol, atol


def _with_solver(system: System, settings: dict) -> System:
    """``system.with_solver(**settings)``, its scene (what the runs report) carrying
    the settings too; nothing is packed again."""
    changed = system.with_solver(**settings)
    if system.scene is not None:
        changed = replace(changed, scene=system.scene.with_params(**settings))
    return changed


def _phase_from_section(time, cycle, period, section_phase) -> np.ndarray:
    """Phase of each impact within its cycle, counted from the section, in [0, 1)."""
    return np.clip(np.asarray(time) / period - section_phase - np.asarray(cycle), 0.0, None)


def length_weights(scene: Scene, state_names: Sequence[str]) -> np.ndarray:
    """Per-component factors putting the state in lengths and velocities (rule 2).

    Rotations and their rates are multiplied by the tower's radius of gyration
    so that every component of a section point is in A_g or A_g omega_Ax.
    """
    rho = {"A": scene.tower_A.rho, "B": scene.tower_B.rho}
    return np.array([rho[name[-1]] if name.lstrip("d").startswith("th_") else 1.0
                     for name in state_names])


def _tail_length(max_period: int) -> int:
    """Sections the convergence test looks at: enough for every P <= max_period."""
    return max(3 * max_period, TAIL_MIN + max_period) + 1


def _scale(states: np.ndarray) -> float:
    """Largest Euclidean norm of the section points (1 for an all-zero record)."""
    scale = float(np.max(np.linalg.norm(states, axis=1)))
    return scale if scale > 0.0 else 1.0


def _mismatch(states: np.ndarray, period: int, scale: float) -> float:
    """max_k |x_{k+P} - x_k| / scale over the record."""
    return float(np.max(np.linalg.norm(states[period:] - states[:-period], axis=1)) / scale)


def _converged_period(states: np.ndarray, max_period: int, tol: float) -> int | None:
    """Smallest P whose last max(2P, TAIL_MIN) mismatches are all below tol (rule 3).

    All the periods at once (:func:`_period_pairs`): a sweep point runs this after
    every few cycles, so it must cost little beside them."""
    pairs = _period_pairs(states.shape[0] - 1, int(max_period))
    if pairs is None:
        return None
    periods, rows, earlier, counted = pairs
    distance = np.linalg.norm(states[rows] - states[earlier], axis=2)
    worst = np.max(distance * counted, axis=0) / _scale(states)
    below = np.flatnonzero(worst < tol)
    return int(periods[below[0]]) if below.size else None


@functools.lru_cache(maxsize=64)
def _period_pairs(last: int, max_period: int):
    """The section pairs :func:`_converged_period` compares in a tail ending at ``last``.

    Returns ``(periods, rows, earlier, counted)``: the periods P that fit (the first
    that does not ends the search), the rows compared (newest first, shape (m, 1)),
    the rows P before them (m, periods) and 1.0 where the pair is among P's last
    max(2P, TAIL_MIN), else 0.0; None when no period fits.
    """
    periods = np.arange(1, max_period + 1)
    comparisons = np.maximum(2 * periods, TAIL_MIN)
    fits = last >= comparisons + periods - 1
    stop = len(fits) if fits.all() else int(np.argmin(fits))
    if stop == 0:
        return None
    periods, comparisons = periods[:stop], comparisons[:stop]
    rows = last - np.arange(int(comparisons[-1]))[:, None]
    earlier = rows - periods[None, :]
    counted = (np.arange(rows.shape[0])[:, None] < comparisons[None, :]).astype(float)
    return periods, rows, np.maximum(earlier, 0), counted


@dataclass(frozen=True)
class _Impacts:
    time: np.ndarray  # cycle + phase, in cycles
    velocity: np.ndarray
    labels: list[str]

    @property
    def n(self) -> int:
        return int(self.time.shape[0])


def _impact_table(cycles, phases, velocities, corners) -> _Impacts:
    cycles = np.asarray(cycles, dtype=float).ravel()
    phases = np.asarray(phases, dtype=float).ravel()
    velocities = np.asarray(velocities, dtype=float).ravel()
    labels = [CORNER_LABELS[int(c)] if isinstance(c, int | np.integer) else str(c)
              for c in corners]
    sizes = {cycles.size, phases.size, velocities.size, len(labels)}
    if len(sizes) != 1:
        raise ValueError(
            f"impact arrays have {cycles.size}, {phases.size}, {velocities.size} and "
            f"{len(labels)} entries: need one of each per impact"
        )
    unknown = sorted(set(labels) - set(CORNER_LABELS))
    if unknown:
        raise ValueError(f"impact corner {unknown[0]!r}: must be one of {', '.join(CORNER_LABELS)}")
    time = cycles + phases
    if not (np.all(np.isfinite(time)) and np.all(np.isfinite(velocities))):
        raise ValueError("impact cycles, phases and velocities must be finite")
    return _Impacts(time=time - cycles.min() if cycles.size else time, velocity=velocities,
                    labels=labels)


def _repeating_group(impacts: _Impacts, period: int, tol: float, cycles: int) -> list[str] | None:
    """Corner labels of one period if the impacts repeat every ``period`` cycles, else None.

    Impact i + n must follow impact i by ``period`` cycles, at the same corner
    and with the same velocity, n being the number of impacts in one period,
    and the impacts must span the record of ``cycles`` cycles but one period.
    """
    if impacts.n == 0:
        return []
    time, velocity, labels = impacts.time, impacts.velocity, impacts.labels
    shift = int(np.argmin(np.abs(time - (time[0] + period))))
    if shift == 0 or abs(time[shift] - time[0] - period) > IMPACT_TOL_FACTOR * tol:
        return None
    if time[-1] - time[0] < cycles - 2 * period:
        return None
    v_scale = max(float(np.max(np.abs(velocity))), 1e-12)
    gaps = time[shift:] - time[:-shift]
    same_corner = all(a == b for a, b in zip(labels[shift:], labels[:-shift], strict=True))
    if (
        not same_corner
        or np.max(np.abs(gaps - period)) > IMPACT_TOL_FACTOR * tol
        or np.max(np.abs(velocity[shift:] - velocity[:-shift])) > IMPACT_TOL_FACTOR * tol * v_scale
    ):
        return None
    return labels[:shift]


def _aperiodic_regime(exponent, error, zero_one, evidence) -> tuple[str, float]:
    """Rules 6 and 7: (regime, confidence) without a period.

    Beside a positive exponent, the 0-1 test's evidence is the larger of its plain K
    and its K less the band means (``evidence["zero_one_banded"]``, computed where the
    sections have bands): banded chaos looks regular to the plain test, whose veto it
    lifts. Everywhere else (regularity, rule 7) the plain K decides: removing the bands
    of some of fig4's banded near-tori raises K to 0.8 - 1 over 1000 sections while
    their exponent stays within its error of 0 (docs/classification.md, rule 6)."""
    chaos_k = None if zero_one is None else max(
        zero_one, evidence.get("zero_one_banded", zero_one))
    k_chaos = None if chaos_k is None else _zero_one_chaos(chaos_k)
    k_regular = None if zero_one is None else _clip(
        (ZERO_ONE_REGULAR - zero_one) / ZERO_ONE_REGULAR)
    if exponent is not None and error is not None and math.isfinite(exponent):
        z = float(exponent) / max(float(error), 1e-300)
        evidence["exponent_over_error"] = z
        if z > SIGMAS and (chaos_k is None or chaos_k >= ZERO_ONE_REGULAR):
            parts = [_clip((z - SIGMAS) / (Z_FULL_CONFIDENCE - SIGMAS)), k_chaos]
            return "chaotic", min(p for p in parts if p is not None)
        digits = evidence.get("birkhoff_digits")
        k_digits = None if digits is None else _clip(
            (digits - BIRKHOFF_DIGITS_REGULAR) / BIRKHOFF_DECADES)
        by_zero_one = zero_one is not None and zero_one < ZERO_ONE_REGULAR
        by_birkhoff = digits is not None and digits >= BIRKHOFF_DIGITS_REGULAR
        if abs(z) <= SIGMAS and (by_zero_one or by_birkhoff):
            regular = max(k for k in (k_regular, k_digits) if k is not None)
            return "quasi-periodic", min(_clip(1.0 - abs(z) / SIGMAS), regular)
        return "unresolved", 0.0
    if zero_one is None:
        return "unresolved", 0.0
    if zero_one > ZERO_ONE_CHAOTIC:
        return "chaotic", _zero_one_chaos(zero_one)
    if zero_one < ZERO_ONE_REGULAR:
        return "quasi-periodic", k_regular
    return "unresolved", 0.0


def vetoed(regime: Regime) -> bool:
    """Rule 6's veto: an unresolved reading whose exponent is above 3 sigma and
    whose 0-1 test, with and without the bands, says "regular" (K < 0.2).

    The 0-1 test needs its record to span many Lyapunov times: fig4 at T/T_Ax
    0.7357, gap 1.4573 (an exponent of 0.0061 +- 0.0005, 0.028 a cycle) gives K =
    0.18 over 1000 sections, 0.37 over 4000 and 0.83 over 16000. Both
    classifications then read LONGER_RUN times the sections before the veto stands.
    """
    if regime.regime != "unresolved" or regime.zero_one is None:
        return False
    z = regime.evidence.get("exponent_over_error")
    k = max(regime.zero_one, regime.evidence.get("zero_one_banded", regime.zero_one))
    return z is not None and z > SIGMAS and k < ZERO_ONE_REGULAR


def _zero_one_chaos(k: float) -> float:
    """The 0-1 test's confidence in chaos: 0 at K = 0.2, 1 at K = 0.8."""
    return _clip((k - ZERO_ONE_REGULAR) / (ZERO_ONE_CHAOTIC - ZERO_ONE_REGULAR))


def _mismatch_confidence(mismatch: float, tol: float) -> float:
    if mismatch <= 0.0:
        return 1.0
    return _clip(math.log10(tol / mismatch) / MISMATCH_DECADES)


def _principal_component(states: np.ndarray) -> np.ndarray:
    """The scaled sections projected on their direction of largest variance."""
    centred = states - states.mean(axis=0)
    if states.shape[1] == 1:
        return states[:, 0]
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    return states @ vt[0]


def _row_correlations(x: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """:func:`_correlation` of x with each row of ``rows`` (0 for a constant row)."""
    sx = np.std(x)
    sy = np.std(rows, axis=1)
    cov = np.mean((x - x.mean()) * (rows - rows.mean(axis=1, keepdims=True)), axis=1)
    out = np.zeros(rows.shape[0])
    ok = (sy != 0.0) & (sx != 0.0)
    out[ok] = cov[ok] / (sx * sy[ok])
    return out


def _clip(value: float) -> float:
    return float(min(max(value, 0.0), 1.0))


def _plain(value):
    """Evidence as JSON types (numpy scalars to Python numbers)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    return value
