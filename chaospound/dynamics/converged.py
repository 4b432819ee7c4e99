"""Converged classification at scan speed: the default regime of a sweep point.

:func:`classify_converged` names the same regimes as
:func:`chaospound.dynamics.classify.classify` (rules, tolerances and
confidences of ``docs/classification.md``), doing less work per point:

1. Start. From the scene's initial state at t = 0 (fresh, a sweep's default)
   or from a warm state (``start_state``: on a continuation branch the
   previous point's last section).
   A warm start runs ``WARM_FIRST`` cycles first, a fresh one ``FRESH_FIRST``.
2. Sections. Then ``CHUNK`` cycles at a time. After each run the tail of the
   sections is tested as :func:`classify` rule 3 does (last max(2P, 10)
   pairs P apart within tol / 10, the smallest P <= max_period).
3. Newton. As soon as the tail repeats with some period P to within
   ``NEWTON_TRY`` (a loose 1e-2: the orbit is near, not reached), or rule 3
   holds, Newton's method (:func:`chaospound.orbits.shooting.newton_fixed_point`,
   the classification's rtol, the variational monodromy, giving up at the first
   step that does not descend) solves P^P(x) = x from the last section. A
   converged orbit whose Floquet multipliers (the monodromy at rtol 1e-6: its
   stability, not its digits, is asked) are all
   inside the unit circle is the attractor: a record of max(3P, 8) cycles from
   the orbit's state is classified by
   :func:`~chaospound.dynamics.classify.classify_sequence` at tol (its
   smallest period, impacts per period, corner sequence; ``none`` without an
   impact). Its confidence is the smaller of the window's mismatch confidence
   (classify's) and ``(1 - max|mu|) / MU_MARGIN`` clipped to [0, 1] (a
   multiplier near the unit circle: near a bifurcation). An unstable orbit, or
   no convergence, is noted in the evidence and the runs go on; each period
   is tried at most twice per point. A tail converged by rule 3 whose Newton
   run fails (a grazing orbit, where P is not smooth) is classified from its
   window as :func:`classify` does.
4. Exponent. When no period is in sight after ``EXPONENT_AFTER`` cycles, the
   largest exponent (one tangent vector, QR at every section, the tangent
   aligned over ``TANGENT_ALIGN`` cycles) is accumulated in blocks of
   ``BLOCK`` cycles, at ``EXPONENT_RTOL`` (1e-6: a statistic, not a mismatch
   at tol, decides here, and it costs half as much as at 1e-8; the two agree
   within their error bars, tests/test_converged.py): lambda is the mean over
   all blocks, sigma the standard error of the block means, from
   ``BATCH_FROM`` blocks on that of batch means of about sqrt(N) blocks (an
   impact's stretching and the contraction after it make neighbouring blocks
   anti-correlated), widened for correlated ones (:func:`_mean_and_error`: a
   torus's block exponents drift together). After at least
   ``MIN_BLOCKS`` blocks it stops as
   soon as |lambda| / sigma > ``Z_EARLY`` (a margin above the 3-sigma line
   for deciding early), or at ``EXPONENT_CAP`` cycles, where the 3-sigma line
   itself decides. The blocks' sections are watched too: after a block that
   contracted (a negative block exponent) the tail is tested as in step 2 and
   step 3 acts on it (a long transient ending on a stable orbit is confirmed
   there, not after the cap and a 0-1 record); a failed attempt lets the
   blocks go on, the next attempt waiting for a fresh tail.
   lambda above it: chaotic (the 0-1 test is not needed;
   confidence as classify's exponent part), once the point has run
   ``CHAOS_WATCH`` cycles in all: until then the sections go on at
   ``WATCH_RTOL``, ``WATCH_CHUNK`` cycles at a time, each run's tail
   tested as in step 2, and a chaotic transient that settles on a stable orbit
   is that orbit, confirmed by step 3 (fig4's scan: 22 of 277 points read
   chaotic after some 100-300 cycles settle on group-periodic orbits before
   1000; the careful classifier, which runs 6000, names them so too). lambda
   below minus it: the motion
   contracts, a period is near: back to step 2 from the current state.
5. 0-1 test, only where the exponent cannot decide (|lambda| / sigma <= 3
   at the cap): ``ZERO_ONE_CYCLES`` sections are recorded, at ``EXPONENT_RTOL``
   too, with the impacts of their last ``record`` cycles only (rule 6 reads the
   sections; the impacts of all of them where the sections repeat within tol
   or those cycles have none: :meth:`_Classifier._zero_one_record`); if their
   tail has settled to a period (rule 3 at tol: a long transient ended), or
   comes within ``NEWTON_TRY`` of one that Newton has not yet been tried at
   twice (a weakly stable orbit, blurred by the looser runs), the search goes
   back to step 3, else
   :func:`classify_sequence` applies classify's rule 6 (period, then lambda
   against 3 sigma and K). Where rule 6 cannot name the point, or names it
   quasi-periodic with lambda more than 1 sigma above zero (weak chaos, its 0-1
   test still below 0.2 over 1000 sections, looks so at the cap), the exponent
   goes on from the record's end, up to ``LONGER_RUN`` times ``EXPONENT_CAP``
   cycles in all (classify's rerun near the 3-sigma line), stopping early as in
   step 4, and rule 6 reads the record again with it. Where the 0-1 test vetoes a
   positive exponent (:func:`~chaospound.dynamics.classify.vetoed`), the record
   goes on for ``LONGER_RUN - 1`` times ``ZERO_ONE_CYCLES`` more sections, as
   classify's rule 6 does, and rule 6 reads the whole.
6. Budget. At most ``max_transient`` cycles of sections and exponents;
   beyond, ``unresolved`` with the reason in ``evidence["why"]``.

Every result carries the evidence behind it (``start``, ``cycles_run``,
``newton`` attempts with residuals and max|mu|, the exponent's blocks, ...),
the regime's ``transient_used`` being the cycles run before the record.

Units: exponents per unit normalised time t = tau omega_Ax; periods, budgets
and transients in excitation cycles.
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass, replace

import numpy as np

from ..scene import Scene
from .classify import (
    AMBIGUOUS_Z,
    ATOL_PER_RTOL,
    LONGER_RUN,
    NEWTON_TRY,
    SIGMAS,
    TOL_PER_RTOL,
    TRANSIENT_MARGIN,
    Z_FULL_CONFIDENCE,
    Regime,
    _classification_system,
    _converged_period,
    _mismatch,
    _phase_from_section,
    _scale,
    _tail_length,
    _with_solver,
    classify_sequence,
    length_weights,
    newton_orbit,
    vetoed,
    with_exponent,
)
from .system import System, advance, as_system, evolve

__all__ = ["ConvergedResult", "classify_converged"]

WARM_FIRST = 10  #: cycles run first from a warm start
FRESH_FIRST = 30  #: cycles run first from the scene's initial state
CHUNK = 10  #: cycles per further run of sections
NEWTON_ATTEMPTS = 2  #: attempts per period and point
MU_MARGIN = 0.05  #: max|mu| <= 1 - MU_MARGIN: full confidence in the orbit's stability
EXPONENT_AFTER = 40  #: cycles of sections without a period in sight before the exponent
TANGENT_ALIGN = 10  #: cycles aligning the tangent vector (discarded)
BLOCK = 10  #: cycles per block of the exponent
MIN_BLOCKS = 5  #: blocks before the exponent may decide
CORRELATION_BLOCKS = 5  #: blocks from which their correlation widens the error
#: blocks from which the error is that of batch means (:func:`_mean_and_error`)
BATCH_FROM = 40
Z_EARLY = 4.0  #: |lambda| / sigma deciding before the cap
EXPONENT_CAP = 300  #: cycles of exponent at most per stage
#: cycles a point must have run before a positive exponent names it chaotic: a chaotic
#: transient that ends on a stable orbit within them is that orbit (fig4: 22 of 277)
CHAOS_WATCH = 1000
WATCH_CHUNK = 50  #: cycles per run of the sections while watching
#: their rtol: the watch asks only whether a period comes within NEWTON_TRY (1e-2) for
#: Newton to start from (it then runs at the classification's rtol)
WATCH_RTOL = 1e-5
ZERO_ONE_CYCLES = 1000  #: sections recorded for the 0-1 test (as classify)
#: rtol of the exponent's and the 0-1 test's runs (atol ATOL_PER_RTOL times it): their
#: statistics, not a mismatch at tol, decide, and they cost half as much as at 1e-8
#: (docs/classification.md, "Sweeps", step 4)
EXPONENT_RTOL = 1e-6
MIN_WINDOW = 8  #: default record of a result (a sweep passes the scene's record)


@dataclass(frozen=True)
class ConvergedResult:
    """A converged classification and the record behind it.

    Attributes
    ----------
    regime : Regime
        The label, confidence, ``transient_used`` and evidence.
    record : Simulation
        The record window the label was read from (sections and impacts),
        starting at a section.
    final_state : ndarray (n,)
        The last section of the record: the next point's warm start.
    """

    regime: Regime
    record: object
    final_state: np.ndarray


def classify_converged(
    system_or_scene: System | Scene,
    *,
    start_state: np.ndarray | None = None,
    max_period: int = 16,
    max_transient: int = 2000,
    tol: float | None = None,
    newton: bool = True,
    record: int = MIN_WINDOW,
) -> ConvergedResult:
    """Classify the steady response of a scene or system, converged and fast.

    Parameters
    ----------
    system_or_scene : System or Scene
        What to classify (its solver tightened as classify's rule 1).
    start_state : ndarray, optional
        A section state to start from (warm start, e.g. the previous point's
        ``final_state``); default the system's initial state at t = 0.
    max_period : int
        Longest period searched, in cycles.
    max_transient : int
        Cycles of sections and exponents at most before the record.
    tol : float, optional
        Relative stroboscopic mismatch accepted as a repeat (default
        ``1e3 * rtol_used``, 1e-5).
    newton : bool
        Confirm periods by Newton's method and the Floquet multipliers
        (False: classify's rule 3 and 4 only, slower to converge).
    record : int
        Cycles of the record returned with the label (a sweep stores it; a
        periodic label's window has at least 3P cycles and is read at tol).

    Returns
    -------
    ConvergedResult

    Raises
    ------
    ValueError
        Bad arguments, or a system without impacts to classify.
    chaospound.simulate.SimulationError
        A run that could not finish.
    """
    if int(record) < 1:
        raise ValueError(f"record = {record}: must be an integer >= 1")
    return _Classifier(system_or_scene, max_period, max_transient, tol, newton,
                       int(record)).run(start_state)


class _Classifier:
    """The stages of :func:`classify_converged` over one point (see the module docstring)."""

    def __init__(self, system_or_scene, max_period, max_transient, tol, newton,
                 record: int = MIN_WINDOW) -> None:
        from ..kernels.params import CUSTOM

        system = as_system(system_or_scene)
        if system.ground not in ("sine", "none"):
            raise ValueError(f"ground = {system.ground}: regimes are defined for periodic "
                             "forcing")
        if system.scene is None and not (system.model_id == CUSTOM and system.has_gap):
            raise ValueError(f"system {system.name!r} has no impacts to classify")
        if int(max_period) < 1:
            raise ValueError(f"max_period = {max_period}: must be an integer >= 1")
        if int(max_transient) < FRESH_FIRST:
            raise ValueError(f"max_transient = {max_transient}: must be >= {FRESH_FIRST}")
        self.system = system
        self.max_period = int(max_period)
        self.max_transient = int(max_transient)
        self.newton = newton
        self.record = record
        self.target, self.rtol, self.atol = _classification_system(system)
        self.flow = _exponent_system(self.target, self.rtol)
        self.watch_flow = (self.flow if self.flow.method == "rk4" or self.flow.rtol >= WATCH_RTOL
                           else _with_solver(self.target, {"rtol": WATCH_RTOL,
                                                           "atol": ATOL_PER_RTOL * WATCH_RTOL}))
        self.tol = TOL_PER_RTOL * self.rtol if tol is None else float(tol)
        if not (math.isfinite(self.tol) and self.tol > 0.0):
            raise ValueError(f"tol = {tol}: must be a finite number > 0")
        if system.scene is not None:
            self.weights = length_weights(self.target.scene, system.state_names)
            self.section_phase = self.target.scene.run.phase
        else:
            self.weights = np.ones(system.dim)
            self.section_phase = 0.0
        self.cycles = 0
        self.sections: list[np.ndarray] = []
        self.attempts: dict[int, int] = {}
        self.evidence: dict = {"rtol": self.rtol, "atol": self.atol,
                               "exponent_rtol": self.flow.rtol, "newton": [],
                               "exponent_stages": []}
        self._smap = None

    # ------------------------------------------------------------- driver
    def run(self, start_state) -> ConvergedResult:
        from ..simulate import simulate

        warm = start_state is not None
        self.evidence["start"] = "warm" if warm else "fresh"
        if warm:
            first = simulate(self.target, transient=0, record=WARM_FIRST,
                             initial_state=np.asarray(start_state, float), start_at_section=True)
            self.cycles = WARM_FIRST
        else:
            first = simulate(self.target, transient=0, record=FRESH_FIRST,
                             initial_state=self.system.initial_state)
            self.cycles = FRESH_FIRST
        self.sections = [first.strobe.state]
        since_exponent = 0 if warm else FRESH_FIRST - EXPONENT_AFTER // 2
        while True:
            found = self._try_period()
            if found is not None:
                return found
            if self.cycles >= self.max_transient:
                return self._unresolved("no period and no exponent decision within "
                                        f"{self.max_transient} cycles")
            if since_exponent >= EXPONENT_AFTER:
                decided = self._exponent_stage()
                if decided is not None:
                    return decided
                since_exponent = 0  # contracting: look for the period again
                continue
            self._more_sections(CHUNK)
            since_exponent += CHUNK

    # ------------------------------------------------------------- stages
    def _last(self) -> np.ndarray:
        return self.sections[-1][-1]

    def _more_sections(self, cycles: int) -> None:
        from ..simulate import simulate

        cycles = max(1, min(cycles, self.max_transient - self.cycles))
        run = simulate(self.target, transient=0, record=cycles, initial_state=self._last(),
                       start_at_section=True)
        self.sections.append(run.strobe.state[1:])
        self.cycles += cycles

    def _tail(self) -> np.ndarray:
        states = np.concatenate(self.sections)[-_tail_length(self.max_period):]
        if len(self.sections) > 4:
            self.sections = [states.copy()]  # keep the tail only
        return states * self.weights

    def _try_period(self) -> ConvergedResult | None:
        tail = self._tail()
        level = TRANSIENT_MARGIN * self.tol
        near = _converged_period(tail, self.max_period, max(NEWTON_TRY, level))
        if near is None:  # (neither converged nor near: one test decides most calls)
            return None
        converged = _converged_period(tail, self.max_period, level)
        candidate = converged if converged is not None else near
        if self.newton and self.attempts.get(candidate, 0) < NEWTON_ATTEMPTS:
            self.attempts[candidate] = self.attempts.get(candidate, 0) + 1
            confirmed = self._newton(candidate)
            if confirmed is not None:
                return confirmed
        if converged is not None:
            return self._window_result(self._last(), converged, newton=None)
        return None

    def _newton(self, period: int) -> ConvergedResult | None:
        from ..orbits.maps import StroboscopicMap

        if self._smap is None:
            self._smap = StroboscopicMap.of(self.target, rtol=self.rtol, atol=self.atol,
                                            method=None)
        note = {"period": period, "after_cycles": self.cycles}
        # the fixed point and its stability (the window reads the impacts)
        state, found = newton_orbit(self._smap, self._last(), period, give_up_early=True)
        note.update(found)
        if state is None:
            self.evidence["newton"].append(note)
            return None
        residual, mu = note["residual"], note["max_multiplier"]
        if not mu < 1.0:
            note["result"] = "unstable orbit"
            self.evidence["newton"].append(note)
            return None
        note["result"] = "stable orbit"
        self.evidence["newton"].append(note)
        return self._window_result(state, period, newton=(residual, mu))

    def _window_result(self, state, period: int, newton) -> ConvergedResult | None:
        """Record max(3P, record, 3) cycles from ``state`` and classify them at tol."""
        from ..simulate import simulate

        window = max(3 * period, self.record, 3)
        record = simulate(self.target, transient=0, record=window, initial_state=state,
                          start_at_section=True)
        imp = record.impacts
        phase = _phase_from_section(imp.time, imp.cycle, record.period, self.section_phase)
        regime = classify_sequence(record.strobe.state * self.weights, imp.cycle, phase,
                                   imp.velocity, imp.labels,
                                   max_period=min(self.max_period, (window - 1) // 2 or 1),
                                   tol=self.tol, test01=False)
        if regime.regime in ("unresolved", "quasi-periodic", "chaotic") or (
                regime.regime == "none" and regime.period_cycles is None):
            if newton is not None:
                self.evidence["newton"][-1]["result"] += ": its window did not repeat"
            return None
        found = regime.period_cycles or 1
        if max(3 * found, self.record, 3) < window:  # a shorter period: the usual record
            window = max(3 * found, self.record, 3)
            record = simulate(self.target, transient=0, record=window, initial_state=state,
                              start_at_section=True)
        confidence = regime.confidence
        if newton is not None:
            residual, mu = newton
            confidence = min(confidence, _clip((1.0 - mu) / MU_MARGIN))
            self.evidence.update(confirmed_by="newton", orbit_residual=residual,
                                 max_multiplier=mu)
        else:
            self.evidence.update(confirmed_by="sections")
        return self._result(regime, record, confidence=confidence, window=window)

    def _exponent_stage(self) -> ConvergedResult | None:
        """Step 4 (and 5 when the exponent cannot decide)."""
        n = self.flow.dim
        augmented = self._aligned_tangent(self._last())
        self.sections = [augmented[None, :n].copy()]
        blocks: list[float] = []
        stage: dict = {}
        self.evidence["exponent_stages"].append(stage)
        augmented, lam, err, z, found = self._blocks(augmented, blocks, EXPONENT_CAP,
                                                     watch=True)
        stage.update(cycles=BLOCK * len(blocks), blocks=len(blocks), exponent=lam,
                     error=err, exponent_over_error=z)
        if found is not None:
            stage["decision"] = "a period came in sight and was confirmed"
            return found
        state = augmented[:n].copy()
        self.sections = [state[None, :]]
        at_cap = abs(z) <= Z_EARLY  # the loop ended at the cap: the 3-sigma rule decides
        if z > (SIGMAS if at_cap else Z_EARLY):
            found = self._watch_chaos()
            stage["watched_to"] = self.cycles
            if found is not None:
                stage["decision"] = "chaotic transient: the sections settled to a period"
                return found
            return self._chaotic(self._last(), lam, err, z)
        if z < -(SIGMAS if at_cap else Z_EARLY):
            stage["decision"] = "contracting: look for the period"
            self.sections = [self._record_sections(state)]
            return None
        if not blocks or len(blocks) < MIN_BLOCKS:
            return None  # the budget ran out: the driver says so
        return self._zero_one(state, lam, err, blocks)

    def _blocks(self, augmented, blocks: list[float], cycles: int, watch: bool = False):
        """Accumulate exponent blocks (appended to ``blocks``) from the tangent state
        ``augmented`` for at most ``cycles`` cycles (and the budget), stopping once
        ``|lambda| / sigma > Z_EARLY`` over all the blocks.

        With ``watch`` the blocks' sections also go to ``self.sections``, and after
        each block that contracted (a negative block exponent: the motion nears a
        stable orbit, not one of chaos's unstable ones) :meth:`_try_period` acts on
        the tail as in step 3 (a long transient ending); a confirmed period ends the
        blocks, a failed attempt leaves them going on, with a fresh tail for the
        next attempt.

        Returns ``(augmented, lambda, sigma, lambda / sigma, result)``, ``result``
        the confirmed period's or None.
        """
        period = self.flow.period
        n = self.flow.dim
        ran = 0
        lam = err = math.nan
        z = 0.0
        while ran < cycles and self.cycles < self.max_transient:
            run = evolve(self.flow, augmented, cycles=BLOCK, start_at_section=True,
                         tangent="qr")
            augmented = run.augmented_state
            blocks.append(float(run.tangent_log.sum()) / (BLOCK * period))
            ran += BLOCK
            self.cycles += BLOCK
            if len(blocks) >= MIN_BLOCKS:
                lam, err = _mean_and_error(blocks)
                z = lam / max(err, 1e-300)
            if watch:
                self.sections.append(run.sections[1:, :n])
                if blocks[-1] < 0.0:  # the block contracted: a stable orbit near?
                    tried = sum(self.attempts.values())
                    found = self._try_period()
                    if found is not None:
                        return augmented, lam, err, z, found
                    if sum(self.attempts.values()) > tried:
                        self.sections = [self.sections[-1][-1:]]
            if abs(z) > Z_EARLY:
                break
        return augmented, lam, err, z, None

    def _watch_chaos(self) -> ConvergedResult | None:
        """Run the sections on, ``WATCH_CHUNK`` cycles at a time at ``WATCH_RTOL``, until
        the point has run ``CHAOS_WATCH`` cycles in all, testing the tail after each run as
        step 2 does: a chaotic transient that settles on a stable orbit within them is
        confirmed by step 3 (Newton at the classification's rtol) and returned."""
        while self.cycles < min(CHAOS_WATCH, self.max_transient):
            cycles = min(WATCH_CHUNK, self.max_transient - self.cycles)
            run = evolve(self.watch_flow, self._last(), cycles=cycles, start_at_section=True)
            self.sections.append(run.sections[1:])
            self.cycles += cycles
            found = self._try_period()
            if found is not None:
                return found
        return None

    def _record_sections(self, state) -> np.ndarray:
        from ..simulate import simulate

        run = simulate(self.target, transient=0, record=CHUNK, initial_state=state,
                       start_at_section=True)
        self.cycles += CHUNK
        return run.strobe.state

    def _chaotic(self, state, lam, err, z) -> ConvergedResult:
        from ..simulate import simulate

        record = simulate(self.target, transient=0, record=max(self.record, 2),
                          initial_state=state, start_at_section=True)
        imp = record.impacts
        if len(imp) == 0:
            return self._unresolved("positive exponent but no impact in the record", record)
        states = record.strobe.state * self.weights
        scale = _scale(states)
        mismatch = _best_mismatch(states, scale)
        confidence = _clip((z - SIGMAS) / (Z_FULL_CONFIDENCE - SIGMAS))
        regime = Regime("chaotic", strobe_mismatch=mismatch, max_exponent=lam,
                        max_exponent_error=err, confidence=confidence,
                        evidence={"tol": self.tol, "scale": scale, "exponent_over_error": z})
        self.evidence["decided_by"] = "exponent"
        return self._result(regime, record, confidence=confidence, window=self.record)

    def _zero_one(self, state, lam, err, blocks: list[float]) -> ConvergedResult | None:
        record = self._zero_one_record(state)
        tail = record.strobe.state[-_tail_length(self.max_period):] * self.weights
        settled = _converged_period(tail, self.max_period, self.tol)
        if settled is None and self.newton:
            near = _converged_period(tail, self.max_period, NEWTON_TRY)
            if near is not None and self.attempts.get(near, 0) < NEWTON_ATTEMPTS:
                settled = near  # a weakly stable orbit, blurred at EXPONENT_RTOL: Newton decides
        if settled is not None:  # a long transient ended within the record: confirm it
            self.cycles += ZERO_ONE_CYCLES
            self.sections = [record.strobe.state[-_tail_length(self.max_period):]]
            self.evidence["exponent_stages"][-1]["decision"] = (
                f"sections settled to period {settled} during the 0-1 record")
            return None
        regime = self._read_record(record, lam, err)
        self.evidence["decided_by"] = "exponent and 0-1 test"
        leaning = regime.regime == "quasi-periodic" and lam > AMBIGUOUS_Z[0] * err
        if (regime.regime == "unresolved" or leaning) and self.cycles < self.max_transient:
            # the two disagree, or a torus's exponent leans positive: near the 3-sigma
            # line a run of EXPONENT_CAP cycles decides by chance (weak chaos's exponent
            # of a few 1e-3 is 1 to 3 sigma after 300 cycles, and 1000 sections are too
            # few for its 0-1 test), so the exponent goes on from the record's end for up
            # to LONGER_RUN times as long in all, as classify's rerun does, and decides anew
            lam, err = self._longer_exponent(record, blocks, leaning)
            regime = with_exponent(regime, lam, err)
        if vetoed(regime):
            # a positive exponent that the 0-1 test calls regular: LONGER_RUN times the
            # sections before the veto stands, as classify does (weak chaos's K rises
            # only over many Lyapunov times)
            more = self._zero_one_record(record.strobe.state[-1],
                                         (LONGER_RUN - 1) * ZERO_ONE_CYCLES)
            record = _joined(record.strobe.state, record.strobe.time[0], record.stats, more)
            self.evidence["zero_one_vetoed"] = regime.zero_one
            regime = self._read_record(record, lam, err)
        if regime.regime == "unresolved":
            k = regime.zero_one
            digits = regime.evidence.get("birkhoff_digits")
            sections = record.strobe.state.shape[0]
            self.evidence["why"] = (
                f"exponent {lam:+.3g} +- {err:.2g} ({lam / max(err, 1e-300):+.1f} sigma) "
                f"after {BLOCK * len(blocks)} cycles"
                + (f", but the 0-1 test over {sections} sections says regular (K = "
                   f"{k:.2f})" if vetoed(regime) else
                   " and 0-1 test K = "
                   + ("n/a" if k is None else f"{k:.2f}")
                   + ("" if digits is None else
                      f", Birkhoff average to {digits:.1f} digits")
                   + " do not agree on a regime"))
        return self._result(regime, record, confidence=regime.confidence,
                            window=record.record)

    def _zero_one_record(self, state, cycles: int = ZERO_ONE_CYCLES):
        """``cycles`` sections from ``state``, with the impacts of the last
        ``record`` cycles only (locating every impact and its peak is about 30 % of such
        a run, and rule 6 reads only the sections). The impacts of the whole window
        where the label may need them: none in those cycles (rule 5 would read
        ``none``), or a period within tol over the sections (rule 4's group check
        reads the impacts of the whole window)."""
        from ..simulate import run_stats, simulate

        window = min(max(self.record, 2), cycles)
        offset = cycles - window
        head = evolve(self.flow, state, cycles=offset, start_at_section=True)
        record = simulate(self.flow, transient=0, record=window, initial_state=head.state,
                          start_at_section=True)
        states = np.concatenate([head.sections, record.strobe.state[1:]])
        scaled = states * self.weights
        if (len(record.impacts) == 0
                or _best_mismatch(scaled, _scale(scaled), self.max_period) < self.tol):
            return simulate(self.flow, transient=0, record=cycles,
                            initial_state=state, start_at_section=True)
        return _joined(head.sections, head.section_times[0], run_stats(head), record)

    def _read_record(self, record, lam: float, err: float) -> Regime:
        """Rule 6 on a record of sections and impacts, with the exponent and the 0-1 test."""
        imp = record.impacts
        phase = _phase_from_section(imp.time, imp.cycle, record.period, self.section_phase)
        return classify_sequence(record.strobe.state * self.weights, imp.cycle, phase,
                                 imp.velocity, imp.labels, max_period=self.max_period,
                                 tol=self.tol, exponent=lam, exponent_error=err, test01=True)

    def _aligned_tangent(self, state) -> np.ndarray:
        """State and one tangent vector, aligned over ``TANGENT_ALIGN`` cycles from ``state``."""
        n = self.flow.dim
        augmented = np.zeros(2 * n)
        augmented[:n] = state
        augmented[n] = 1.0
        augmented, _, _ = advance(self.flow, augmented, TANGENT_ALIGN, tangent="qr",
                                  tangent_log=np.zeros((0, 1)), record_from=TANGENT_ALIGN)
        self.cycles += TANGENT_ALIGN
        return augmented

    def _longer_exponent(self, record, blocks: list[float],
                         leaning: bool = False) -> tuple[float, float]:
        """More exponent blocks (appended to ``blocks``) from the end of the 0-1 record.
        Returns ``(lambda, sigma)`` over all the blocks."""
        augmented = self._aligned_tangent(record.strobe.state[-1])
        before = len(blocks)
        _, lam, err, z, _ = self._blocks(augmented, blocks, (LONGER_RUN - 1) * EXPONENT_CAP)
        self.evidence["exponent_stages"].append({
            "cycles": BLOCK * (len(blocks) - before), "blocks": len(blocks) - before,
            "exponent": lam, "error": err,
            "exponent_over_error": z,
            "decision": ("a quasi-periodic reading with an exponent over 1 sigma: the "
                         "exponent went on") if leaning else
                        "exponent and 0-1 test disagreed: the exponent went on"})
        return lam, err

    # ------------------------------------------------------------- results
    def _result(self, regime: Regime, record, *, confidence: float,
                window: int) -> ConvergedResult:
        evidence = {**regime.evidence, **self.evidence, "window_cycles": window,
                    "cycles_run": self.cycles, "impacts_in_window": len(record.impacts)}
        regime = replace(regime, confidence=confidence, transient_used=self.cycles,
                         evidence=evidence)
        return ConvergedResult(regime=regime, record=record,
                               final_state=record.strobe.state[-1].copy())

    def _unresolved(self, why: str, record=None) -> ConvergedResult:
        from ..simulate import simulate

        if record is None:
            record = simulate(self.target, transient=0, record=max(self.record, 2),
                              initial_state=self._last(), start_at_section=True)
        states = record.strobe.state * self.weights
        scale = _scale(states)
        mismatch = _best_mismatch(states, scale)
        self.evidence["why"] = why
        regime = Regime("unresolved", strobe_mismatch=mismatch,
                        evidence={"tol": self.tol, "scale": scale})
        return self._result(regime, record, confidence=0.0, window=len(states) - 1)


def _exponent_system(target: System, rtol: float) -> System:
    """The classification's system at :data:`EXPONENT_RTOL` (or its own rtol, if looser;
    a fixed-step method unchanged): what the exponent and the 0-1 test run on."""
    if target.method == "rk4" or rtol >= EXPONENT_RTOL:
        return target
    return _with_solver(target, {"rtol": EXPONENT_RTOL, "atol": ATOL_PER_RTOL * EXPONENT_RTOL})


def _joined(sections: np.ndarray, time0: float, stats, second):
    """One record: the sections ``sections`` (the first at time ``time0``, the work
    ``stats``), then the record ``second`` run from the last of them: the sections of
    both, the impacts of ``second`` only (a 0-1 record's last cycles), the work of both."""
    from ..simulate import RunStats, Strobe

    offset, period = sections.shape[0] - 1, second.period
    imp = second.impacts
    impacts = replace(imp, time=imp.time + offset * period, cycle=imp.cycle + offset)
    k = np.arange(offset + second.record + 1)
    strobe = Strobe(cycle=k, time=time0 + k * period,
                    state=np.concatenate([sections, second.strobe.state[1:]]))
    stats = RunStats(*(a + b for a, b in zip(astuple(stats), astuple(second.stats),
                                             strict=True)))
    return replace(second, impacts=impacts, strobe=strobe, stats=stats,
                   record=offset + second.record)


def _mean_and_error(blocks: list[float]) -> tuple[float, float]:
    """The mean of the block exponents and its standard error, widened where the blocks
    are correlated.

    On a torus, or a slowly modulated motion, consecutive block exponents drift
    together (fig4 at T/T_Ax 1.054: a smooth swing over some 60 blocks), and
    ``std / sqrt(N)`` understates the spread of their mean several times over. From
    ``CORRELATION_BLOCKS`` blocks on, the lag-1 autocorrelation rho of the series is
    estimated and, where positive, the error is that of an AR(1) series,
    ``std / sqrt(N) * sqrt((1 + rho) / (1 - rho))`` (rho capped at 0.99).

    From ``BATCH_FROM`` blocks on, the series is the means of consecutive batches of
    ``floor(sqrt(N))`` blocks (the oldest blocks that do not fill a batch left out of
    the error, not of the mean). An impact's stretching and the contraction after it
    fall in neighbouring 10-cycle blocks, whose exponents are then anti-correlated:
    their sum telescopes, and ``std / sqrt(N)`` overstates the spread of their mean
    (fig4 at T/T_Ax 0.4600: 0.0035 from 120 blocks, 0.0019 from their 12 batches of
    10, as ``classify``'s 10 blocks of 160 cycles give). Batches longer than
    that pairing see it cancel; the AR(1) widening of the batch means still guards
    against a slow drift.
    """
    values = np.asarray(blocks, dtype=float)
    mean = float(values.mean())
    if values.size >= BATCH_FROM:
        size = math.isqrt(values.size)
        batches = values.size // size
        series = values[values.size - batches * size:].reshape(batches, size).mean(axis=1)
    else:
        series = values
    error = float(series.std(ddof=1) / math.sqrt(series.size))
    if series.size >= CORRELATION_BLOCKS:
        centred = series - series.mean()
        rho = float(centred[1:] @ centred[:-1]) / max(float(centred @ centred), 1e-300)
        if rho > 0.0:
            rho = min(rho, 0.99)
            error *= math.sqrt((1.0 + rho) / (1.0 - rho))
    return mean, error


def _best_mismatch(states: np.ndarray, scale: float, max_period: int | None = None) -> float:
    """The smallest mismatch of a period (up to ``max_period``) that fits the record twice."""
    longest = max(1, (states.shape[0] - 1) // 2)
    periods = range(1, longest + 1 if max_period is None else min(longest, max_period) + 1)
    return min(_mismatch(states, p, scale) for p in periods)


def _clip(value: float) -> float:
    return float(min(max(value, 0.0), 1.0))
