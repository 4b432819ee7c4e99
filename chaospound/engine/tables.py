"""Layouts of the arrays an engine run fills: the impact table and the run statistics."""

from chaospound.physics.corners import (  # noqa: F401  (re-exported for the drivers)
    CORNER_A_MINUS,
    CORNER_A_PLUS,
    CORNER_B_MINUS,
    CORNER_B_PLUS,
    CORNER_FACE,
    CORNER_LABELS,
    FACE_TOL,
)

# ------------------------------------------------------------- impact table
IMP_TIME = 0  #: onset time t (normalised)
IMP_PHASE = 1  #: (t mod T) / T in [0, 1)
IMP_VELOCITY = 2  #: relative impact velocity V (units of A_g omega_Ax)
IMP_CORNER = 3  #: corner code, see CORNER_LABELS
IMP_PEAK_PEN = 4  #: peak penetration of the episode (max of d_max)
IMP_PEAK_FORCE = 5  #: peak resultant contact force on A along -x
IMP_DURATION = 6  #: episode duration (until d_max falls back through 0)
IMP_CYCLE = 7  #: excitation cycle index k of the onset
IMP_Y = 8  #: global y of the contact point
N_IMP_FIELDS = 9

# ------------------------------------------------------------ run statistics
ST_ACCEPTED = 0
ST_REJECTED = 1
ST_RHS_EVALS = 2
ST_IMPACTS = 3
ST_EVENTS = 4
ST_STATUS = 5
N_STATS = 6

STATUS_OK = 0
STATUS_MAX_STEPS = 1  #: the step budget ran out
STATUS_OVERFLOW = 2  #: the impact table is full (caller enlarges and reruns)
STATUS_STEP_UNDERFLOW = 3  #: the step size fell below round-off (stiffness, NaN)
STATUS_NONFINITE = 4  #: the state became NaN or infinite

MAX_EVENTS = 4  #: per step: two ends, each with at most two crossings
N_SCALARS = 18 + MAX_EVENTS  #: length of the scalar workspace of a run
