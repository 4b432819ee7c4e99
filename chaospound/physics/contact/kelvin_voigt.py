"""Kelvin-Voigt contact, ``F = k d + c d'`` (Anagnostopoulos 1988).

Force per unit length ``f(d, r) = k d + c r`` where ``d > 0`` (``r = d'`` the
local penetration rate), 0 elsewhere, with

    c = 2 xi sqrt(k m_eff),   xi = -ln e / sqrt(pi^2 + ln^2 e)

so that a free impact of two bodies of effective mass ``m_eff`` ends with the
speed ratio e exactly (the half-cycle of a damped linear oscillator; checked to
1e-8 in tests/test_contact_laws.py).

Units (dimensionless model, docs/model.md section 2): d in A_g, r in A_g
omega_Ax, k in K_Ax, c in K_Ax / omega_Ax, m_eff in m_A (from
:func:`.dissipation.effective_mass`).

Two variants, by the block's ``no_pull`` flag:

* ``no_pull = 0`` (**default**), the law as Anagnostopoulos wrote it: near the
  end of the restitution phase ``k d + c d' < 0`` and the law pulls the bodies
  together (a small tensile force; the force jumps from ``c d'`` to 0 when d
  reaches 0). It is the default because it is the law every xi(e) formula of
  the literature is derived for: the measured e equals the target exactly, and
  the law is linear (smooth) inside the contact, so the Jacobians and tangent
  dynamics have no extra switch.
* ``no_pull = 1``: ``f = max(k d + c d', 0)``, the usual fix "contact ends when
  F reaches 0", written pointwise and memoryless (for a free impact the two
  readings coincide; the pointwise form re-engages continuously if the rate
  reverses while the faces still overlap). No tensile force, but the measured e
  exceeds the target (docs/contact_laws.md gives the numbers).

The force jumps at onset (``c v0``), hence ``JUMPS = True``: on a point
contact the engine maps the tangent vectors there by the saltation matrix, from
:func:`point_jump`, and in a tangent run lands on the no-pull switch ``k d + c
d' = 0``, :func:`point_switch` (docs/contact_laws.md section 7). On a line
contact the penetrated part and, with ``no_pull``, the part where ``k d + c r >
0`` are both half-lines in y (d and r are linear), so the resultants are closed
forms:
the plain law through the moments of :mod:`.moments` with j = 1 and j = 0
(``M0(0)`` is the penetrated fraction), the clipped law by integrating the
linear ``k d + c r`` over the intersection.
"""

from __future__ import annotations

import math

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.contact.dissipation import (
    check_restitution,
    rate_moments,
    restitution_log,
)
from chaospound.physics.contact.linear import (  # noqa: F401  (elastic potential; no memory)
    line_potential,
    on_onset,
    point_potential,
)
from chaospound.physics.contact.moments import force_moments, moments

NAME = "kelvin-voigt"
#: the law's block, in order; the slot ``no_pull`` holds mode bits: bit 0 is the
#: no-pull flag (0 or 1 from :func:`block`), bits 1-3 the engine's contact flags of the
#: ends (:func:`on_sides`), bits 4-5 its no-pull switch flag of a point contact in a
#: tangent run (:func:`on_switch`); 0 until an engine writes them
PARAMETERS = ("k", "c", "no_pull")
NO_PULL = 1  #: bit of the ``no_pull`` slot: clip the force at 0
SIDES_KNOWN = 2  #: bit: the engine wrote its contact flags (the next two bits)
SIDE_LO = 4  #: bit: the engine counts the y_lo end in contact
SIDE_HI = 8  #: bit: the engine counts the y_hi end in contact
SWITCH_KNOWN = 16  #: bit: the engine wrote its no-pull switch flag (the next bit)
CLIPPED = 32  #: bit: the engine counts a point contact's no-pull force clipped (g < 0)
MEMORY = ()  #: no per-episode memory
CONSERVATIVE = False  #: dissipative; the potentials below are the elastic part's
DISSIPATIVE = True  #: the force depends on the penetration rate
JUMPS = True  #: the force jumps at onset (and, plain, at release)
SWITCHES = 0  #: no_pull adds the surface k d + c d' = 0, continuous in F (no jump)


def damping_ratio(e: float) -> float:
    """``xi = -ln e / sqrt(pi^2 + ln^2 e)`` (dimensionless), 0 for e = 1."""
    return restitution_log(e)


