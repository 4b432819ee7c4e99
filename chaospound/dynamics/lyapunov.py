"""Lyapunov exponents with error bars (docs/model.md section 12).

Two independent methods:

* :func:`lyapunov_spectrum`: the k largest exponents (all by default) from
  the variational equations ``V' = J(t, y) V`` with the analytic Jacobian,
  integrated together with the trajectory by the same jitted integrator
  (contact events landed on), with QR re-orthonormalisation (modified
  Gram-Schmidt) once per period: Benettin et al. (1980), Shimada & Nagashima
  (1979). The contact force is continuous, so no saltation matrix is needed.
* :func:`largest_exponent_two_trajectory`: the largest exponent from the
  growth of the separation of two nearby trajectories, renormalised every
  period (each trajectory lands on its own contact events).

Error bars: the record is cut into ``n_blocks`` consecutive blocks; the
error is the standard error of the block means (after the tangent
transient), so it includes the correlation of the stretching along the
orbit. Exponents are per unit normalised time (t = tau omega_Ax for the
pounding models) and, multiplied by T, per excitation cycle.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..kernels.params import CUSTOM
from ..scene import Scene
from .system import System, as_system, evolve

__all__ = [
    "LargestExponent",
    "Spectrum",
    "kaplan_yorke",
    "largest_exponent_two_trajectory",
    "lyapunov_spectrum",
]


@dataclass(frozen=True)
class Spectrum:
    """Lyapunov spectrum of a system, with its evidence.

    Attributes
    ----------
    exponents, errors : ndarray (k,)
        Exponents (descending, per unit normalised time) and standard errors.
    period : float
        Sampling period T; ``exponents * period`` is per excitation cycle.
    history : ndarray (cycles, k)
        Running estimates after each period (the convergence history).
    block_means : ndarray (n_blocks, k)
        Exponent estimates of the consecutive blocks behind the error bars.
    transient, tangent_transient, cycles : int
        Periods discarded before the tangent vectors start, periods discarded
        while they align, and periods averaged.
    trace : float
        Mean trace of the Jacobian (constant for the built-in models with an
        elastic contact law; NaN for a custom system or a dissipative law, whose
        trace varies along the orbit): the sum of
        all exponents must equal it.
    steps, rhs_evals : int
        Work of the tangent run.
    final_state : ndarray (n,) or None
        The state at the last section of the run (where a periodic response's
        orbit can be solved: :func:`chaospound.orbits.floquet.spectrum_floquet`).
    """

    exponents: np.ndarray
    errors: np.ndarray
    period: float
    history: np.ndarray
    block_means: np.ndarray
    transient: int
    tangent_transient: int
    cycles: int
    trace: float
    steps: int
    rhs_evals: int
    final_state: np.ndarray | None = None

    @property
    def per_cycle(self) -> np.ndarray:
        """Exponents per excitation cycle (times T)."""
        return self.exponents * self.period

    @property
    def errors_per_cycle(self) -> np.ndarray:
        return self.errors * self.period

    @property
    def max_exponent(self) -> float:
        return float(self.exponents[0])

    @property
    def max_error(self) -> float:
        return float(self.errors[0])

    @property
    def kaplan_yorke(self) -> float:
        return kaplan_yorke(self.exponents)


@dataclass(frozen=True)
class LargestExponent:
    """Largest exponent by the two-trajectory method."""

    exponent: float
    error: float
    period: float
    history: np.ndarray
    block_means: np.ndarray
    separation: float
    cycles: int

    @property
    def per_cycle(self) -> float:
        return self.exponent * self.period


def lyapunov_spectrum(
    system: System | Scene,
    *,
    k: int | None = None,
    transient: int | None = None,
    tangent_transient: int = 20,
    cycles: int = 400,
    n_blocks: int = 10,
    initial_state: np.ndarray | None = None,
) -> Spectrum:
    """The k largest Lyapunov exponents with error bars.

    Parameters
    ----------
    system : System or Scene
        What to analyse; a Scene runs its smallest exact model.
    k : int, optional
        Number of exponents (default: all, the full spectrum).
    transient : int, optional
        Periods integrated first without tangent vectors (default: the
        system's, e.g. the scene's run.transient).
    tangent_transient : int
        Periods during which the tangent vectors align, discarded.
    cycles : int
        Periods averaged (>= n_blocks).
    n_blocks : int
        Blocks for the error estimate (>= 2).
    initial_state : ndarray, optional
        Starting state at a section (skips nothing: the transient still runs).

    Returns
    -------
    Spectrum
    """
    system = as_system(system)
    n = system.dim
    k = n if k is None else int(k)
    if not 1 <= k <= n:
        raise ValueError(f"k = {k}: must be between 1 and the state dimension {n}")
    _check_counts(cycles, n_blocks, tangent_transient)
    transient = system.transient if transient is None else int(transient)
    state = system.initial_state if initial_state is None else np.asarray(initial_state, float)
    if transient > 0:
        state = evolve(system, state, cycles=transient,
                       start_at_section=initial_state is not None).state
    run = evolve(system, state, transient=tangent_transient, cycles=cycles,
                 start_at_section=True, tangent="qr", vectors=k)
    logs, stats = run.tangent_log, run.stats
    period = system.period
    exponents = logs.sum(axis=0) / (cycles * period)
    blocks = _block_means(logs, n_blocks) / period
    errors = blocks.std(axis=0, ddof=1) / np.sqrt(n_blocks)
    history = np.cumsum(logs, axis=0) / (np.arange(1, cycles + 1)[:, None] * period)
    # QR yields the exponents in descending order only asymptotically: report them sorted
    order = np.argsort(-exponents, kind="stable")
    exponents, errors, history, blocks = (exponents[order], errors[order], history[:, order],
                                          blocks[:, order])
    return Spectrum(
        exponents=exponents,
        errors=errors,
        period=period,
        history=history,
        block_means=blocks,
        transient=transient,
        tangent_transient=tangent_transient,
        cycles=cycles,
        trace=_constant_trace(system),
        steps=int(stats[0]),
        rhs_evals=int(stats[2]),
        final_state=run.state,
    )


def _constant_trace(system: System) -> float:
    """Trace of the Jacobian of a built-in model with an elastic contact law (constant);
    NaN for a custom system and for a dissipative law, whose contact damping adds
    ``-mu dF/dd'`` to the trace during every contact episode, so that the trace varies
    along the orbit."""
    if system.model_id == CUSTOM:
        return float("nan")
    if system.engine().module.LAW_DISSIPATIVE:
        return float("nan")
    return float(system.engine().module.model_trace(system.params))


def largest_exponent_two_trajectory(
    system: System | Scene,
    *,
    transient: int | None = None,
    cycles: int = 400,
    separation: float = 1e-7,
    n_blocks: int = 10,
    seed: int = 1,
    initial_state: np.ndarray | None = None,
) -> LargestExponent:
    """Largest exponent from two nearby trajectories, renormalised every period.

    The perturbed trajectory starts ``separation`` away (Euclidean norm of the
    state, a fixed random direction from ``seed``); after every period the
    log of the growth of the separation is recorded and the separation is
    scaled back along its current direction. Use a tight tolerance: the
    integration error must stay far below ``separation``. ``initial_state``, a
    state at a section, replaces the system's initial state at t = 0 (as in
    :func:`lyapunov_spectrum`; the transient still runs).
    """
    system = as_system(system)
    _check_counts(cycles, n_blocks, 0)
    transient = system.transient if transient is None else int(transient)
    # each trajectory its own packed vector: a contact law's per-episode memory
    # (the onset velocity of hertzdamp) lives there
    system = replace(system, params=system.params.copy())
    state = system.initial_state if initial_state is None else np.asarray(initial_state, float)
    if transient > 0:
        state = evolve(system, initial_state, cycles=transient).state
    perturbed = replace(system, params=system.params.copy())
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=state.shape[0])
    other = state + separation * direction / np.linalg.norm(direction)
    logs = np.zeros(cycles)
    for c in range(cycles):
        state = evolve(system, state).state
        other = evolve(perturbed, other).state
        delta = other - state
        norm = float(np.linalg.norm(delta))
        logs[c] = np.log(norm / separation)
        other = state + delta * (separation / norm)
    period = system.period
    blocks = _block_means(logs[:, None], n_blocks)[:, 0] / period
    return LargestExponent(
        exponent=float(logs.sum() / (cycles * period)),
        error=float(blocks.std(ddof=1) / np.sqrt(n_blocks)),
        period=period,
        history=np.cumsum(logs) / (np.arange(1, cycles + 1) * period),
        block_means=blocks,
        separation=separation,
        cycles=cycles,
    )


def kaplan_yorke(exponents: np.ndarray) -> float:
    """Kaplan-Yorke (Lyapunov) dimension of a descending spectrum.

    ``D = j + (l_1 + ... + l_j) / |l_(j+1)|`` with j the largest index whose
    partial sum is >= 0; 0 when the largest exponent is negative, the full
    dimension when every partial sum is >= 0.
    """
    lam = np.sort(np.asarray(exponents, dtype=float))[::-1]
    sums = np.cumsum(lam)
    if lam.size == 0 or sums[0] < 0.0:
        return 0.0
    j = int(np.nonzero(sums >= 0.0)[0][-1])
    if j == lam.size - 1:
        return float(lam.size)
    return float(j + 1 + sums[j] / abs(lam[j + 1]))


def _block_means(logs: np.ndarray, n_blocks: int) -> np.ndarray:
    """Mean log-stretch per period in each of n_blocks consecutive blocks."""
    edges = np.linspace(0, logs.shape[0], n_blocks + 1).astype(int)
    return np.array([logs[edges[b]:edges[b + 1]].mean(axis=0) for b in range(n_blocks)])


def _check_counts(cycles: int, n_blocks: int, tangent_transient: int) -> None:
    if n_blocks < 2:
        raise ValueError(f"n_blocks = {n_blocks}: must be >= 2 for an error estimate")
    if cycles < n_blocks:
        raise ValueError(f"cycles = {cycles}: must be >= n_blocks = {n_blocks}")
    if tangent_transient < 0:
        raise ValueError(f"tangent_transient = {tangent_transient}: must be >= 0")
