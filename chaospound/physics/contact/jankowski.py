"""Jankowski's nonlinear viscoelastic contact (Jankowski 2005).

Force per unit length, with ``r = d'`` the local penetration rate::

    f = beta d^chi + c(d) r    while approaching (r > 0)
    f = beta d^chi             while separating (r <= 0)
    c(d) = 2 xi sqrt(beta d^(chi - 1) m_eff) = c_s d^q,  q = (chi - 1) / 2,
    xi = 9 sqrt(5) (1 - e^2) / (2 e (e (9 pi - 16) + 16))

with the paper's ``chi = 3/2`` (q = 1/4); ``c_s = 2 xi sqrt(beta m_eff)`` is the
block's ``c_scale``. The formula for xi is Jankowski's fit for chi = 3/2; another
chi is accepted but its e is not calibrated.

The force is continuous: ``c(d) r`` vanishes at the contact edge (d = 0) and
at the switch (r = 0), so ``JUMPS = False`` and the saltation matrix is the
identity at an onset, a release and the switch. Its Jacobian jumps across the
switch ``d' = 0`` (``SWITCHES = 1``: dF/dd' goes from c(d) to 0), and on a
point contact it is unbounded after an onset (``dF/dd = chi beta d^(chi - 1) +
q c(d) d' / d ~ d^(-3/4)``), which no Runge-Kutta stage can sample. A tangent
run on a point model (wall, pair) integrates the approach phase's tangent
vectors in shifted coordinates instead (``SHIFTED_TANGENT``): ``w = v - c(d)
e_F (grad(d) . v)``, whose equations ``w' = J_el (w + c(d) e_F (grad(d) .
w))`` (``J_el`` the Jacobian with the elastic stiffness only) have bounded
coefficients; the engine lands on the switch d' = 0 (:func:`point_switch`), where it
converts back, and keeps the phase in the block's ``phase`` slot
(:func:`on_switch`, :func:`point_stiffness`, :func:`point_shift`;
docs/contact_laws.md section 7).

Line resultants: the approach part of the line (``r(s) > 0``) is a half-line,
split at ``s* = r_lo / (r_lo - r_hi)``; on it ``d`` and ``r`` are again linear
and :func:`.dissipation.approach_rate_moments` rescales the piece's moments.
The Jacobian's d-derivative of the damping uses the exponent ``q - 1 = -3/4``
(an integrable singularity at the contact edge, where the moments stay finite).

Units (docs/model.md section 2): d in A_g, r in A_g omega_Ax, beta in
``K_Ax A_g^(1 - chi)``, m_eff in m_A; ``c(d) = c_s d^q`` is a damping
coefficient in K_Ax / omega_Ax, so c_s is in ``K_Ax / (omega_Ax A_g^q)``.
"""

from __future__ import annotations

import math

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.contact.dissipation import (
    approach_rate_force,
    approach_rate_moments,
    check_restitution,
)
from chaospound.physics.contact.hertz import (  # noqa: F401  (elastic potential; no memory)
    line_potential,
    on_onset,
    point_potential,
)
from chaospound.physics.contact.moments import moments
from chaospound.physics.powers import power

NAME = "jankowski"
#: the law's block, in order; ``phase`` holds the engine's flags of a point contact's
#: tangent run (:func:`on_switch`), 0 from :func:`block` and in every other run
PARAMETERS = ("beta", "chi", "c_scale", "phase")
PHASE_KNOWN = 1  #: bit of the ``phase`` slot: the engine wrote its phase flag (the next bit)
APPROACH = 2  #: bit: the engine integrates the approach phase's shifted tangent vectors
MEMORY = ()  #: no per-episode memory
CONSERVATIVE = False  #: dissipative; the potentials below are the elastic part's
DISSIPATIVE = True  #: the force depends on the penetration rate
JUMPS = False  #: continuous force; its Jacobian jumps at d' = 0
SWITCHES = 1  #: the surface d' = 0 while in contact (approach -> restitution)
#: dF/dd grows like d^(-3/4) d' as a point contact starts (the damping coefficient
#: goes like d^(1/4)): integrable, so the flow is differentiable, but the variational
#: equations of a point contact are singular at every onset. A point model's tangent
#: run integrates the approach phase's vectors shifted by ``-c(d) e_F grad(d)^T``,
#: whose equations are bounded (:func:`point_shift`; along a line the singularity is
#: integrated over the overlap and no shift is needed)
SHIFTED_TANGENT = True


