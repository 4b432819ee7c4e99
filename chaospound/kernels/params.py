"""Layout of the packed parameter vector shared by every kernel.

A :class:`chaospound.scene.Scene` is packed (``Scene.pack()``) into one float64
vector ``p`` of length :data:`N_PARAMS` plus an integer model id. Kernels read
``p`` through the index constants below and never see names or objects.
Every quantity is dimensionless (docs/model.md section 2): lengths in A_g, time
multiplied by omega_Ax.

The slots are not numbered by hand: they are generated from the named blocks
of :data:`BLOCKS` (the global entries, tower A, tower B, the reference
systems), each block starting where the previous one ends, so that every slot
is unique and the vector has no holes. The generated names are plain
module-level integers (numba reads them as compile-time constants):

* ``P_*``: the slot of a global entry;
* ``TOWER_A``, ``TOWER_B``: the first slot of a tower's block, and ``T_*`` the
  offset of a field inside a tower block (``p[TOWER_B + T_MU]``);
* ``REF_*``: the slot of a reference-system parameter;
* :data:`N_PARAMS`: the length of the vector; :data:`LAYOUT`: every slot's
  qualified name (``"tower_B.T_MU"``).

Derived quantities (products such as ``2 zeta Om``) are precomputed by the
packer so that the right-hand sides stay a handful of multiply-adds.
"""

# ---------------------------------------------------------------- model ids
WALL = 0  #: Davis (1992): tower A, X only, against a ground-borne wall (2 states)
TOWER_WALL = 1  #: tower A (X, Y, th) against a ground-borne wall (6 states)
PAIR = 2  #: Chau & Wei (2001): X_A and X_B (4 states)
TOWERS = 3  #: the general 12-state torsional model

LORENZ = 4  #: Lorenz (1963) system, a validation case for the Lyapunov engine
DUFFING = 5  #: forced Duffing oscillator x'' + d x' + a x + b x^3 = g cos(w t)
CUSTOM = 6  #: a user's jitted system (composed with the model "user")
TANGENT = 8  #: offset of the tangent (variational) models: id = TANGENT + base id

MODEL_NAMES = ("wall", "tower-wall", "pair", "towers")  #: the pounding models
SYSTEM_NAMES = MODEL_NAMES + ("lorenz", "duffing", "custom")  #: every system kind
MODEL_DIMS = (2, 6, 4, 12, 3, 2)  #: state dimension of each base model

# ------------------------------------------------------------ the blocks
#: the global entries of a scene: (name, meaning)
GLOBAL_FIELDS = (
    ("P_PERIOD_RATIO", "r = T / T_Ax; u_g(t) = sin(t / r)"),
    ("P_GROUND", "1.0: harmonic ground motion, 0.0: none (u_g = 0)"),
    ("P_GAP", "a, clear gap at rest"),
    ("P_BETA", "Hertz stiffness beta"),
    ("P_CHI", "Hertz exponent chi"),
    ("P_Y_C", "centre of the rest overlap [y_lo, y_hi] (global y)"),
    ("P_HALF_L", "half of L_ref = y_hi - y_lo"),
    ("P_Y_OFF", "y of B's stiffness centre minus A's"),
    ("P_PHASE0", "time origin of the stroboscopic section t0 (normalised time)"),
    ("P_PERIOD", "excitation period T = 2 pi r"),
)

#: the fields of one tower block (the same for A and B): (offset name, meaning)
TOWER_FIELDS = (
    ("T_OM2", "Om_i^2 (Om_i: 1 for A, Om for B)"),
    ("T_MU", "mu_i (1 for A, m for B): factor on the contact forces"),
    ("T_CX", "2 zeta_x Om_i (x damping coefficient)"),
    ("T_CY", "2 zeta_y Om_i (y damping coefficient)"),
    ("T_CT", '2 zeta_t Om_ti ("consistent") or 2 zeta_t Om_i ("as-printed")'),
    ("T_EX", "e_x = CM minus stiffness centre, x"),
    ("T_EY", "e_y = CM minus stiffness centre, y"),
    ("T_RHO2", "rho_i^2, squared radius of gyration about the CM"),
    ("T_OMT2", "Om_ti^2 = Om_i^2 (l^2 + w^2 + 4|e|^2) / (4 rho^2)"),
    ("T_L", "l_i, plan length along the gap line (y)"),
    ("T_W", "w_i, plan width across the gap (x)"),
    ("T_KTH", "Om_i^2 / rho_i^2 (coupling of translation into torsion)"),
    ("T_MU_RHO2", "mu_i / rho_i^2 (contact moment into torsional acceleration)"),
)

#: the parameters of the reference (validation) systems, :mod:`.reference`
REFERENCE_FIELDS = (
    ("REF_0", "Lorenz sigma; Duffing damping d"),
    ("REF_1", "Lorenz rho; Duffing linear stiffness a"),
    ("REF_2", "Lorenz b; Duffing cubic stiffness b"),
    ("REF_3", "Duffing forcing amplitude g"),
    ("REF_4", "Duffing forcing frequency w (the period P_PERIOD is 2 pi / w)"),
)

#: the vector, block after block: (block name, fields, name of its first slot or None)
BLOCKS = (
    ("globals", GLOBAL_FIELDS, None),
    ("tower_A", TOWER_FIELDS, "TOWER_A"),
    ("tower_B", TOWER_FIELDS, "TOWER_B"),
    ("reference", REFERENCE_FIELDS, None),
)


def _generate(blocks) -> tuple[dict[str, int], tuple[str, ...]]:
    """The index constants and the qualified name of every slot, block after block.

    A block with a start name (a tower) defines that name as its first slot
    and its fields as offsets inside it; the fields of a block without one
    are absolute slots.
    """
    constants: dict[str, int] = {}
    layout: list[str] = []
    for block, fields, start_name in blocks:
        start = len(layout)
        if start_name is not None:
            constants[start_name] = start
        for offset, (name, _meaning) in enumerate(fields):
            value = offset if start_name is not None else start + offset
            if constants.setdefault(name, value) != value:
                raise ValueError(f"{name} names two different slots")
            layout.append(f"{block}.{name}")
    constants["N_PARAMS"] = len(layout)
    return constants, tuple(layout)


_CONSTANTS, LAYOUT = _generate(BLOCKS)
globals().update(_CONSTANTS)  # P_*, TOWER_A, TOWER_B, T_*, REF_*, N_PARAMS
