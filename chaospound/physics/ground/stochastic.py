"""Filtered white noise: Kanai-Tajimi with the Clough-Penzien high-pass, under an envelope.

Process
-------
White noise w(t) of two-sided power spectral density S0 (``E[w(t) w(t')] =
2 pi S0 delta(t - t')``, so that ``R(tau) = integral of S(omega) e^{i omega tau}
d omega`` over the real line) drives the Kanai-Tajimi ground filter and the
Clough-Penzien high-pass filter in series::

    x_g'' + 2 zeta_g omega_g x_g' + omega_g^2 x_g = -w
    a_KT  = -(2 zeta_g omega_g x_g' + omega_g^2 x_g)
    x_f'' + 2 zeta_f omega_f x_f' + omega_f^2 x_f = a_KT
    a     = x_f'' = a_KT - 2 zeta_f omega_f x_f' - omega_f^2 x_f

whose stationary output has the two-sided density (:func:`kt_cp_psd`)::

    S(w) = S0 (w_g^4 + 4 z_g^2 w_g^2 w^2) / ((w_g^2 - w^2)^2 + 4 z_g^2 w_g^2 w^2)
              * w^4 / ((w_f^2 - w^2)^2 + 4 z_f^2 w_f^2 w^2)

The ground acceleration is ``u_g''(t_k) = e(t_k) a(t_k)`` at ``t_k = k dt``, e the
envelope, and between samples it is linearly interpolated and integrated exactly
with the baseline correction of :mod:`.record` (whose kernels this module
re-exports: a stochastic motion is evaluated exactly like a record).

Discretisation: exact, no time-stepping error
---------------------------------------------
With the state ``z = (x_g, x_g', x_f, x_f')``, ``z' = A z + b w`` and ``a = c z``,
the samples ``z_k = z(k dt)`` obey exactly ``z_{k+1} = Phi z_k + eta_k`` with
``Phi = exp(A dt)`` and ``eta_k`` independent Gaussian vectors of covariance
``Q = integral_0^dt exp(A s) (2 pi S0 b b^T) exp(A^T s) ds`` (Van Loan's
matrix exponential). ``eta_k = L xi_k`` with ``L`` the Cholesky factor of Q and
``xi_k`` four standard normals; ``z_0 = chol(P) xi_0`` with P the stationary
covariance (``A P + P A^T + 2 pi S0 b b^T = 0``), so the unmodulated sequence
``a_k`` is a sample of the stationary continuous process at the sample times:
its spectrum is S aliased at the sample rate, with no discretisation error.
The normals come from ``numpy.random.Generator(PCG64(seed))``:
``standard_normal((n, 4))`` for x, then (two components) the same for y. The
recursion is a numba kernel: the same seed gives the same bits.

Envelopes e(t) (t from the first sample)
----------------------------------------
- ``none``: 1 (stationary).
- ``jennings`` (Jennings, Housner & Tsai 1968): ``(t / t_rise)^2`` for t < t_rise, 1
  up to ``t_plateau``, then ``exp(-decay (t - t_plateau))``.
- ``saragoni-hart`` (Saragoni & Hart 1974): ``(t / t_peak)^b exp(b (1 - t / t_peak))``,
  ``t_peak = b / c``: ``a t^b exp(-c t)`` normalised to a unit peak.

Units
-----
All parameters are dimensionless model units (docs/model.md section 2):
frequencies in omega_Ax, times in 1 / omega_Ax, S0 in A_g^2 omega_Ax^3 (then a is
in A_g omega_Ax^2). :func:`model_parameters` converts from SI (rad/s, s,
m^2/s^3) given A_g [m] and omega_Ax [rad/s].
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import scipy.linalg

from chaospound.kernels.jit import kernel

from . import record

NAME = "stochastic"
PARAMETERS = record.PARAMETERS
PERIODIC = False
KINKS = True

# the kernels: those of a record (the block is a record block)
at = record.at
at_y = record.at_y
acceleration = record.acceleration
anchor = record.anchor
shifted = record.shifted
at_anchor = record.at_anchor
next_kink = record.next_kink

ENVELOPES = ("none", "jennings", "saragoni-hart")
#: the spec entries and their defaults (None: required)
DEFAULTS: dict[str, Any] = {
    "omega_g": None, "zeta_g": None, "omega_f": None, "zeta_f": None, "intensity": None,
    "dt": None, "duration": None, "seed": None,
    "envelope": "none", "t_rise": None, "t_plateau": None, "decay": None, "b": None, "c": None,
    "components": 1, "baseline": "rest",
}
_FREQUENCIES = ("omega_g", "omega_f", "decay", "c")
_TIMES = ("dt", "duration", "t_rise", "t_plateau")


def kt_cp_psd(
    omega: np.ndarray | float,
    omega_g: float,
    zeta_g: float,
    omega_f: float,
    zeta_f: float,
    intensity: float,
) -> np.ndarray:
    """Two-sided Kanai-Tajimi-Clough-Penzien power spectral density of the acceleration.

    Parameters
    ----------
    omega : array_like
        Circular frequency (units of omega_Ax).
    omega_g, zeta_g, omega_f, zeta_f : float
        Ground and high-pass filter frequencies (units of omega_Ax) and damping ratios.
    intensity : float
        S0, two-sided density of the white noise (units A_g^2 omega_Ax^3).

    Returns
    -------
    numpy.ndarray
        S(omega) in A_g^2 omega_Ax^3.
    """
    w2 = np.asarray(omega, dtype=np.float64) ** 2
    g2 = omega_g * omega_g
    f2 = omega_f * omega_f
    kt = (g2 * g2 + 4.0 * zeta_g**2 * g2 * w2) / ((g2 - w2) ** 2 + 4.0 * zeta_g**2 * g2 * w2)
    cp = w2 * w2 / ((f2 - w2) ** 2 + 4.0 * zeta_f**2 * f2 * w2)
    return intensity * kt * cp


def model_parameters(spec_si: Mapping[str, Any], length_scale: float, omega: float) -> dict:
    """Convert a spec in SI (rad/s, s, S0 in m^2/s^3) to model units.

    Frequencies (``omega_g``, ``omega_f``, ``decay``, ``c``) are divided by
    omega_Ax, times (``dt``, ``duration``, ``t_rise``, ``t_plateau``) multiplied by
    it, and ``intensity`` divided by ``A_g^2 omega_Ax^3``; the rest is copied.
    """
    out = dict(spec_si)
    for key in _FREQUENCIES:
        if out.get(key) is not None:
            out[key] = float(out[key]) / omega
    for key in _TIMES:
        if out.get(key) is not None:
            out[key] = float(out[key]) * omega
    if out.get("intensity") is not None:
        out["intensity"] = float(out["intensity"]) / (length_scale**2 * omega**3)
    return out


def _checked(spec: Mapping[str, Any]) -> dict:
    unknown = set(spec) - set(DEFAULTS)
    if unknown:
        raise ValueError(f"stochastic ground motion: unknown entries {sorted(unknown)}")
    values = {**DEFAULTS, **spec}
    envelope = values["envelope"]
    if envelope not in ENVELOPES:
        raise ValueError(f"stochastic ground motion: unknown envelope {envelope!r}; use one of "
                         + ", ".join(ENVELOPES))
    needed = ["omega_g", "zeta_g", "omega_f", "zeta_f", "intensity", "dt", "duration", "seed"]
    needed += {"none": [], "jennings": ["t_rise", "t_plateau", "decay"],
               "saragoni-hart": ["b", "c"]}[envelope]
    for key in needed:
        if values[key] is None:
            raise ValueError(f"stochastic ground motion: {key!r} is required")
        if key != "seed":
            value = float(values[key])
            if not (math.isfinite(value) and value >= 0.0) or (value == 0.0 and key != "t_rise"):
                raise ValueError(f"stochastic ground motion: {key} must be > 0, got {value}")
    if envelope == "jennings" and values["t_plateau"] < values["t_rise"]:
        raise ValueError("stochastic ground motion: t_plateau must be >= t_rise")
    if values["components"] not in (1, 2):
        raise ValueError("stochastic ground motion: components must be 1 or 2")
    return values


def envelope(t: np.ndarray, spec: Mapping[str, Any]) -> np.ndarray:
    """The modulating function e(t) at times t (dimensionless) of the spec's envelope."""
    values = _checked(spec)
    t = np.asarray(t, dtype=np.float64)
    kind = values["envelope"]
    if kind == "none":
        return np.ones_like(t)
    if kind == "jennings":
        t1, t2, decay = float(values["t_rise"]), float(values["t_plateau"]), float(values["decay"])
        rise = (t / t1) ** 2 if t1 > 0.0 else np.ones_like(t)
        return np.where(t < t1, rise, np.where(t <= t2, 1.0, np.exp(-decay * (t - t2))))
    b, c = float(values["b"]), float(values["c"])
    ratio = t * (c / b)
    return np.where(t > 0.0, ratio**b * np.exp(b * (1.0 - ratio)), 0.0)


