"""Hertz contact with nonlinear damping, ``F = beta d^chi + xi d^chi d'``.

Force per unit length ``f(d, r) = beta d+^chi (1 + (xi / beta) r)``, with the
per-episode damping coefficient ``xi = zeta / v0`` and ``v0`` the approach
velocity at the episode's onset (memory written by :func:`on_onset`). Two
choices of ``zeta`` (the ``variant`` of :func:`block`):

* ``"lankarani-nikravesh"`` (default; Lankarani & Nikravesh 1990, the
  "Hertzdamp" model of Muthukumar & DesRoches 2006 and of OpenSees):
  ``zeta = 3 beta (1 - e^2) / 4``. Derived from an energy balance that assumes
  little dissipation: accurate for e near 1, it overestimates e as e falls;
* ``"ye"`` (Ye, Li & Zhu 2009): ``zeta = 8 beta (1 - e) / (5 e)``, derived for
  any e; it underestimates e slightly at low e.

:mod:`.hunt_crossley` is this law with ``zeta = 3 beta (1 - e) / 2``.
OpenSees' ``uniaxialMaterial Hertzdamp $Kh $xiNorm $gap <$n>`` is this law with
``xiNorm = zeta / beta`` (its manual recommends Ye's ``8 (1 - e) / (5 e)``);
:func:`block` takes ``xi_norm`` to set it directly.
docs/contact_laws.md gives the measured e of each against its target.

Units (docs/model.md section 2): d in A_g, r in A_g omega_Ax, beta in
``K_Ax A_g^(1 - chi)``, zeta likewise, v0 in A_g omega_Ax, xi in
``K_Ax A_g^(1 - chi) / (A_g omega_Ax)``.

The force is continuous (0 at d = 0, whatever the rate): ``JUMPS = False``. It
can turn tensile only if ``r < -v0 beta / zeta``; in a free impact the
force vanishes as the rate approaches that bound, so the separating rate
cannot cross it and the law never pulls (with other forces acting it could).
At low e, Ye's bound ``5 e v0 / (8 (1 - e))`` is what limits the measured e
(0.0694 at e = 0.1, equal to the bound to 3e-6).

v0 on a line contact: the closing velocity ``d'`` at the end that touches
first (the onset's contact point, the model's ``model_contact_point``; the
centre when the faces touch flat), at the onset, floored at ``v0_floor`` so a
grazing onset (``d' -> 0``) gives a finite xi. The force stays bounded as
v0 -> 0 (``xi d' <= zeta`` while ``d' <= v0``), so the floor only guards the
division; its default is :data:`.dissipation.V0_FLOOR`.

Line resultants (docs/design/engine.md 4.2): ``int d+^chi r (s - 1/2)^k ds =
r_m M_k + dr M_(k+1)`` from the moments of :mod:`.moments`; the Jacobian's
rate term needs the third moment :func:`.dissipation.moment3`.
"""

from __future__ import annotations

from chaospound.kernels.jit import inline, kernel
from chaospound.physics.contact.dissipation import (
    MAX_TANGENT_VECTORS,
    V0_FLOOR,
    check_restitution,
    moment3,
)
from chaospound.physics.contact.hertz import (  # noqa: F401  (the elastic part's potential)
    line_potential,
    point_potential,
)
from chaospound.physics.contact.moments import moments
from chaospound.physics.powers import power

NAME = "hertzdamp"
PARAMETERS = ("beta", "chi", "zeta", "v0_floor")  #: the law's block, in order
#: per-episode memory after PARAMETERS: onset velocity, xi = zeta / v0, then the tangent
#: dynamics' sensitivities d xi of each tangent vector (written at onset, docs/contact_laws.md 7)
MEMORY = ("v0", "xi") + tuple(f"dxi_{i}" for i in range(MAX_TANGENT_VECTORS))
CONSERVATIVE = False  #: dissipative; the potentials below are the elastic part's
DISSIPATIVE = True  #: the force depends on the penetration rate
JUMPS = False  #: the force is continuous across onset and release
SWITCHES = 0  #: no extra event surface while in contact
VARIANTS = ("lankarani-nikravesh", "ye")  #: the zeta(e) formulas of :func:`block`
_V0 = 4  #: offset of the memory slot v0 in the block
_XI = 5  #: offset of the memory slot xi
TANGENT_SLOT = 6  #: offset of the first tangent sensitivity d xi (one slot per tangent vector)


