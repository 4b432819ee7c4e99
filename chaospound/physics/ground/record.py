"""A recorded (or generated) accelerogram, integrated exactly between samples.

Model
-----
The ground acceleration is the piecewise-linear interpolant of its samples
``a_k`` at times ``t_k`` (dimensionless, docs/model.md section 2). On
``[t_k, t_{k+1})``, with ``s = t - t_k``, ``h = t_{k+1} - t_k`` and the jerk
``j = (a_{k+1} - a_k) / h``::

    u_g''(t) = a_k + j s
    u_g'(t)  = v_k + a_k s + j s^2 / 2
    u_g(t)   = u_k + v_k s + a_k s^2 / 2 + j s^3 / 6

with the sample values from the exact recursion (``u_0 = v_0 = 0``)::

    v_{k+1} = v_k + h (a_k + a_{k+1}) / 2
    u_{k+1} = u_k + h v_k + h^2 (2 a_k + a_{k+1}) / 6

(summed with Neumaier's compensation). u_g and u_g' are continuous, u_g'' is
continuous with kinks at the samples (hence ``KINKS``: the integrator lands on
every sample time, :func:`next_kink`). Before the first sample u_g'' = 0 and the
ground moves on the straight line of its initial state (at rest at 0 for a
record; ``initial_x`` of :func:`block_from_samples` for a sampled analytic
motion); after the last one u_g'' = 0 and the ground moves on with its final
velocity (zero after the default baseline correction).

Baseline correction (``baseline="rest"``, the default)
------------------------------------------------------
Integrating a real accelerogram twice leaves a drift: a small offset of the
baseline makes u_g grow like t^2. The correction subtracts from the
acceleration the linear function ``c0 + c1 (t - t_0)`` chosen so that the ground
ends at rest where it started, ``u_g(t_end) = u_0, u_g'(t_end) = 0`` (a closed-form
2x2 system). Why this one: a linear function of time is exactly representable by
the piecewise-linear interpolant, so the corrected record stays in the class
integrated exactly above (no resampling, no filter); it keeps the initial state
at rest (the structure starts at rest on a resting ground); and the ground is at
rest after the record, so a free-vibration tail after it is well defined. It is
the displacement polynomial ``c0 s^2 / 2 + c1 s^3 / 6`` removal of the classical
polynomial baseline corrections, with its two coefficients fixed by the end
conditions instead of a least-squares fit. ``baseline="none"`` integrates the
samples as they are.

Block
-----
Fixed part (:data:`PARAMETERS`): ``samples`` n, ``components`` (1 or 2),
``rate`` = (n - 1) / (t_{n-1} - t_0) (for the O(1) index guess on a uniform
grid). Variable part, right after: ``t[n], u_x[n], v_x[n], a_x[n]`` and, with two
components, ``u_y[n], v_y[n], a_y[n]``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from chaospound.kernels.jit import inline, kernel

from . import records_io

NAME = "record"
PARAMETERS = ("samples", "components", "rate")
PERIODIC = False
KINKS = True

_FIXED = len(PARAMETERS)
BASELINES = ("rest", "none")


# ------------------------------------------------------------------ Python side
def integrate(
    t: np.ndarray, a: np.ndarray, u0: float = 0.0, v0: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Sample displacements and velocities of the piecewise-linear acceleration.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times (dimensionless), strictly increasing.
    a : numpy.ndarray
        Accelerations at ``t`` (dimensionless).
    u0, v0 : float
        ``u_g`` and ``u_g'`` at the first sample (A_g, A_g omega_Ax); 0 for a record.

    Returns
    -------
    u, v : numpy.ndarray
        ``u_g`` and ``u_g'`` at the samples by the exact recursion of the module
        docstring (Neumaier-compensated sums).
    """
    n = len(t)
    u = np.full(n, float(u0))
    v = np.full(n, float(v0))
    u_sum, v_sum = float(u0), float(v0)
    u_comp = v_comp = 0.0
    t_list = t.tolist()
    a_list = a.tolist()
    for k in range(n - 1):
        h = t_list[k + 1] - t_list[k]
        a0 = a_list[k]
        a1 = a_list[k + 1]
        du = h * (v_sum + v_comp) + h * h * (2.0 * a0 + a1) / 6.0
        dv = h * (a0 + a1) / 2.0
        total = u_sum + du  # Neumaier: keep what the addition drops
        u_comp += (u_sum - total) + du if abs(u_sum) >= abs(du) else (du - total) + u_sum
        u_sum = total
        total = v_sum + dv
        v_comp += (v_sum - total) + dv if abs(v_sum) >= abs(dv) else (dv - total) + v_sum
        v_sum = total
        u[k + 1] = u_sum + u_comp
        v[k + 1] = v_sum + v_comp
    return u, v


