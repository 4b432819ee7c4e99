"""Cycle-by-cycle integration with located contact events (docs/model.md sections 8, 10).

Time is kept as (cycle index k, local time tau): ``t = t0 + k T + tau`` with
``t0`` the stroboscopic section's time origin and ``tau`` reset to exactly 0
at every section, so the forcing phase ``(t0 + tau) / r`` never accumulates
round-off, however long the run. Steps end exactly on every section.

Contact events are the sign changes of the end penetrations d_lo, d_hi
(:mod:`chaospound.kernels.events`). With ``restart`` on, a step that contains
one is redone so that it ends exactly on the earliest event (the force is
only once or twice differentiable there and an embedded error estimate does
not see the kink); the rest of the step is then integrated afresh.

Impacts (onsets of contact episodes, ``d_max = max(d_lo, d_hi)`` crossing 0
upwards) whose onset lies in the record window ``[t0 + k_record T,
t0 + k_end T)`` are recorded with their state; an episode still running at the
end of the window is followed to its release for its peak and duration.
"""

import numpy as np

from .events import FORCE_RATE, end_value, locate_extremum, locate_root
from .jit import driver, kernel
from .models import (
    base_model,
    contact_ends,
    contact_force_rate,
    contact_forces,
    penetration_rate,
    rhs,
)
from .params import (
    MODEL_DIMS,
    P_HALF_L,
    P_PERIOD,
    P_PHASE0,
    P_Y_C,
    P_Y_OFF,
    T_EX,
    T_L,
    T_W,
    TANGENT,
    TOWER_A,
    TOWER_B,
    TOWER_WALL,
    TOWERS,
)
from .powers import ground_phase
from .rk import (
    DENSE_EVALS,
    MAX_DENSE,
    MAX_STAGES,
    NEW_EVALS,
    RK4,
    carried_step,
    dense_eval,
    dense_prepare,
    initial_step,
    step_factor,
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

CORNER_FACE = 0
CORNER_A_PLUS = 1
CORNER_A_MINUS = 2
CORNER_B_PLUS = 3
CORNER_B_MINUS = 4
CORNER_LABELS = ("face", "A+", "A-", "B+", "B-")
FACE_TOL = 1e-9  #: |d_lo - d_hi| < FACE_TOL max(1, |d_max|): a "face" impact

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

GRAZE_MARGIN = 0.25  #: relative margin of the graze pre-test (see _may_cross)
GRAZE_FLOOR = 1e-6  #: absolute margin of the graze pre-test (units of A_g)
LAND_SLACK = 1e-8  #: a landing may miss its crossing by this much time, no more
LAND_ERR = 4.0  #: ... or by this many units of atol + rtol max(1, |y|) (see _landed_short)
FOLLOW_CYCLES = 5  #: cycles an episode running at the window's end is followed
MERGE_TOL = 1e-10  #: events closer than this in time are handled together
LAND_SHIFT_MAX = 1e-3  #: largest move of a landed event onto its crossing, in steps
MAX_EVENTS = 4  #: per step: two ends, each with at most two crossings


@driver
def run_cycles(model, method, p, y, clock, k_record, k_end, rtol, atol, h_fixed, max_steps,
               restart, n_samples, strobe, traj, imp, imp_state, stats, tangent_log):
    """Integrate from ``clock`` to the section ``k_end``, recording the window.

    Parameters
    ----------
    model, method : int
        Model id (params) and Runge-Kutta method id (rk).
    p : ndarray
        Packed parameters.
    y : ndarray (n,)
        State at the start; overwritten with the final state.
    clock : ndarray (3,)
        ``[k, tau, h]`` at the start (cycle index, local time, step size; h <= 0
        selects the initial step automatically); overwritten at the end.
    k_record, k_end : int
        Section indices bounding the record window.
    rtol, atol, h_fixed : float
        Tolerances (adaptive methods) and the fixed step (RK4).
    max_steps : int
        Budget of attempted steps.
    restart : bool
        End steps exactly at contact kinks.
    n_samples : int
        Dense trajectory samples per cycle in the record window (0: none);
        ``traj`` has shape (n_samples (k_end - k_record) + 1, n + 1), column 0
        holding the time.
    strobe : ndarray (k_end - k_record + 1, n)
        Stroboscopic states at the sections k_record .. k_end.
    imp, imp_state : ndarray
        Impact table (capacity, N_IMP_FIELDS) and states at onset (capacity, n);
        capacity 0 records no impacts.
    stats : ndarray of int64 (N_STATS,)
        Counters, see ST_*; ``stats[ST_STATUS]`` is the exit status.
    tangent_log : ndarray (k_end - k_record, k)
        Tangent models only (``model >= TANGENT``, ``y`` holding the state and k
        tangent vectors): at every section the vectors are re-orthonormalised
        (modified Gram-Schmidt, i.e. QR) and, for the cycles of the record
        window, ``log R_ii`` of the cycle just ended is stored here.

    Returns
    -------
    int
        Number of impacts recorded.
    """
    n = y.shape[0]
    vectors = np.empty((MAX_STAGES + MAX_DENSE + 5, n))
    scalars = np.empty(18 + MAX_EVENTS)
    ev_end = np.empty(MAX_EVENTS, dtype=np.int64)
    return _run_cycles(model, method, p, y, clock, k_record, k_end, rtol, atol, h_fixed,
                       max_steps, restart, n_samples, strobe, traj, imp, imp_state, stats,
                       tangent_log, vectors, scalars, ev_end)


@kernel
def _run_cycles(model, method, p, y, clock, k_record, k_end, rtol, atol, h_fixed, max_steps,
                restart, n_samples, strobe, traj, imp, imp_state, stats, tangent_log, vectors,
                scalars, ev_end):
    """:func:`run_cycles` on caller-allocated workspaces.

    Compiled without numba's reference-counting runtime (see
    :mod:`chaospound.kernels.jit`), so the step loop carries no reference
    counts on its arrays; only this thin wrapper allocates.
    """
    n = y.shape[0]
    base = base_model(model)
    n_base = MODEL_DIMS[base]
    n_vectors = n // n_base - 1 if model >= TANGENT else 0
    period = p[P_PERIOD]
    t0 = p[P_PHASE0]
    capacity = imp.shape[0]
    two_ends = base == TOWERS or base == TOWER_WALL

    # workspaces: views of the caller's blocks
    stage = vectors[:MAX_STAGES]
    dense = vectors[MAX_STAGES:MAX_STAGES + MAX_DENSE]
    rest = MAX_STAGES + MAX_DENSE
    f0 = vectors[rest]
    f_new = vectors[rest + 1]
    y_new = vectors[rest + 2]
    work = vectors[rest + 3]
    work2 = vectors[rest + 4]
    ends_old = scalars[0:4]
    ends_new = scalars[4:8]
    ends_tmp = scalars[8:12]
    forces = scalars[12:18]
    ev_theta = scalars[18:18 + MAX_EVENTS]

    k = int(clock[0])
    tau = clock[1]
    h = clock[2]
    for i in range(N_STATS):
        stats[i] = 0

    rhs(model, t0 + tau, y, p, f0)
    stats[ST_RHS_EVALS] += 1
    if method == RK4:
        h = h_fixed
    elif h <= 0.0:
        h = initial_step(method, model, t0 + tau, y, f0, p, rtol, atol, work, work2)
        if not (h > 0.0 and np.isfinite(h)):  # the heuristic overflows for atol ~ 1e-155
            h = 1e-6 * max(1.0, period)
        stats[ST_RHS_EVALS] += 1

    contact_ends(model, t0 + tau, y, p, ends_old)
    sin0, cos0 = ground_phase(t0 + tau, p)  # carried from step to step (carried_step)
    inside_lo = ends_old[0] > 0.0
    inside_hi = ends_old[1] > 0.0 if two_ends else inside_lo
    active = inside_lo or inside_hi
    episode = -1  # row of the impact whose episode is running, -1 if none recorded
    n_imp = 0
    n_traj = 0
    err_prev = 1e-4
    rejected_last = False
    short_end = -1  # end whose crossing the last accepted step landed short of
    short_next = -1
    record_done = k >= k_end
    at_section = tau == 0.0
    seg_end = 0.0 if tau < 0.0 else period
    status = STATUS_OK
    attempts = 0

    while True:
        if at_section:
            at_section = False
            if n_vectors > 0 and attempts > 0:
                _orthonormalize(y, n_base, n_vectors, tangent_log, k - 1 - k_record)
                rhs(model, t0, y, p, f0)
                stats[ST_RHS_EVALS] += 1
            if k_record <= k <= k_end:
                row = k - k_record
                for i in range(n):
                    strobe[row, i] = y[i]
                if n_samples > 0 and n_traj < traj.shape[0]:
                    _store_sample(traj, n_traj, t0 + k * period, y, n)
                    n_traj += 1
            if k >= k_end:
                record_done = True
            seg_end = period
        if record_done and (not active or k > k_end + FOLLOW_CYCLES):
            break  # an episode that never ends (towers resting on each other) is cut
        if attempts >= max_steps:
            status = STATUS_MAX_STEPS
            break
        attempts += 1

        # ---- attempt one step, truncated at the segment end
        h_prop = h
        h_try = h
        to_end = seg_end - tau
        reaches_end = False
        if h_try >= to_end or to_end - h_try < 1e-12 * max(1.0, period):
            h_try = to_end
            reaches_end = True
        t_here = t0 + tau
        err, sin1, cos1 = carried_step(method, model, t_here, h_try, y, f0, p, rtol, atol,
                                       stage, y_new, f_new, sin0, cos0)
        stats[ST_RHS_EVALS] += NEW_EVALS[method]
        if not np.isfinite(err) or not _all_finite(y_new, n):
            if method == RK4 or h_try < 1e-14 * max(1.0, period):
                status = STATUS_NONFINITE
                break
            stats[ST_REJECTED] += 1
            h = 0.25 * h_try
            rejected_last = True
            continue
        if method != RK4 and err > 1.0:
            stats[ST_REJECTED] += 1
            h = h_try * min(1.0, step_factor(method, err, err_prev))
            rejected_last = True
            if h < 1e-14 * max(1.0, period):
                status = STATUS_STEP_UNDERFLOW
                break
            continue

        # ---- events inside the accepted step
        contact_ends(model, t_here + h_try, y_new, p, ends_new)
        n_ev = 0
        dense_ready = False
        for end in range(2 if two_ends else 1):
            inside = inside_lo if end == 0 else inside_hi
            d_new = ends_new[end]
            rate_old = ends_old[end + 2]
            rate_new = ends_new[end + 2]
            crossing = (d_new > 0.0) != inside
            turning = (not inside and rate_old > 0.0 and rate_new < 0.0) or (
                inside and rate_old < 0.0 and rate_new > 0.0)
            if turning and not crossing:
                turning = _may_cross(ends_old[end], d_new, h_try * rate_old, h_try * rate_new)
            if not crossing and not turning:
                continue
            if not dense_ready:
                dense_prepare(method, model, t_here, h_try, y, f0, y_new, f_new, p, stage, dense)
                stats[ST_RHS_EVALS] += DENSE_EVALS[method]
                dense_ready = True
            # value at theta = 0: the true one when on the side of `inside`, else a
            # conventional one (an end landed on exactly, or just short of, 0)
            d_old = ends_old[end]
            if d_old == 0.0 or (d_old > 0.0) != inside:
                d_old = 1e-300 if inside else -1e-300
            if crossing:
                theta = locate_root(model, method, dense, y, t_here, h_try, p, end, 0.0,
                                    d_old, 1.0, d_new, h_try * rate_new, work, ends_tmp)
                ev_theta[n_ev] = theta
                ev_end[n_ev] = end
                n_ev += 1
            else:
                theta_m = locate_extremum(model, method, dense, y, t_here, h_try, p, end,
                                          rate_old, rate_new, work, ends_tmp)
                d_m = end_value(model, method, dense, y, t_here, h_try, theta_m, p, end,
                                work, ends_tmp)
                if (d_m > 0.0) != inside:  # two crossings inside the step
                    theta = locate_root(model, method, dense, y, t_here, h_try, p, end, 0.0,
                                        d_old, theta_m, d_m, 0.0, work, ends_tmp)
                    ev_theta[n_ev] = theta
                    ev_end[n_ev] = end
                    n_ev += 1
                    theta2 = locate_root(model, method, dense, y, t_here, h_try, p, end,
                                         theta_m, d_m, 1.0, -d_m, 0.0, work, ends_tmp)
                    ev_theta[n_ev] = theta2
                    ev_end[n_ev] = end
                    n_ev += 1

        truncated_to_event = False
        short_next = -1
        if n_ev > 0:
            _sort_events(ev_theta, ev_end, n_ev)
            stats[ST_EVENTS] += 1
            first = ev_theta[0]
            if (restart and first * h_try > MERGE_TOL and (1.0 - first) * h_try > MERGE_TOL
                    and ev_end[0] != short_end):
                # redo the step so that it ends on the earliest event (unless the last
                # step already landed short of this end's crossing: a poor interpolant,
                # e.g. a blown-up run, could make the landings creep forward forever)
                h_ev = first * h_try
                err2, sin1, cos1 = carried_step(method, model, t_here, h_ev, y, f0, p, rtol,
                                                atol, stage, y_new, f_new, sin0, cos0)
                stats[ST_RHS_EVALS] += NEW_EVALS[method]
                if not np.isfinite(err2) or (method != RK4 and err2 > 1.0):
                    stats[ST_REJECTED] += 1
                    h = h_ev
                    rejected_last = True
                    continue
                contact_ends(model, t_here + h_ev, y_new, p, ends_new)
                # keep the events that coincide with the first one, at theta = 1
                m = 0
                for i in range(n_ev):
                    if (ev_theta[i] - first) * h_try <= MERGE_TOL:
                        ev_theta[m] = 1.0
                        ev_end[m] = ev_end[i]
                        m += 1
                n_ev = m
                h_try = h_ev
                dense_ready = False
                truncated_to_event = True
                reaches_end = False

        # ---- accept
        sampling = n_samples > 0 and (not record_done) and k >= k_record and tau >= 0.0
        if sampling and not dense_ready:
            dense_prepare(method, model, t_here, h_try, y, f0, y_new, f_new, p, stage, dense)
            stats[ST_RHS_EVALS] += DENSE_EVALS[method]
            dense_ready = True
        if sampling:
            n_traj = _store_samples(method, dense, y, t0, k, period, tau, h_try, n_samples,
                                    traj, n_traj, work, n)

        # process the events in time order (interpolated states when not landed)
        peak_row = episode  # the episode running during this step, if recorded
        for i in range(n_ev):
            theta = ev_theta[i]
            end = ev_end[i]
            if theta >= 1.0:
                if _landed_short(ends_new, end, inside_lo if end == 0 else inside_hi, y_new,
                                 n_base, rtol, atol):
                    short_next = end
                    continue  # the landed state is still clearly before the crossing
                # the landed state misses the surface by about the local error: the
                # event's time and state are moved onto it to first order
                shift = _crossing_shift(ends_new[end], ends_new[end + 2], h_try)
                t_ev = t_here + h_try + shift
                for j in range(n):
                    work[j] = y_new[j] + shift * f_new[j]
            else:
                t_ev = t_here + theta * h_try
                end_value(model, method, dense, y, t_here, h_try, theta, p, 0, work, ends_tmp)
            if end == 0:
                inside_lo = not inside_lo
                if not two_ends:
                    inside_hi = inside_lo
            else:
                inside_hi = not inside_hi
            now_active = inside_lo or inside_hi
            if now_active and not active:
                # onset of an episode
                if not record_done and k >= k_record and capacity > 0:
                    if n_imp >= capacity:
                        status = STATUS_OVERFLOW
                        break
                    _record_onset(model, p, t_ev, k, period, t0, work, imp, imp_state, n_imp, n,
                                  ends_tmp)
                    episode = n_imp
                    if peak_row < 0:
                        peak_row = n_imp  # began inside this step (not landed on)
                    n_imp += 1
                else:
                    episode = -1
            elif active and not now_active:
                if episode >= 0:
                    duration = t_ev + k * period - imp[episode, IMP_TIME]
                    if duration <= 0.0 and episode == n_imp - 1:
                        # onset and release at one instant: a touch at round-off level
                        # (rattling at the integrator's noise floor), no contact, no impact
                        n_imp -= 1
                        if peak_row == episode:
                            peak_row = -1
                    else:
                        imp[episode, IMP_DURATION] = duration
                episode = -1
            active = now_active
        if status != STATUS_OK:
            break

        # peak penetration and force of the episode that ran during this step
        if peak_row >= 0:
            if not dense_ready:
                dense_prepare(method, model, t_here, h_try, y, f0, y_new, f_new, p, stage, dense)
                stats[ST_RHS_EVALS] += DENSE_EVALS[method]
                dense_ready = True
            _update_peak(model, method, dense, y, y_new, t_here, h_try, p, ends_old, ends_new,
                         imp, peak_row, work, ends_tmp, forces, two_ends)

        stats[ST_ACCEPTED] += 1
        tau += h_try
        sin0 = sin1  # the ground's phase at the new step start
        cos0 = cos1
        for i in range(n):
            y[i] = y_new[i]
            f0[i] = f_new[i]
        for i in range(4):
            ends_old[i] = ends_new[i]

        # ---- next step size
        if method == RK4:
            h = h_fixed
        else:
            fac = step_factor(method, err, err_prev)
            if rejected_last:
                fac = min(fac, 1.0)
            err_prev = max(err, 1e-4)
            h_next = h_prop * fac
            if not truncated_to_event and h_try < h_prop:
                h_next = max(h_try * fac, h_prop)
            h = h_next
        rejected_last = False
        short_end = short_next

        # ---- section reached
        if reaches_end:
            if seg_end == period:
                k += 1
            tau = 0.0
            at_section = True
            sin0, cos0 = ground_phase(t0, p)
            rhs(model, t0, y, p, f0)
            stats[ST_RHS_EVALS] += 1
            contact_ends(model, t0, y, p, ends_old)

    clock[0] = k
    clock[1] = tau
    clock[2] = h
    stats[ST_IMPACTS] = n_imp
    stats[ST_STATUS] = status
    return n_imp


@kernel
def _may_cross(d0, d1, slope0, slope1):
    """Whether an extremum of d inside a step can reach the other side of 0.

    ``slope0`` and ``slope1`` are ``h d'`` at the step ends. For a parabola the
    two end tangents meet exactly at the extremum's value; the departure of d
    from a parabola over one step is O(h^3) times its third derivative and is
    covered by a margin of GRAZE_MARGIN times the spread of the slopes (plus a
    floor), so only an
    excursion that stays clearly on one side of 0 skips the dense-output search.
    """
    spread = abs(slope0) + abs(slope1)
    if spread == 0.0:
        return False
    theta = (d1 - slope1 - d0) / (slope0 - slope1)
    extreme = d0 + slope0 * theta
    margin = GRAZE_MARGIN * spread + GRAZE_FLOOR
    if d0 < 0.0:  # outside: a maximum, can it reach d > 0?
        return extreme > -margin
    return extreme < margin  # inside: a minimum, can it reach d < 0?


@kernel
def _orthonormalize(y, n_base, n_vectors, log_out, row):
    """Modified Gram-Schmidt on the tangent vectors stored after the state.

    Stores ``log R_ii`` (the log of each vector's norm after removing its
    projections on the previous ones) in ``log_out[row]`` when ``row`` is a
    valid row, and replaces the vectors by the orthonormal basis.
    """
    store = 0 <= row < log_out.shape[0]
    for i in range(n_vectors):
        a = n_base * (i + 1)
        for j in range(i):
            b = n_base * (j + 1)
            dot = 0.0
            for c in range(n_base):
                dot += y[a + c] * y[b + c]
            for c in range(n_base):
                y[a + c] -= dot * y[b + c]
        norm = 0.0
        for c in range(n_base):
            norm += y[a + c] * y[a + c]
        norm = np.sqrt(norm)
        if store:
            log_out[row, i] = np.log(norm)
        for c in range(n_base):
            y[a + c] /= norm


@kernel
def _landed_short(ends, end, inside, y, n_base, rtol, atol):
    """Whether a step landed on a located crossing actually stopped before it.

    The root was located on the long step's interpolant and the step redone to
    end there, so the landed state misses the surface by about the local
    error (up to ~2.4 units of ``atol + rtol S``, ``S = max(1, |y|)``, measured
    at rtol 1e-6). Within LAND_ERR such units, or LAND_SLACK in time, of the
    surface, and moving towards it, the crossing counts: the force is
    ``max(d, 0)^chi`` whatever the flag says, so only the bookkeeping changes.
    Further away, or moving away from 0, it has not happened yet and the next
    step will find it (a re-detection costs a root search and a tiny step).
    """
    d = ends[end]
    rate = ends[end + 2]
    if d == 0.0 or (d > 0.0) != inside:
        return False
    towards = rate < 0.0 if inside else rate > 0.0
    size = 1.0
    for i in range(n_base):
        size = max(size, abs(y[i]))
    slack = max(abs(rate) * LAND_SLACK, LAND_ERR * (atol + rtol * size))
    return not towards or abs(d) > slack


@kernel
def _crossing_shift(d, rate, h):
    """Time from a landed state to its end's crossing, ``-d / d'`` (first order).

    A landing ends on the root of the long step's interpolant, which misses the
    true crossing by about the local error (a few ``atol + rtol |y|`` in d); the
    event is recorded at ``t + shift`` with the state ``y + shift y'``, which
    leaves an O(shift^2) error. 0 when the shift would not be small against the
    step (a rate near 0: a graze, whose root the linearisation cannot find).
    """
    if d == 0.0 or rate == 0.0:
        return 0.0
    shift = -d / rate
    if abs(shift) > LAND_SHIFT_MAX * h:
        return 0.0
    return shift


@kernel
def _all_finite(v, n):
    for i in range(n):
        if not np.isfinite(v[i]):
            return False
    return True


@kernel
def _sort_events(theta, end, n_ev):
    """Insertion sort of the (few) events of a step by theta."""
    for i in range(1, n_ev):
        th = theta[i]
        en = end[i]
        j = i - 1
        while j >= 0 and theta[j] > th:
            theta[j + 1] = theta[j]
            end[j + 1] = end[j]
            j -= 1
        theta[j + 1] = th
        end[j + 1] = en


@kernel
def _record_onset(model, p, t_force, k, period, t0, state, imp, imp_state, row, n, ends):
    """Fill one impact row at onset: time, phase, velocity, corner, state."""
    contact_ends(model, t_force, state, p, ends)
    d_lo = ends[0]
    d_hi = ends[1]
    d_max = max(d_lo, d_hi)
    if model == TOWERS or model == TOWER_WALL:
        y_c = p[P_Y_C]
        half = p[P_HALF_L]
        if abs(d_lo - d_hi) < FACE_TOL * max(1.0, abs(d_max)):
            corner = CORNER_FACE
            y_at = y_c
        elif d_hi > d_lo:
            y_at = y_c + half
            corner = _corner_label(model, p, state, True)
        else:
            y_at = y_c - half
            corner = _corner_label(model, p, state, False)
        velocity = penetration_rate(model, t_force, state, p, y_at)
    else:
        corner = CORNER_FACE
        y_at = 0.0
        velocity = ends[2]
    x = t_force / period
    if x >= 1.0:
        x -= 1.0
    imp[row, IMP_TIME] = t_force + k * period
    imp[row, IMP_PHASE] = x
    imp[row, IMP_VELOCITY] = velocity
    imp[row, IMP_CORNER] = corner
    imp[row, IMP_PEAK_PEN] = max(d_max, 0.0)
    imp[row, IMP_PEAK_FORCE] = 0.0
    imp[row, IMP_DURATION] = np.nan
    imp[row, IMP_CYCLE] = k
    imp[row, IMP_Y] = y_at
    for i in range(n):
        imp_state[row, i] = state[i]


@kernel
def _corner_label(model, p, s, plus_end):
    """Whose corner is the inner one at the + (y_hi) or - (y_lo) end (docs/model.md 8)."""
    if model == TOWER_WALL:
        return CORNER_A_PLUS if plus_end else CORNER_A_MINUS
    a = TOWER_A
    b = TOWER_B
    sign = 1.0 if plus_end else -1.0
    h_a = s[2] + sign * 0.5 * p[a + T_L] + s[4] * (0.5 * p[a + T_W] - p[a + T_EX])
    h_b = s[8] + p[P_Y_OFF] + sign * 0.5 * p[b + T_L] - s[10] * (0.5 * p[b + T_W] + p[b + T_EX])
    if plus_end:
        return CORNER_A_PLUS if h_a <= h_b else CORNER_B_PLUS
    return CORNER_A_MINUS if h_a >= h_b else CORNER_B_MINUS


@kernel
def _update_peak(model, method, dense, y, y_new, t, h, p, ends_old, ends_new, imp, row, work,
                 ends_tmp, forces, two_ends):
    """Raise an episode's peak penetration and peak force with this step's maxima.

    Candidates: the step's end, the interior maxima of each end penetration
    (where its rate turns from + to -) and, for the line contact, the interior
    maximum of the force itself (where its analytic rate turns), all located on
    the step's dense output. A graze shorter than one step is covered: its
    maximum lies inside the step between the landed onset and release.
    """
    pen = max(ends_new[0], ends_new[1])
    if pen > imp[row, IMP_PEAK_PEN]:
        imp[row, IMP_PEAK_PEN] = pen
    force = contact_forces(model, t + h, y_new, p, forces)
    if force > imp[row, IMP_PEAK_FORCE]:
        imp[row, IMP_PEAK_FORCE] = force
    for end in range(2 if two_ends else 1):
        if ends_old[end + 2] > 0.0 and ends_new[end + 2] < 0.0:
            theta = locate_extremum(model, method, dense, y, t, h, p, end, ends_old[end + 2],
                                    ends_new[end + 2], work, ends_tmp)
            d_m = end_value(model, method, dense, y, t, h, theta, p, end, work, ends_tmp)
            if d_m > imp[row, IMP_PEAK_PEN]:
                imp[row, IMP_PEAK_PEN] = d_m
            f_m = contact_forces(model, t + theta * h, work, p, forces)
            if f_m > imp[row, IMP_PEAK_FORCE]:
                imp[row, IMP_PEAK_FORCE] = f_m
    if two_ends:
        rate_old = contact_force_rate(model, t, y, p, ends_old)
        rate_new = contact_force_rate(model, t + h, y_new, p, ends_new)
        if rate_old > 0.0 and rate_new < 0.0:
            theta = locate_root(model, method, dense, y, t, h, p, FORCE_RATE, 0.0, rate_old,
                                1.0, rate_new, 0.0, work, ends_tmp)
            end_value(model, method, dense, y, t, h, theta, p, 0, work, ends_tmp)
            f_m = contact_forces(model, t + theta * h, work, p, forces)
            if f_m > imp[row, IMP_PEAK_FORCE]:
                imp[row, IMP_PEAK_FORCE] = f_m


@kernel
def _store_sample(traj, row, t, state, n):
    traj[row, 0] = t
    for i in range(n):
        traj[row, i + 1] = state[i]


@kernel
def _store_samples(method, dense, y, t0, k, period, tau, h, n_samples, traj, n_traj, work, n):
    """Interpolated samples on the grid tau = j T / n_samples, 0 < j < n_samples, in (tau, tau + h].

    The sample at tau = 0 is the section state, stored at the section.
    """
    dt = period / n_samples
    j = int(np.floor(tau / dt)) + 1
    while j < n_samples and j * dt <= tau + h and n_traj < traj.shape[0]:
        theta = min((j * dt - tau) / h, 1.0)
        dense_eval(method, dense, y, h, theta, work)
        _store_sample(traj, n_traj, t0 + k * period + j * dt, work, n)
        n_traj += 1
        j += 1
    return n_traj