def damping_numerator(e: float, beta: float, variant: str = "lankarani-nikravesh") -> float:
    """``zeta = xi v0`` of a variant (units of ``K_Ax A_g^(1 - chi)``), 0 for e = 1."""
    check_restitution(e)
    if variant == "lankarani-nikravesh":
        return 3.0 * beta * (1.0 - e * e) / 4.0
    if variant == "ye":
        return 8.0 * beta * (1.0 - e) / (5.0 * e)
    raise ValueError(f"variant = {variant!r}: need one of {', '.join(VARIANTS)}")


def block(e: float, *, beta: float, chi: float = 1.5, variant: str = "lankarani-nikravesh",
          v0_floor: float = V0_FLOOR, v0_initial: float = 1.0,
          xi_norm: float | None = None) -> dict[str, float]:
    """Block values (parameters and initial memory) from the physical inputs.

    Parameters
    ----------
    e : float
        Target coefficient of restitution, 0 < e <= 1 (e = 1: Hertz).
    beta : float
        Hertz stiffness, units of ``K_Ax A_g^(1 - chi)``, > 0.
    chi : float
        Hertz exponent, >= 1.
    variant : str
        ``"lankarani-nikravesh"`` or ``"ye"`` (module docstring).
    v0_floor : float
        Floor of the onset velocity, units of A_g omega_Ax, > 0.
    v0_initial : float
        Memory before the first onset (a run that starts in contact), units of
        A_g omega_Ax; the ground velocity's scale by default.
    xi_norm : float or None
        OpenSees' normalised damping ``zeta / beta`` (dimensionless, >= 0);
        given, it replaces the variant's formula (e is then only checked).

    Returns
    -------
    dict
        ``beta, chi, zeta, v0_floor`` and the memory ``v0, xi``.
    """
    if xi_norm is not None:
        check_restitution(e)
        if not xi_norm >= 0.0:
            raise ValueError(f"xi_norm = {xi_norm}: need >= 0")
        return _block(xi_norm * beta, beta, chi, v0_floor, v0_initial)
    return _block(damping_numerator(e, beta, variant), beta, chi, v0_floor, v0_initial)


def _block(zeta: float, beta: float, chi: float, v0_floor: float,
           v0_initial: float) -> dict[str, float]:
    if not beta > 0.0 or not chi >= 1.0:
        raise ValueError(f"beta = {beta}, chi = {chi}: need beta > 0 and chi >= 1")
    if not v0_floor > 0.0:
        raise ValueError(f"v0_floor = {v0_floor}: need > 0")
    v0 = max(float(v0_initial), v0_floor)
    values = {"beta": float(beta), "chi": float(chi), "zeta": float(zeta),
              "v0_floor": float(v0_floor), "v0": v0, "xi": zeta / v0}
    values.update({name: 0.0 for name in MEMORY[2:]})
    return values


@kernel
def on_onset(p, base, rate):
    """Write the episode's memory: ``v0 = max(rate, v0_floor)``, ``xi = zeta / v0``.

    ``rate`` is the closing velocity at the onset (units of A_g omega_Ax) at the
    end that touches first.
    """
    v0 = max(rate, p[base + 3])
    p[base + _V0] = v0
    p[base + _XI] = p[base + 2] / v0


@kernel
def onset_sensitivity(p, base, rate):
    """``d xi / d rate`` of :func:`on_onset` at the onset's closing velocity ``rate``.

    ``-zeta / rate^2`` above the floor, 0 below it (v0 is then the constant
    floor). Units of ``K_Ax A_g^(1 - chi) / (A_g omega_Ax)^2``.
    """
    if rate > p[base + 3]:
        return -p[base + 2] / (rate * rate)
    return 0.0


@inline
def point_memory_force(p, base, d, rate):
    """``dF/d xi = d^chi d'`` of :func:`point_force` (0 when d <= 0)."""
    if d <= 0.0:
        return 0.0
    return power(d, p[base + 1]) * rate