def filter_matrices(
    omega_g: float, zeta_g: float, omega_f: float, zeta_f: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A``, ``b``, ``c`` of the state ``(x_g, x_g', x_f, x_f')`` (module docstring)."""
    kg, cg = omega_g * omega_g, 2.0 * zeta_g * omega_g
    kf, cf = omega_f * omega_f, 2.0 * zeta_f * omega_f
    a = np.array([[0.0, 1.0, 0.0, 0.0],
                  [-kg, -cg, 0.0, 0.0],
                  [0.0, 0.0, 0.0, 1.0],
                  [-kg, -cg, -kf, -cf]])
    b = np.array([0.0, -1.0, 0.0, 0.0])
    c = np.array([-kg, -cg, -kf, -cf])
    return a, b, c


def _factor(matrix: np.ndarray) -> np.ndarray:
    """A square root L L^T = matrix of a covariance (Cholesky, else clipped eigenvalues)."""
    matrix = 0.5 * (matrix + matrix.T)
    try:
        return np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError:
        values, vectors = np.linalg.eigh(matrix)
        return vectors * np.sqrt(np.clip(values, 0.0, None))


def discretisation(
    omega_g: float, zeta_g: float, omega_f: float, zeta_f: float, intensity: float, dt: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``Phi``, ``chol(Q)``, ``chol(P)`` and ``c`` of the exact sampled recursion."""
    a, b, c = filter_matrices(omega_g, zeta_g, omega_f, zeta_f)
    noise = 2.0 * math.pi * intensity * np.outer(b, b)
    van_loan = np.zeros((8, 8))
    van_loan[:4, :4] = -a
    van_loan[:4, 4:] = noise
    van_loan[4:, 4:] = a.T
    g = scipy.linalg.expm(van_loan * dt)
    phi = g[4:, 4:].T
    q = phi @ g[:4, 4:]
    p = scipy.linalg.solve_continuous_lyapunov(a, -noise)
    return (np.ascontiguousarray(phi), np.ascontiguousarray(_factor(q)),
            np.ascontiguousarray(_factor(p)), np.ascontiguousarray(c))


@kernel
def _recursion(phi, q_factor, p_factor, c, xi, out):
    """``out[k] = c z_k``, ``z_0 = chol(P) xi_0``, ``z_{k+1} = Phi z_k + chol(Q) xi_{k+1}``."""
    z0 = 0.0
    z1 = 0.0
    z2 = 0.0
    z3 = 0.0
    for j in range(4):
        z0 += p_factor[0, j] * xi[0, j]
        z1 += p_factor[1, j] * xi[0, j]
        z2 += p_factor[2, j] * xi[0, j]
        z3 += p_factor[3, j] * xi[0, j]
    out[0] = c[0] * z0 + c[1] * z1 + c[2] * z2 + c[3] * z3
    for k in range(1, out.shape[0]):
        y0 = phi[0, 0] * z0 + phi[0, 1] * z1 + phi[0, 2] * z2 + phi[0, 3] * z3
        y1 = phi[1, 0] * z0 + phi[1, 1] * z1 + phi[1, 2] * z2 + phi[1, 3] * z3
        y2 = phi[2, 0] * z0 + phi[2, 1] * z1 + phi[2, 2] * z2 + phi[2, 3] * z3
        y3 = phi[3, 0] * z0 + phi[3, 1] * z1 + phi[3, 2] * z2 + phi[3, 3] * z3
        for j in range(4):
            y0 += q_factor[0, j] * xi[k, j]
            y1 += q_factor[1, j] * xi[k, j]
            y2 += q_factor[2, j] * xi[k, j]
            y3 += q_factor[3, j] * xi[k, j]
        z0, z1, z2, z3 = y0, y1, y2, y3
        out[k] = c[0] * z0 + c[1] * z1 + c[2] * z2 + c[3] * z3


def generate(spec: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Sample times and modulated accelerations of one realisation (before baseline correction).

    Parameters
    ----------
    spec : mapping
        ``omega_g``, ``zeta_g``, ``omega_f``, ``zeta_f``, ``intensity`` (S0), ``dt``,
        ``duration``, ``seed``; ``envelope`` ("none", "jennings" with ``t_rise``,
        ``t_plateau``, ``decay``, "saragoni-hart" with ``b``, ``c``); ``components``
        (1 or 2: independent x and y). Model units (module docstring).

    Returns
    -------
    t, a_x, a_y : numpy.ndarray (a_y None for one component)
        ``t_k = k dt`` for ``k = 0 .. floor(duration / dt)`` and ``e(t_k) a_k``.
    """
    values = _checked(spec)
    dt = float(values["dt"])
    n = int(math.floor(float(values["duration"]) / dt + 1e-9)) + 1
    if n < 2:
        raise ValueError("stochastic ground motion: duration must cover at least one dt")
    phi, q_factor, p_factor, c = discretisation(
        float(values["omega_g"]), float(values["zeta_g"]), float(values["omega_f"]),
        float(values["zeta_f"]), float(values["intensity"]), dt)
    rng = np.random.Generator(np.random.PCG64(int(values["seed"])))
    t = np.arange(n) * dt
    e = envelope(t, values)
    out = []
    for _ in range(int(values["components"])):
        xi = rng.standard_normal((n, 4))
        a = np.empty(n)
        _recursion(phi, q_factor, p_factor, c, xi, a)
        out.append(e * a)
    return t, out[0], out[1] if len(out) > 1 else None


def block(spec: Mapping[str, Any]) -> np.ndarray:
    """The record block of one realisation.

    :func:`generate`, then :func:`record.block_from_samples` with the spec's
    ``baseline`` ("rest" by default).
    """
    t, a_x, a_y = generate(spec)
    return record.block_from_samples(t, a_x, a_y, str(_checked(spec)["baseline"]))


def period(values: np.ndarray) -> None:
    """None: not periodic."""
    return None