def baseline_rest(t: np.ndarray, a: np.ndarray, u0: float = 0.0, v0: float = 0.0) -> np.ndarray:
    """The acceleration minus ``c0 + c1 (t - t_0)`` that brings the ground to rest at ``u0``.

    ``c0, c1`` solve ``u(T) = u0, v(T) = 0`` for the corrected record (``T = t_end - t_0``):
    ``c0 T + c1 T^2 / 2 = v_raw(T)`` and ``c0 T^2 / 2 + c1 T^3 / 6 = u_raw(T) - u0``.
    """
    u, v = integrate(t, a, u0, v0)
    du, dv = u[-1] - u0, v[-1]
    span = t[-1] - t[0]
    # Cramer on [[T, T^2/2], [T^2/2, T^3/6]] (c0, c1) = (dv, du), determinant -T^4 / 12
    c0 = 6.0 * du / (span * span) - 2.0 * dv / span
    c1 = 6.0 * dv / (span * span) - 12.0 * du / (span * span * span)
    return a - (c0 + c1 * (t - t[0]))


def block_from_samples(
    t: np.ndarray,
    a_x: np.ndarray,
    a_y: np.ndarray | None = None,
    baseline: str = "rest",
    initial_x: tuple[float, float] = (0.0, 0.0),
    initial_y: tuple[float, float] = (0.0, 0.0),
) -> np.ndarray:
    """The block of a record given in model units.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times (dimensionless, t = omega_Ax tau), strictly increasing, >= 2.
    a_x, a_y : numpy.ndarray
        Dimensionless accelerations ``u_g''`` (units A_g omega_Ax^2); ``a_y`` None
        for one component.
    baseline : {"rest", "none"}
        The baseline correction (module docstring).
    initial_x, initial_y : (float, float)
        ``(u_g, u_g')`` at the first sample (A_g, A_g omega_Ax); a record starts
        from rest, a sampled analytic motion (a sine from its phase) need not.
        Before the first sample the ground moves on this state's straight line.

    Returns
    -------
    numpy.ndarray
        ``[n, components, rate, t..., u_x..., v_x..., a_x...(, u_y..., v_y..., a_y...)]``.
    """
    t = np.ascontiguousarray(t, dtype=np.float64)
    n = len(t)
    components = [np.ascontiguousarray(a_x, dtype=np.float64)]
    if a_y is not None:
        components.append(np.ascontiguousarray(a_y, dtype=np.float64))
    if baseline not in BASELINES:
        raise ValueError(f"record: unknown baseline correction {baseline!r}; use one of "
                         + ", ".join(BASELINES))
    if t.ndim != 1 or n < 2:
        raise ValueError(f"record: need at least 2 samples, got {n}")
    if not np.all(np.isfinite(t)) or not np.all(np.diff(t) > 0.0):
        raise ValueError("record: sample times must be finite and strictly increasing")
    for a in components:
        if a.shape != t.shape:
            raise ValueError(f"record: {a.shape[0]} accelerations for {n} times")
        if not np.all(np.isfinite(a)):
            raise ValueError("record: non-finite acceleration")
    parts = [np.array([n, len(components), (n - 1) / (t[-1] - t[0])]), t]
    for a, (u0, v0) in zip(components, (initial_x, initial_y), strict=False):
        if not (math.isfinite(u0) and math.isfinite(v0)):
            raise ValueError("record: non-finite initial state")
        if baseline == "rest":
            a = baseline_rest(t, a, u0, v0)
        u, v = integrate(t, a, u0, v0)
        parts += [u, v, a]
    return np.concatenate(parts)


