"""Layout of the packed parameter vector shared by every kernel.

A :class:`chaospound.scene.Scene` is packed (``Scene.pack()``) into one float64
vector ``p`` of length :data:`N_PARAMS` plus an integer model id. Kernels read
``p`` through the index constants below and never see names or objects.
Every quantity is dimensionless (docs/model.md section 2): lengths in A_g, time
multiplied by omega_Ax.

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
CUSTOM = 6  #: a user's jitted system (kernels.custom builds its integrator)
TANGENT = 8  #: offset of the tangent (variational) models: id = TANGENT + base id

MODEL_NAMES = ("wall", "tower-wall", "pair", "towers")  #: the pounding models
SYSTEM_NAMES = MODEL_NAMES + ("lorenz", "duffing", "custom")  #: every system kind
MODEL_DIMS = (2, 6, 4, 12, 3, 2)  #: state dimension of each base model

# ------------------------------------------------------------ global entries
P_PERIOD_RATIO = 0  #: r = T / T_Ax; u_g(t) = sin(t / r)
P_GROUND = 1  #: 1.0: harmonic ground motion, 0.0: none (u_g = 0)
P_GAP = 2  #: a, clear gap at rest
P_BETA = 3  #: Hertz stiffness beta
P_CHI = 4  #: Hertz exponent chi
P_Y_C = 5  #: centre of the rest overlap [y_lo, y_hi] (global y)
P_HALF_L = 6  #: half of L_ref = y_hi - y_lo
P_Y_OFF = 7  #: y of B's stiffness centre minus A's
P_PHASE0 = 8  #: time origin of the stroboscopic section t0 (normalised time)
P_PERIOD = 9  #: excitation period T = 2 pi r

# ------------------------------------------------------ per-tower blocks
TOWER_A = 10  #: first index of tower A's block
TOWER_B = 30  #: first index of tower B's block
# offsets inside a block
T_OM = 0  #: Om_i (1 for A, Om for B)
T_OM2 = 1  #: Om_i^2
T_MU = 2  #: mu_i (1 for A, m for B): factor on the contact forces
T_CX = 3  #: 2 zeta_x Om_i  (x damping coefficient)
T_CY = 4  #: 2 zeta_y Om_i  (y damping coefficient)
T_CT = 5  #: 2 zeta_t Om_ti ("consistent") or 2 zeta_t Om_i ("as-printed")
T_EX = 6  #: e_x = CM minus stiffness centre, x
T_EY = 7  #: e_y = CM minus stiffness centre, y
T_RHO2 = 8  #: rho_i^2, squared radius of gyration about the CM
T_OMT2 = 9  #: Om_ti^2 = Om_i^2 (l^2 + w^2 + 4|e|^2) / (4 rho^2)
T_L = 10  #: l_i, plan length along the gap line (y)
T_W = 11  #: w_i, plan width across the gap (x)
T_KTH = 12  #: Om_i^2 / rho_i^2 (coupling of translation into torsion)
T_MU_RHO2 = 13  #: mu_i / rho_i^2 (contact moment into torsional acceleration)

# ------------------------------------------- reference (validation) systems
REF_0 = 43  #: Lorenz sigma; Duffing damping d
REF_1 = 44  #: Lorenz rho; Duffing linear stiffness a
REF_2 = 45  #: Lorenz b; Duffing cubic stiffness b
REF_3 = 46  #: Duffing forcing amplitude g
REF_4 = 47  #: Duffing forcing frequency w (the period P_PERIOD is 2 pi / w)

N_PARAMS = 50
