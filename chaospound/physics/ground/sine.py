"""Harmonic ground motion ``u_g(t) = sin(t / r)`` (units of A_g; r = T / T_Ax).

A ground motion is one module with this interface (docs/extending.md): ``at``
gives ``(u_g, u_g')`` at a time, and a stepper that takes many stages per step
carries a cheap state instead (``anchor`` at the step start, ``shifted`` to a
stage, ``at_anchor`` to read it), which for the sine is ``(sin, cos)`` of the
phase advanced by angle addition: no library sine inside a step. The engine
resets the anchor from the library sine at every section, so it never drifts.
The block is ``p[base] = r``.
"""

import math

from chaospound.kernels.jit import inline

NAME = "sine"
PARAMETERS = ("period_ratio",)  #: the motion's block, in order
PERIODIC = True  #: the section interval is the forcing period 2 pi r

SHIFT_MAX = 0.3  #: |x| up to which sin/cos(x) come from the Taylor series below

# Taylor coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!: the truncation
# error at |x| = SHIFT_MAX is below 1e-19, so sin x and cos x equal the
# library's to rounding. Products only: without fastmath a division by a
# constant stays a division, and the 13 divisions of a nested form would sit
# on the critical path of every Runge-Kutta stage.
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


@inline
def at(t, p, base):
    """Ground displacement and velocity ``(u_g, u_g')`` at forcing time t."""
    r = p[base]
    arg = t / r
    return math.sin(arg), math.cos(arg) / r


@inline
def anchor(t, p, base):
    """``(sin(t/r), cos(t/r))``: the carried state of a step starting at t."""
    arg = t / p[base]
    return math.sin(arg), math.cos(arg)


@inline
def shifted(c0, c1, shift, p, base):
    """The carried state at ``t + shift`` from its value ``(c0, c1)`` at t.

    Angle addition with ``x = shift / r``; for ``|x| <= SHIFT_MAX`` sin x and cos x
    are their Taylor polynomials to x^13 and x^14 in Horner form (truncation
    below 1e-19, so the result equals the direct evaluation to a few ulps),
    else the library's.
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
    return c0 * cos_x + c1 * sin_x, c1 * cos_x - c0 * sin_x


@inline
def at_anchor(c0, c1, p, base):
    """``(u_g, u_g')`` from the carried state; bitwise :func:`at` at the same t."""
    return c0, c1 / p[base]