def block(e: float, *, k: float, m_eff: float, no_pull: bool = False) -> dict[str, float]:
    """Block values from the physical inputs.

    Parameters
    ----------
    e : float
        Target coefficient of restitution, 0 < e <= 1 (e = 1: the linear law).
    k : float
        Contact stiffness, units of K_Ax, > 0.
    m_eff : float
        Effective mass of the pair, units of m_A (:func:`.dissipation.effective_mass`).
    no_pull : bool
        Clip the force at 0 (no tensile force); default False (see the module).

    Returns
    -------
    dict
        ``{"k": k, "c": 2 xi sqrt(k m_eff), "no_pull": 0.0 or 1.0}``, c in units
        of K_Ax / omega_Ax.
    """
    check_restitution(e)
    if not k > 0.0 or not m_eff > 0.0:
        raise ValueError(f"k = {k}, m_eff = {m_eff}: need both > 0")
    c = 2.0 * damping_ratio(e) * math.sqrt(k * m_eff)
    return {"k": float(k), "c": float(c), "no_pull": 1.0 if no_pull else 0.0}


@kernel
def on_sides(p, base, inside_lo, inside_hi):
    """Record which ends of the line the engine counts in contact (its event flags).

    The line resultant is continuous where an end crosses d = 0, but its
    Jacobian jumps there (the edge term of :func:`line_gradient` appears or
    vanishes). The engine lands a step on every crossing and flips its flag
    after the step, so a Jacobian that follows the flags is the one-sided
    limit on each side of the crossing at every stage of both steps, which the
    variational equations need (docs/contact_laws.md section 7); one that
    followed the sign of d would switch at a stage a rounding error from the
    crossing. The flags are bits of the ``no_pull`` slot (its bit 0 kept); a block
    no engine has run has none, and the sign of d decides.
    """
    bits = (int(p[base + 2]) & NO_PULL) | SIDES_KNOWN
    if inside_lo:
        bits |= SIDE_LO
    if inside_hi:
        bits |= SIDE_HI
    p[base + 2] = float(bits)


@kernel
def point_switch(p, base, d, rate):
    """The no-pull law's switch function ``g = k d + c d'`` of a point contact.

    In contact the force is clipped where g < 0; its Jacobian jumps from ``(k,
    c)`` to 0 on g = 0 (the force does not: no saltation), so a tangent run lands
    its steps there as on a crossing (chaospound/engine/loop.py). Units of A_g
    K_Ax; 1.0 for the plain law (no switch).
    """
    if not _no_pull(p, base):
        return 1.0
    return p[base] * d + p[base + 1] * rate


@kernel
def on_switch(p, base, clipped):
    """Record whether the engine counts the point contact's no-pull force clipped.

    Bits 4 and 5 of the ``no_pull`` slot (the others kept); :func:`on_sides`
    clears them, so only a run that writes them (a tangent run on a point
    contact) has them, and :func:`point_stiffness` follows them there.
    """
    bits = (int(p[base + 2]) & ~(SWITCH_KNOWN | CLIPPED)) | SWITCH_KNOWN
    if clipped:
        bits |= CLIPPED
    p[base + 2] = float(bits)


@inline
def _no_pull(p, base):
    """The ``no_pull`` flag (bit 0 of its slot)."""
    return (int(p[base + 2]) & NO_PULL) != 0


@inline
def point_force(p, base, d, rate):
    """Contact force ``k d + c d'`` of a point contact (0 when d <= 0), units of A_g K_Ax."""
    if d <= 0.0:
        return 0.0
    f = p[base] * d + p[base + 1] * rate
    if _no_pull(p, base) and f < 0.0:
        return 0.0
    return f


@inline
def point_stiffness(p, base, d, rate):
    """``(dF/dd, dF/drate)`` of :func:`point_force` (0 where clipped), units of K_Ax
    and K_Ax / omega_Ax.

    In contact where the engine's flag says so (:func:`on_sides`; a point contact
    has one end, both flags equal), else where d > 0 (a block no engine has run);
    with no_pull, clipped where the engine's switch flag says so
    (:func:`on_switch`), else where ``k d + c d' < 0``: the variational equations
    need the one-sided Jacobian on each side of an onset, a release or the
    no-pull switch at every stage, and a landed state is a rounding error from
    the surface on either side (docs/contact_laws.md section 7). The force
    itself (:func:`point_force`) follows the signs of d and of ``k d + c d'``.
    """
    bits = int(p[base + 2])
    inside = d > 0.0
    if bits & SIDES_KNOWN:
        inside = (bits & SIDE_LO) != 0
    if not inside:
        return 0.0, 0.0
    if bits & NO_PULL:
        clipped = p[base] * d + p[base + 1] * rate < 0.0
        if bits & SWITCH_KNOWN:
            clipped = (bits & CLIPPED) != 0
        if clipped:
            return 0.0, 0.0
    return p[base], p[base + 1]


