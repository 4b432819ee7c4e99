"""The names a composition binds, as placeholders for the templates' linting.

Template modules (the model, glue, stepper, event and loop templates) are
ordinary Python text whose functions call names they do not define: the
contact law's ``law_*``, the ground motion's ``ground_*``, the model's
``model_*``, the method's ``step`` and its constants. They import those names
from here so that linters and readers can resolve them;
:mod:`chaospound.engine.compose` drops that import and binds the real ones in
the generated module of each composition. Calling a placeholder is a bug.
"""


def _unbound(*args):
    raise RuntimeError("a template function was called outside a composition")


# ---- composition constants (block offsets, sizes, switches fixed at generation)
LAW = 0  #: first slot of the contact law's block
LAW_DISSIPATIVE = False  #: the law's force depends on the penetration rate
LAW_MEMORY = False  #: the law keeps per-episode memory (written at every onset)
LAW_JUMPS = False  #: the law's force can jump at an onset or a release
LAW_SHIFTED = False  #: a point model's tangent run shifts the approach phase's vectors
LAW_DXI = 0  #: slot of the first tangent vector's memory sensitivity d xi (laws with memory)
GROUND = 0  #: first slot of the ground motion's block
GROUND_PERIODIC = True  #: the motion is periodic with the section interval (the sine)
GROUND_KINKS = False  #: the motion's acceleration has kinks at samples (a record)
GROUND_Y = False  #: the ground's y component drives the towers' Y (models with Y only)
N_BASE = 0  #: state dimension of the model (the tangent vectors follow it)
N_ENDS = 0  #: contact ends the events watch: 2 (line contact), 1 (point), 0 (none)
TANGENT = False  #: integrate tangent vectors after the state (QR at sections)
POINT_JUMPS = False  #: a tangent run maps a point contact's vectors by saltation (jumping laws)
POINT_SWITCH = False  #: a tangent run watches a point law's switch (jumping or shifted laws)
ADAPTIVE = True  #: the method has an error estimate and a controller
NEW_EVALS = 0  #: rhs evaluations per step, f_new included
DENSE_EVALS = 0  #: extra rhs evaluations to prepare the dense output
DENSE_ROWS = 0  #: rows of the dense-output coefficients
ERROR_ORDER = 0  #: order of the error estimator (initial step)
TAB_A = TAB_B = TAB_C = None  #: the tableau of a generic explicit method
USER_BASE = 0  #: where a user system's parameters start (its Jacobian scratch: the last n x n)

# ---- contact law
law_point_force = law_point_stiffness = law_point_force_rate = law_point_potential = _unbound
law_line_force = law_line_gradient = law_line_force_rate = law_line_potential = _unbound
law_on_onset = _unbound
law_onset_sensitivity = law_point_memory_force = law_line_memory_force = _unbound
law_on_sides = law_point_jump = law_point_switch = law_on_switch = _unbound
law_point_shift = law_shift_scale = _unbound
# ---- ground motion
ground_at = ground_anchor = ground_shifted = ground_at_anchor = ground_next_kink = _unbound
ground_acceleration = ground_at_y = _unbound
# ---- model
model_rhs = model_ends = model_rate = model_forces = model_force_rate = _unbound
model_potential = model_energy = model_trace = model_linearize = model_jvp = _unbound
model_contact_point = _unbound
model_memory_linearize = model_memory_jvp = model_onset_variation = model_onset_accel = _unbound
# ---- user system
user_rhs = user_jacobian = user_gap = _unbound
# ---- method
step = dense_prepare = controller = step_error = _unbound
# ---- defined by the engine templates, used by others
rhs = rhs_grounded = end_value = locate_root = locate_extremum = _unbound
onset_tangent = reset_tangent_memory = saltation_tangent = rhs_vectors = _unbound
shift_tangent = _unbound