def damping_ratio(e: float) -> float:
    """Jankowski's ``xi = 9 sqrt(5) (1 - e^2) / (2 e (e (9 pi - 16) + 16))``, 0 for e = 1."""
    check_restitution(e)
    return 9.0 * math.sqrt(5.0) * (1.0 - e * e) / (2.0 * e * (e * (9.0 * math.pi - 16.0) + 16.0))


def block(e: float, *, beta: float, m_eff: float, chi: float = 1.5) -> dict[str, float]:
    """Block values from the physical inputs.

    Parameters
    ----------
    e : float
        Target coefficient of restitution, 0 < e <= 1 (e = 1: Hertz).
    beta : float
        Hertz stiffness, units of ``K_Ax A_g^(1 - chi)``, > 0.
    m_eff : float
        Effective mass of the pair, units of m_A (:func:`.dissipation.effective_mass`).
    chi : float
        Hertz exponent; the paper's 1.5 (the xi formula is calibrated for it).

    Returns
    -------
    dict
        ``{"beta", "chi", "c_scale": 2 xi sqrt(beta m_eff), "phase": 0}``.
    """
    if not beta > 0.0 or not m_eff > 0.0 or not chi >= 1.0:
        raise ValueError(f"beta = {beta}, m_eff = {m_eff}, chi = {chi}: need > 0, > 0, >= 1")
    c_scale = 2.0 * damping_ratio(e) * math.sqrt(beta * m_eff)
    return {"beta": float(beta), "chi": float(chi), "c_scale": float(c_scale), "phase": 0.0}


@inline
def point_force(p, base, d, rate):
    """``beta d^chi + c_s d^q d'`` approaching, ``beta d^chi`` separating; 0 for d <= 0."""
    if d <= 0.0:
        return 0.0
    chi = p[base + 1]
    f = p[base] * power(d, chi)
    if rate > 0.0:
        f += p[base + 2] * power(d, 0.5 * (chi - 1.0)) * rate
    return f


@inline
def _stiffness(p, base, d, rate):
    """``(dF/dd, dF/drate)`` of :func:`point_force` (one-sided at d' = 0: separating)."""
    if d <= 0.0:
        return 0.0, 0.0
    chi = p[base + 1]
    k = p[base] * chi * power(d, chi - 1.0)
    if rate > 0.0:
        q = 0.5 * (chi - 1.0)
        c = p[base + 2] * power(d, q)
        return k + q * c / d * rate, c
    return k, 0.0


@inline
def point_stiffness(p, base, d, rate):
    """``(dF/dd, dF/drate)`` of :func:`point_force`, units of K_Ax and K_Ax / omega_Ax.

    In a tangent run of a point model (the engine's flag written,
    :func:`on_switch`): the elastic stiffness ``chi beta d^(chi - 1)`` alone, in
    both phases: while approaching, the damping enters the shifted tangent
    vectors' equations through :func:`point_shift`, and ``dF/dd``'s singular
    term ``q c(d) d' / d`` cancels (docs/contact_laws.md section 7). Otherwise
    the derivatives themselves, one-sided at d' = 0 (separating).
    """
    if int(p[base + 3]) & PHASE_KNOWN:
        if d <= 0.0:
            return 0.0, 0.0
        chi = p[base + 1]
        return p[base] * chi * power(d, chi - 1.0), 0.0
    return _stiffness(p, base, d, rate)


@kernel
def point_force_rate(p, base, d, rate, accel=0.0):
    """``dF/dt = dF/dd d' + dF/dd' d''`` in contact (``accel`` = d'')."""
    k, c = _stiffness(p, base, d, rate)
    return k * rate + c * accel


@kernel
def shift_scale(p, base, d):
    """The damping coefficient ``c(d) = c_s d^q`` (0 for d <= 0), units of K_Ax / omega_Ax.

    The shift of the approach phase's tangent vectors, ``w = v - c(d) e_F
    (grad(d) . v)``, and of its inverse ``v = w + c(d) e_F (grad(d) . w)``
    (:func:`chaospound.engine.memory.shift_tangent`): 0 at an onset, so the
    shift starts as the identity.
    """
    if d <= 0.0:
        return 0.0
    return p[base + 2] * power(d, 0.5 * (p[base + 1] - 1.0))


@inline
def point_shift(p, base, d):
    """The shift coefficient of the model's linearisation (units of K_Ax / omega_Ax).

    ``c(d)`` in contact where the engine's flag says it integrates an approach
    phase (:func:`on_switch`), else 0. The point models apply their Jacobian
    (with :func:`point_stiffness`'s elastic stiffness) to ``w + s e_F (grad(d) .
    w)``: ``J_w w = J_el P^-1 w``, the shifted vectors' equations.
    """
    if int(p[base + 3]) & APPROACH:
        return shift_scale(p, base, d)
    return 0.0


