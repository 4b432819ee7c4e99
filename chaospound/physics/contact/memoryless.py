"""The memory and jump kernels of a law without memory or jumps (bound by such compositions).

A composition binds ``law_onset_sensitivity``, ``law_point_memory_force`` and
``law_line_memory_force`` from the law's module when the law has ``MEMORY``
(:mod:`.hertzdamp`, :mod:`.hunt_crossley`), and ``law_on_sides``,
``law_point_jump`` when it ``JUMPS`` (:mod:`.kelvin_voigt`), ``law_point_switch``
and ``law_on_switch`` when it jumps or shifts its point tangent
(``SHIFTED_TANGENT``: :mod:`.jankowski`), ``law_point_shift`` and
``law_shift_scale`` when it shifts, else from here: the engine calls them only
when ``LAW_MEMORY`` (``LAW_JUMPS``, ``LAW_SHIFTED``) is on, so these are never
reached; they exist so that every composition's text resolves the same names
(docs/contact_laws.md section 7).
"""

from chaospound.kernels.jit import inline, kernel

TANGENT_SLOT = 0  #: no tangent sensitivities in the block


@kernel
def onset_sensitivity(p, base, rate):
    """0: no memory written at onset."""
    return 0.0


@inline
def point_memory_force(p, base, d, rate):
    """0: the force does not depend on a memory."""
    return 0.0


@inline
def line_memory_force(p, base, d_c, slope, rate_c, rate_slope, half_length):
    """``(0, 0)``: the force does not depend on a memory."""
    return 0.0, 0.0


@kernel
def on_sides(p, base, inside_lo, inside_hi):
    """Nothing to record: the law's Jacobian does not jump where an end crosses."""
    return


@kernel
def point_jump(p, base, rate, onset):
    """0: the point force is continuous where d crosses 0 (no saltation)."""
    return 0.0


@kernel
def point_switch(p, base, d, rate):
    """1.0: no switch surface in contact."""
    return 1.0


@kernel
def on_switch(p, base, clipped):
    """Nothing to record: no switch surface."""
    return


@kernel
def shift_scale(p, base, d):
    """0: no shift of the tangent vectors."""
    return 0.0


@inline
def point_shift(p, base, d):
    """0: the point Jacobian is bounded, its tangent vectors are not shifted."""
    return 0.0