@kernel
def point_jump(p, base, rate, onset):
    """The point force's jump where d crosses 0, divided by the closing rate.

    The saltation matrix of a point contact (docs/contact_laws.md section 7) is
    ``I + (f+ - f-) grad(d)^T / d'``, and ``f+ - f-`` is the jump ``dF`` of the
    force times its column of the vector field, so the engine needs
    ``dF / d'``, a contact stiffness (:func:`chaospound.engine.memory.saltation_tangent`).
    Just inside, at d = 0, the force is ``c d'`` (``max(c d', 0)`` with no_pull), so

    * onset (``onset`` True, d' >= 0): ``dF = c d'``, returns ``c``;
    * plain release (d' <= 0): ``dF = -c d'``, returns ``-c``;
    * no_pull release: ``k d + c d' = c d' < 0`` is clipped, F is already 0: returns 0
      (the clipped law's release is continuous); likewise an onset at d' < 0.

    Parameters
    ----------
    p : ndarray
        Packed parameters; the block is ``(k, c, no_pull)`` from ``p[base]``.
    base : int
        First slot of the law's block.
    rate : float
        Closing rate d' at the event, units of A_g omega_Ax (only its sign matters).
    onset : bool
        True where d becomes positive, False where it becomes negative.

    Returns
    -------
    float
        ``dF / d'``, units of K_Ax / omega_Ax (finite at a graze, d' -> 0).
    """
    c = p[base + 1]
    if _no_pull(p, base) and (rate < 0.0 if onset else rate <= 0.0):
        return 0.0
    return c if onset else -c


@kernel
def point_force_rate(p, base, d, rate, accel=0.0):
    """``dF/dt = k d' + c d''`` in contact (``accel`` = d'', units of A_g omega_Ax^2)."""
    if _no_pull(p, base) and p[base] * d + p[base + 1] * rate < 0.0:
        return 0.0
    return p[base] * rate + p[base + 1] * accel


@inline
def _penetrated(d_lo, d_hi):
    """``(a, b, edge)``: the penetrated interval [a, b] of s in [0, 1] and the
    position of the contact edge d = 0 inside it (-1.0 when in full contact)."""
    if d_lo > 0.0 and d_hi > 0.0:
        return 0.0, 1.0, -1.0
    s_d = d_lo / (d_lo - d_hi)
    if d_hi > 0.0:
        return s_d, 1.0, s_d
    return 0.0, s_d, s_d


@inline
def _flagged_edge(inside_lo, inside_hi, d_lo, d_hi):
    """The contact edge's position in [0, 1] when exactly one end is flagged in
    contact (where d = 0, clamped to the line), else -1.0 (:func:`on_sides`)."""
    if inside_lo == inside_hi or d_lo == d_hi:
        return -1.0
    return min(max(d_lo / (d_lo - d_hi), 0.0), 1.0)


@inline
def _clipped_region(k, c, d_lo, d_hi, r_lo, r_hi):
    """The part of the line where ``d > 0`` and ``g = k d + c r > 0``.

    Returns ``(a, b, g_a, g_b, edge, pulls)``: the interval, g at its ends, the
    contact edge's position when it bounds the interval (else -1.0), and whether
    g < 0 anywhere on the penetrated part (``pulls``: False means the plain
    formulas apply unchanged).
    """
    a, b, edge = _penetrated(d_lo, d_hi)
    dd = d_hi - d_lo
    dr = r_hi - r_lo
    g_a = (k * (d_lo + dd * a) if a != edge else 0.0) + c * (r_lo + dr * a)
    g_b = (k * (d_lo + dd * b) if b != edge else 0.0) + c * (r_lo + dr * b)
    if g_a >= 0.0 and g_b >= 0.0:
        return a, b, g_a, g_b, edge, False
    if g_a <= 0.0 and g_b <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, -1.0, True
    s_g = a + (b - a) * (g_a / (g_a - g_b))
    if g_b > 0.0:
        return s_g, b, 0.0, g_b, (edge if b == edge else -1.0), True
    return a, s_g, g_a, 0.0, (edge if a == edge else -1.0), True