@kernel
def point_switch(p, base, d, rate):
    """The switch function of a point contact: its rate d' (units of A_g omega_Ax).

    Approaching where d' > 0; its Jacobian (and the tangent vectors'
    representation) changes on d' = 0 inside the contact (the force does not:
    no saltation), so a tangent run lands its steps there
    (chaospound/engine/loop.py).
    """
    return rate


@kernel
def on_switch(p, base, clipped):
    """Record the engine's phase of a point contact in a tangent run.

    ``clipped`` False: in contact and approaching, the damping on, the tangent
    vectors shifted (:func:`point_shift`); True: separating or out of contact.
    Sets :data:`PHASE_KNOWN`, after which :func:`point_stiffness` drops the
    damping's derivatives (only a run that writes the flag has it).
    """
    p[base + 3] = float(PHASE_KNOWN if clipped else PHASE_KNOWN | APPROACH)


@inline
def line_force(p, base, d_c, slope, rate_c, rate_slope, half_length):
    """Resultant force and first moment of the line contact.

    Parameters
    ----------
    p : ndarray
        Packed parameters; block ``(beta, chi, c_scale)``.
    base : int
        First slot of the law's block.
    d_c, slope : float
        Centre penetration (units of A_g) and ``dd/dy`` (radians).
    rate_c, rate_slope : float
        Their time derivatives (units of A_g omega_Ax, omega_Ax).
    half_length : float
        L / 2 (units of A_g).

    Returns
    -------
    (force, moment, d_lo, d_hi) : tuple of float
        ``(1/L) int f dy`` (units of A_g K_Ax), ``(1/L) int f (y - y_c) dy``
        (units of A_g^2 K_Ax) and the end penetrations.
    """
    beta = p[base]
    chi = p[base + 1]
    c_s = p[base + 2]
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, d_lo, d_hi
    m0, m1, _ = moments(chi, d_lo, d_hi)
    force = beta * m0
    moment = beta * 2.0 * half_length * m1
    r_lo = rate_c - rate_slope * half_length
    r_hi = rate_c + rate_slope * half_length
    if r_lo > 0.0 or r_hi > 0.0:
        i0, i1 = approach_rate_force(0.5 * (chi - 1.0), d_lo, d_hi, r_lo, r_hi)
        force += c_s * i0
        moment += c_s * 2.0 * half_length * i1
    return force, moment, d_lo, d_hi


@kernel
def line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length):
    """Derivatives of (force, moment) of :func:`line_force`.

    Returns
    -------
    tuple of 8 float
        ``(F_dc, F_sl, M_dc, M_sl, F_rc, F_rs, M_rc, M_rs)`` with respect to the
        centre penetration, the slope, the centre rate and the rate's slope
        (one-sided where the rate vanishes: separating).
    """
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    beta = p[base]
    chi = p[base + 1]
    c_s = p[base + 2]
    q = 0.5 * (chi - 1.0)
    n0, n1, n2 = moments(chi - 1.0, d_lo, d_hi)
    length = 2.0 * half_length
    scale = beta * chi
    f_dc = scale * n0
    f_sl = scale * length * n1
    m_sl = scale * length * length * n2
    if rate_lo <= 0.0 and rate_hi <= 0.0:
        return f_dc, f_sl, f_sl, m_sl, 0.0, 0.0, 0.0, 0.0
    _, _, _, j0, j1, j2 = approach_rate_moments(q - 1.0, d_lo, d_hi, rate_lo, rate_hi)
    a0, a1, a2, _, _, _ = approach_rate_moments(q, d_lo, d_hi, rate_lo, rate_hi)
    damp = c_s * q
    f_sl += damp * length * j1
    return (f_dc + damp * j0, f_sl, f_sl, m_sl + damp * length * length * j2,
            c_s * a0, c_s * length * a1, c_s * length * a1, c_s * length * length * a2)


@kernel
def line_force_rate(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length, accel_lo=0.0,
                    accel_hi=0.0):
    """``dF/dt`` from the end rates and accelerations (units of A_g omega_Ax^2)."""
    fc, fs, _, _, frc, frs, _, _ = line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi,
                                                 half_length)
    length = 2.0 * half_length
    return (fc * 0.5 * (rate_lo + rate_hi) + fs * (rate_hi - rate_lo) / length
            + frc * 0.5 * (accel_lo + accel_hi) + frs * (accel_hi - accel_lo) / length)
