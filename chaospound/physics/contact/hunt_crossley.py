"""Hunt-Crossley contact, ``F = beta d^chi (1 + 3 (1 - e) d' / (2 v0))`` (Hunt & Crossley 1975).

The same force as :mod:`.hertzdamp` with the damping numerator
``zeta = xi v0 = 3 beta (1 - e) / 2``: ``f = beta d^chi + (zeta / v0) d^chi d'``.
Hunt and Crossley obtained it from an energy balance valid for small
dissipation (e near 1, where ``1 - e^2 ~ 2 (1 - e)`` makes it agree with
Lankarani-Nikravesh); at low e it loses too little energy (docs/contact_laws.md).

The block, the memory (v0 and xi of the episode, written at onset), the units,
the v0 rule and every kernel are those of :mod:`.hertzdamp`; only :func:`block`
differs. Units: the dimensionless model (docs/model.md section 2).
"""

from __future__ import annotations

from chaospound.physics.contact.dissipation import V0_FLOOR, check_restitution
from chaospound.physics.contact.hertzdamp import (  # noqa: F401  (the law's kernels)
    CONSERVATIVE,
    DISSIPATIVE,
    JUMPS,
    MEMORY,
    PARAMETERS,
    SWITCHES,
    TANGENT_SLOT,
    _block,
    line_force,
    line_force_rate,
    line_gradient,
    line_memory_force,
    line_potential,
    on_onset,
    onset_sensitivity,
    point_force,
    point_force_rate,
    point_memory_force,
    point_potential,
    point_stiffness,
)

NAME = "hunt-crossley"


def damping_numerator(e: float, beta: float) -> float:
    """``zeta = 3 beta (1 - e) / 2`` (units of ``K_Ax A_g^(1 - chi)``), 0 for e = 1."""
    check_restitution(e)
    return 1.5 * beta * (1.0 - e)


def block(e: float, *, beta: float, chi: float = 1.5, v0_floor: float = V0_FLOOR,
          v0_initial: float = 1.0) -> dict[str, float]:
    """Block values (parameters and initial memory) from the physical inputs.

    Parameters
    ----------
    e : float
        Target coefficient of restitution, 0 < e <= 1 (e = 1: Hertz).
    beta : float
        Hertz stiffness, units of ``K_Ax A_g^(1 - chi)``, > 0.
    chi : float
        Hertz exponent, >= 1.
    v0_floor, v0_initial : float
        As :func:`chaospound.physics.contact.hertzdamp.block` (units of A_g omega_Ax).

    Returns
    -------
    dict
        ``beta, chi, zeta, v0_floor`` and the memory ``v0, xi``.
    """
    return _block(damping_numerator(e, beta), beta, chi, v0_floor, v0_initial)