@inline
def line_force(p, base, d_c, slope, rate_c, rate_slope, half_length):
    """Resultant force and first moment of a Kelvin-Voigt line contact.

    Parameters
    ----------
    p : ndarray
        Packed parameters; the block is ``(k, c, no_pull)`` from ``p[base]``.
    base : int
        First slot of the law's block.
    d_c, slope : float
        Penetration at the centre of the rest overlap (units of A_g) and
        ``dd/dy`` (radians).
    rate_c, rate_slope : float
        Their time derivatives (units of A_g omega_Ax and omega_Ax).
    half_length : float
        Half the rest-overlap length L / 2 (units of A_g).

    Returns
    -------
    (force, moment, d_lo, d_hi) : tuple of float
        ``force = (1/L) int f dy`` (units of A_g K_Ax), ``moment = (1/L) int f
        (y - y_c) dy`` (units of A_g^2 K_Ax) and the end penetrations.
    """
    k = p[base]
    c = p[base + 1]
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, d_lo, d_hi
    r_lo = rate_c - rate_slope * half_length
    r_hi = rate_c + rate_slope * half_length
    if _no_pull(p, base):
        a, b, g_a, g_b, _, pulls = _clipped_region(k, c, d_lo, d_hi, r_lo, r_hi)
        if pulls:
            ell = b - a
            mean_g = 0.5 * (g_a + g_b)
            first = ell * (mean_g * (0.5 * (a + b) - 0.5) + (g_b - g_a) * ell / 12.0)
            return ell * mean_g, 2.0 * half_length * first, d_lo, d_hi
    m0, m1 = force_moments(1.0, d_lo, d_hi)
    i0, i1 = rate_moments(0.0, d_lo, d_hi, r_lo, r_hi)
    length = 2.0 * half_length
    return k * m0 + c * i0, k * 2.0 * half_length * m1 + c * length * i1, d_lo, d_hi


@kernel
def line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length):
    """Derivatives of (force, moment) of :func:`line_force`.

    Returns
    -------
    tuple of 8 float
        ``(F_dc, F_sl, M_dc, M_sl, F_rc, F_rs, M_rc, M_rs)`` with respect to the
        centre penetration, the slope, the centre rate and the rate's slope. The
        moving contact edge ``s_e`` (where ``f = c r(s_e)`` jumps to 0) adds
        ``B = c r(s_e) / |d_hi - d_lo|`` to ``F_dc`` and ``L (s_e - 1/2)``,
        ``L^2 (s_e - 1/2)^2`` times it to ``F_sl = M_dc`` and ``M_sl``.
    """
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    k = p[base]
    c = p[base + 1]
    length = 2.0 * half_length
    clipped = False
    if _no_pull(p, base):
        a, b, _, _, edge, clipped = _clipped_region(k, c, d_lo, d_hi, rate_lo, rate_hi)
    if clipped:
        ell = b - a
        off = 0.5 * (a + b) - 0.5
        n0 = ell
        n1 = ell * off
        n2 = ell * (off * off + ell * ell / 12.0)
    else:
        n0, n1, n2 = moments(0.0, d_lo, d_hi)
        _, _, edge = _penetrated(d_lo, d_hi)
    bits = int(p[base + 2])
    if bits & SIDES_KNOWN:  # the engine's flags decide whether an edge is inside the line
        edge = _flagged_edge((bits & SIDE_LO) != 0, (bits & SIDE_HI) != 0, d_lo, d_hi)
    bound = 0.0
    arm = 0.0
    if edge >= 0.0:
        bound = c * (rate_lo + (rate_hi - rate_lo) * edge) / abs(d_hi - d_lo)
        arm = length * (edge - 0.5)
    f_dc = k * n0 + bound
    f_sl = k * length * n1 + arm * bound
    m_sl = k * length * length * n2 + arm * arm * bound
    return (f_dc, f_sl, f_sl, m_sl, c * n0, c * length * n1, c * length * n1,
            c * length * length * n2)


@kernel
def line_force_rate(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length, accel_lo=0.0,
                    accel_hi=0.0):
    """``dF/dt`` of the resultant from the end rates and accelerations (units of
    A_g omega_Ax^2): ``F_dc r_m + F_sl dr / L + F_rc a_m + F_rs da / L``."""
    fc, fs, _, _, frc, frs, _, _ = line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi,
                                                 half_length)
    length = 2.0 * half_length
    return (fc * 0.5 * (rate_lo + rate_hi) + fs * (rate_hi - rate_lo) / length
            + frc * 0.5 * (accel_lo + accel_hi) + frs * (accel_hi - accel_lo) / length)