@inline
def line_memory_force(p, base, d_c, slope, rate_c, rate_slope, half_length):
    """``(dF/d xi, dM/d xi)`` of :func:`line_force` (the force is affine in xi).

    Units: the force's and the moment's divided by xi's.
    """
    chi = p[base + 1]
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0
    m0, m1, m2 = moments(chi, d_lo, d_hi)
    length = 2.0 * half_length
    dr = rate_slope * length
    return rate_c * m0 + dr * m1, length * (rate_c * m1 + dr * m2)


@inline
def point_force(p, base, d, rate):
    """``beta d^chi + xi d^chi d'`` (0 when d <= 0), units of A_g K_Ax."""
    if d <= 0.0:
        return 0.0
    dj = power(d, p[base + 1])
    return p[base] * dj + p[base + _XI] * dj * rate


@inline
def point_stiffness(p, base, d, rate):
    """``(dF/dd, dF/drate)`` of :func:`point_force`."""
    if d <= 0.0:
        return 0.0, 0.0
    chi = p[base + 1]
    xi = p[base + _XI]
    pw = power(d, chi - 1.0)
    return p[base] * chi * pw + xi * chi * pw * rate, xi * power(d, chi)


@kernel
def point_force_rate(p, base, d, rate, accel=0.0):
    """``dF/dt = dF/dd d' + dF/dd' d''`` in contact (``accel`` = d'')."""
    beta = p[base]
    chi = p[base + 1]
    xi = p[base + _XI]
    pw = power(d, chi - 1.0)
    return beta * chi * pw * rate + xi * chi * pw * rate * rate + xi * pw * d * accel


@inline
def line_force(p, base, d_c, slope, rate_c, rate_slope, half_length):
    """Resultant force and first moment of the line contact.

    Parameters
    ----------
    p : ndarray
        Packed parameters; block ``(beta, chi, zeta, v0_floor, v0, xi)``.
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
    xi = p[base + _XI]
    d_lo = d_c - slope * half_length
    d_hi = d_c + slope * half_length
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, d_lo, d_hi
    m0, m1, m2 = moments(chi, d_lo, d_hi)
    length = 2.0 * half_length
    dr = rate_slope * length
    return (beta * m0 + xi * (rate_c * m0 + dr * m1),
            beta * 2.0 * half_length * m1 + xi * length * (rate_c * m1 + dr * m2), d_lo, d_hi)


@kernel
def line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length):
    """Derivatives of (force, moment) of :func:`line_force`.

    Returns
    -------
    tuple of 8 float
        ``(F_dc, F_sl, M_dc, M_sl, F_rc, F_rs, M_rc, M_rs)`` with respect to the
        centre penetration, the slope, the centre rate and the rate's slope.
    """
    if d_lo <= 0.0 and d_hi <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    beta = p[base]
    chi = p[base + 1]
    xi = p[base + _XI]
    n0, n1, n2 = moments(chi - 1.0, d_lo, d_hi)
    n3 = moment3(chi - 1.0, d_lo, d_hi)
    m0, m1, m2 = moments(chi, d_lo, d_hi)
    length = 2.0 * half_length
    r_m = 0.5 * (rate_lo + rate_hi)
    dr = rate_hi - rate_lo
    scale = beta * chi
    damp = xi * chi
    f_sl = scale * length * n1 + damp * length * (r_m * n1 + dr * n2)
    return (scale * n0 + damp * (r_m * n0 + dr * n1), f_sl, f_sl,
            scale * length * length * n2 + damp * length * length * (r_m * n2 + dr * n3),
            xi * m0, xi * length * m1, xi * length * m1, xi * length * length * m2)


@kernel
def line_force_rate(p, base, d_lo, d_hi, rate_lo, rate_hi, half_length, accel_lo=0.0,
                    accel_hi=0.0):
    """``dF/dt`` from the end rates and accelerations (units of A_g omega_Ax^2)."""
    fc, fs, _, _, frc, frs, _, _ = line_gradient(p, base, d_lo, d_hi, rate_lo, rate_hi,
                                                 half_length)
    length = 2.0 * half_length
    return (fc * 0.5 * (rate_lo + rate_hi) + fs * (rate_hi - rate_lo) / length
            + frc * 0.5 * (accel_lo + accel_hi) + frs * (accel_hi - accel_lo) / length)
