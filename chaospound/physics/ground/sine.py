"""Harmonic ground motion: ``u_g = sin(t / r)`` along x, optionally a y component.

Block (dimensionless, docs/model.md section 2: lengths in A_g, time times omega_Ax):

====  ==============  ==========================================================
slot  name            meaning
====  ==============  ==========================================================
0     ``period_ratio``  r = T / T_Ax; u_gx = sin(t / r), u_gx' = cos(t / r) / r
1     ``y_ratio``       amplitude of the y component over the x one (0: none)
2     ``y_phase``       phase lead of the y component [rad]
====  ==============  ==========================================================

The y component is ``u_gy = y_ratio sin(t / r + y_phase)``, a bi-directional
harmonic input as in Gong & Hao (2005). The x functions carry the phase
as ``(sin, cos)`` from step to step (``anchor``, ``shifted``, ``at_anchor``): a
many-stage step evaluates no library sine (angle addition with a Taylor
series for small shifts), and the engine resets the anchor from the library
sine at every section, so the phase never drifts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from chaospound.kernels.jit import inline, kernel

NAME = "sine"
PARAMETERS = ("period_ratio", "y_ratio", "y_phase")
PERIODIC = True
KINKS = False

SHIFT_MAX = 0.3  #: |x| up to which sin/cos(x) come from the Taylor series (as powers.py)

# Taylor coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!, copied from powers.py
_S1 = -1.0 / 6.0
_S2 = 1.0 / 120.0
_S3 = -1.0 / 5040.0
_S4 = 1.0 / 362880.0
_S5 = -1.0 / 39916800.0
_S6 = 1.0 / 6227020800.0
_C1 = -0.5
_C2 = 1.0 / 24.0
_C3 = -1.0 / 720.0
_C4 = 1.0 / 40320.0
_C5 = -1.0 / 3628800.0
_C6 = 1.0 / 479001600.0
_C7 = -1.0 / 87178291200.0


def block(spec: Mapping[str, float]) -> np.ndarray:
    """The block values ``[period_ratio, y_ratio, y_phase]``.

    Parameters
    ----------
    spec : mapping
        ``period_ratio`` (r = T / T_Ax, > 0, dimensionless), optional
        ``y_ratio`` (dimensionless, default 0) and ``y_phase`` (rad, default 0).

    Raises
    ------
    ValueError
        If ``period_ratio`` is missing, not finite or not positive, or the y
        entries are not finite.
    """
    if "period_ratio" not in spec:
        raise ValueError("sine ground motion: 'period_ratio' is required")
    r = float(spec["period_ratio"])
    y_ratio = float(spec.get("y_ratio", 0.0))
    y_phase = float(spec.get("y_phase", 0.0))
    if not (math.isfinite(r) and r > 0.0):
        raise ValueError(f"sine ground motion: period_ratio must be finite and > 0, got {r}")
    if not (math.isfinite(y_ratio) and math.isfinite(y_phase)):
        raise ValueError("sine ground motion: y_ratio and y_phase must be finite")
    return np.array([r, y_ratio, y_phase], dtype=np.float64)


def period(values: np.ndarray) -> float:
    """The forcing period ``T = 2 pi r`` (dimensionless time)."""
    return 2.0 * math.pi * float(values[0])


@inline
def at(t, p, base):
    """``(u_g, u_g')`` of x at t: ``(sin(t/r), cos(t/r) / r)`` (powers.ground)."""
    r = p[base]
    arg = t / r
    return math.sin(arg), math.cos(arg) / r


@inline
def at_y(t, p, base):
    """``(u_gy, u_gy')`` at t: ``y_ratio (sin, cos / r)(t/r + y_phase)``; (0, 0) if y_ratio = 0."""
    ratio = p[base + 1]
    if ratio == 0.0:
        return 0.0, 0.0
    r = p[base]
    arg = t / r + p[base + 2]
    return ratio * math.sin(arg), ratio * math.cos(arg) / r


@inline
def acceleration(t, p, base):
    """``u_g''`` of x at t: ``-sin(t/r) / r^2``."""
    r = p[base]
    return -math.sin(t / r) / (r * r)


@inline
def anchor(t, p, base):
    """``(sin(t/r), cos(t/r))``, the carried phase at t (powers.ground_phase)."""
    arg = t / p[base]
    return math.sin(arg), math.cos(arg)


@inline
def shifted(sin0, cos0, shift, p, base):
    """The carried phase at ``t + shift`` from its value at t (powers.phase_shifted).

    Angle addition with ``x = shift / r``; for ``|x| <= SHIFT_MAX`` sin x and cos x
    are their Taylor polynomials to x^13 and x^14 in Horner form, else the library's.
    """
    x = shift / p[base]
    if abs(x) <= SHIFT_MAX:
        x2 = x * x
        sin_x = x + x * x2 * (_S1 + x2 * (_S2 + x2 * (_S3 + x2 * (_S4 + x2 * (_S5 + x2 * _S6)))))
        cos_x = 1.0 + x2 * (_C1 + x2 * (_C2 + x2 * (_C3 + x2 * (_C4 + x2 * (_C5 + x2 * (
            _C6 + x2 * _C7))))))
    else:
        sin_x = math.sin(x)
        cos_x = math.cos(x)
    return sin0 * cos_x + cos0 * sin_x, cos0 * cos_x - sin0 * sin_x


@inline
def at_anchor(sin_x, cos_x, p, base):
    """``(u_g, u_g')`` of x from the carried phase (powers.ground_at_phase)."""
    return sin_x, cos_x / p[base]


@kernel
def next_kink(t, p, base):
    """No kinks: ``inf``."""
    return math.inf