def block(spec: Mapping[str, Any]) -> np.ndarray:
    """The block of a recorded motion.

    Parameters
    ----------
    spec : mapping
        Either ``t``, ``a_x`` (and optionally ``a_y``, ``initial_x``, ``initial_y``)
        already in model units (:func:`block_from_samples`), or
        ``file`` (a path or a pair of paths), with ``units`` (optional), ``dt``
        [s] (text without a time column), ``scale`` (default 1),
        ``length_scale`` A_g [m] and ``omega`` omega_Ax [rad/s], converted by
        :func:`records_io.to_model`. Both take ``baseline`` ("rest" default).

    Raises
    ------
    ValueError
        One line naming the file and the problem.
    """
    baseline = str(spec.get("baseline", "rest"))
    if "file" in spec:
        for key in ("length_scale", "omega"):
            if key not in spec:
                raise ValueError(f"record {spec['file']}: {key!r} is required to convert it")
        record = records_io.load_record(
            spec["file"], units=spec.get("units"), dt=spec.get("dt"),
            scale=float(spec.get("scale", 1.0)),
        )
        t, a_x, a_y = records_io.to_model(record, float(spec["length_scale"]), float(spec["omega"]))
        return block_from_samples(t, a_x, a_y, baseline)
    if "t" not in spec or "a_x" not in spec:
        raise ValueError("record: give 'file' or the samples 't' and 'a_x'")
    return block_from_samples(np.asarray(spec["t"]), np.asarray(spec["a_x"]),
                              None if spec.get("a_y") is None else np.asarray(spec["a_y"]),
                              baseline, tuple(spec.get("initial_x", (0.0, 0.0))),
                              tuple(spec.get("initial_y", (0.0, 0.0))))


def period(values: np.ndarray) -> None:
    """None: a record is not periodic."""
    return None


# ------------------------------------------------------------------ kernels
@inline
def _interval(t, p, d, n, rate):
    """k with ``t_k <= t < t_{k+1}``, for ``t_0 <= t < t_{n-1}`` (times at ``p[d:d+n]``)."""
    k = int((t - p[d]) * rate)
    if k > n - 2:
        k = n - 2
    if k < 0:
        k = 0
    if p[d + k] <= t:
        if t < p[d + k + 1]:
            return k
        if k + 2 < n and t < p[d + k + 2]:
            return k + 1
    elif k >= 1 and p[d + k - 1] <= t:
        return k - 1
    lo = 0  # bisection: t_lo <= t < t_hi
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[d + mid] <= t:
            lo = mid
        else:
            hi = mid
    return lo


@inline
def _evaluate(t, p, base, first):
    """``(u, v, a)`` of the component whose samples start at ``p[base + first]``."""
    n = int(p[base])
    d = base + _FIXED
    c = d + first * n  # u at c, v at c + n, a at c + 2 n
    if t != t:
        return math.nan, math.nan, math.nan
    if not t >= p[d]:
        return p[c] + p[c + n] * (t - p[d]), p[c + n], 0.0
    last = n - 1
    if t >= p[d + last]:
        s = t - p[d + last]
        return p[c + last] + p[c + n + last] * s, p[c + n + last], 0.0
    k = _interval(t, p, d, n, p[base + 2])
    s = t - p[d + k]
    a0 = p[c + 2 * n + k]
    jerk = (p[c + 2 * n + k + 1] - a0) / (p[d + k + 1] - p[d + k])
    v0 = p[c + n + k]
    u = p[c + k] + s * (v0 + s * (0.5 * a0 + s * (jerk / 6.0)))
    v = v0 + s * (a0 + s * (0.5 * jerk))
    return u, v, a0 + s * jerk


@inline
def at(t, p, base):
    """``(u_g, u_g')`` of x at absolute time t (piecewise cubic, quadratic)."""
    u, v, _ = _evaluate(t, p, base, 1)
    return u, v


@inline
def at_y(t, p, base):
    """``(u_gy, u_gy')`` at t; (0, 0) for a one-component record."""
    if p[base + 1] < 2.0:
        return 0.0, 0.0
    u, v, _ = _evaluate(t, p, base, 4)
    return u, v


@inline
def acceleration(t, p, base):
    """``u_g''`` of x at t (piecewise linear; right-continuous at samples)."""
    _, _, a = _evaluate(t, p, base, 1)
    return a


@inline
def anchor(t, p, base):
    """The carried state is the time itself: ``(t, 0)``."""
    return t, 0.0


@inline
def shifted(c0, c1, shift, p, base):
    """``(c0 + shift, 0)``."""
    return c0 + shift, 0.0


@inline
def at_anchor(c0, c1, p, base):
    """``at(c0)``."""
    return at(c0, p, base)


@kernel
def next_kink(t, p, base):
    """The first sample time strictly after t; ``inf`` from the last sample on."""
    n = int(p[base])
    d = base + _FIXED
    if t != t:
        return math.nan
    if t < p[d]:
        return p[d]
    if t >= p[d + n - 1]:
        return math.inf
    return p[d + _interval(t, p, d, n, p[base + 2]) + 1]
