"""Cycle-by-cycle integration with located contact events (docs/model.md sections 8, 10).

A template (:mod:`.compose`): the loop of every composition. Time is kept as
(cycle index k, local time tau): ``t = t0 + k T + tau`` with ``t0`` the
stroboscopic section's time origin and ``tau`` reset to exactly 0 at every
section, so the forcing phase never accumulates round-off, however long the
run. Steps end exactly on every section. For a ground motion that is not
periodic (a record) the kernels see absolute time: the local ``t0`` advances
by T at every section, and steps also land on the motion's samples
(``GROUND_KINKS``), where its acceleration has kinks.

Contact events are the sign changes of the end penetrations d_lo, d_hi
(:mod:`.events`). With ``restart`` on, a step that contains one is redone so
that it ends exactly on the earliest event (the force is only once or twice
differentiable there and an embedded error estimate does not see the kink);
the rest of the step is then integrated afresh.

Impacts (onsets of contact episodes, ``d_max = max(d_lo, d_hi)`` crossing 0
upwards) whose onset lies in the record window ``[t0 + k_record T,
t0 + k_end T)`` are recorded with their state; an episode still running at the
end of the window is followed to its release for its peak and duration.
"""

import numpy as np

from chaospound.engine.bookkeeping import (
    all_finite,
    crossing_shift,
    landed_short,
    may_cross,
    orthonormalize,
    orthonormalize_memory,
    sort_events,
    store_propagator,
    store_propagator_memory,
    store_sample,
)
from chaospound.engine.events import EXTREMUM_TOL, FORCE_RATE, SWITCH
from chaospound.engine.tables import (
    IMP_CORNER,
    IMP_CYCLE,
    IMP_DURATION,
    IMP_PEAK_FORCE,
    IMP_PEAK_PEN,
    IMP_PHASE,
    IMP_TIME,
    IMP_VELOCITY,
    IMP_Y,
    MAX_EVENTS,
    N_STATS,
    ST_ACCEPTED,
    ST_EVENTS,
    ST_IMPACTS,
    ST_REJECTED,
    ST_RHS_EVALS,
    ST_STATUS,
    STATUS_MAX_STEPS,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_OVERFLOW,
    STATUS_STEP_UNDERFLOW,
)
from chaospound.kernels.free import (
    ADAPTIVE,
    DENSE_EVALS,
    DENSE_ROWS,
    GROUND,
    GROUND_KINKS,
    GROUND_PERIODIC,
    LAW,
    LAW_DISSIPATIVE,
    LAW_DXI,
    LAW_JUMPS,
    LAW_MEMORY,
    LAW_SHIFTED,
    N_BASE,
    N_ENDS,
    NEW_EVALS,
    POINT_JUMPS,
    POINT_SWITCH,
    TANGENT,
    controller,
    dense_prepare,
    end_value,
    ground_anchor,
    ground_next_kink,
    initial_step,
    law_on_onset,
    law_on_sides,
    law_on_switch,
    law_point_switch,
    locate_extremum,
    locate_root,
    model_contact_point,
    model_ends,
    model_force_rate,
    model_forces,
    onset_tangent,
    reset_tangent_memory,
    rhs,
    rhs_vectors,
    saltation_tangent,
    shift_tangent,
    step,
)
from chaospound.kernels.jit import kernel
from chaospound.kernels.params import P_PERIOD, P_PHASE0
from chaospound.solvers.dense import dense_eval
from chaospound.solvers.tableaux import MAX_DENSE, MAX_STAGES

FOLLOW_CYCLES = 5  #: cycles an episode running at the window's end is followed
SWITCH_END = 2  #: the event list's "end" of a point contact's switch surface (events.SWITCH)
MERGE_TOL = 1e-10  #: events closer than this in time are handled together
#: a ground sample closer than this (relative to max(1, |t|)) counts as reached: a
#: step that landed on it a rounding error short does not take a second, tiny step
KINK_SLACK = 1e-12

# ==== template ====


@kernel
def run(p, y, clock, k_record, k_end, rtol, atol, h_fixed, max_steps, restart, n_samples, strobe,
        traj, imp, imp_state, stats, tangent_log, propagate, vectors, scalars, ev_end):
    """Integrate from ``clock`` to the section ``k_end``, recording the window.

    Parameters
    ----------
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
        Tolerances (adaptive methods) and the fixed step (fixed-step methods).
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
    tangent_log : ndarray
        Tangent compositions only (``y`` holding the state and k tangent
        vectors), at every section: "qr", shape (k_end - k_record, k), the
        vectors are re-orthonormalised (modified Gram-Schmidt, i.e. QR) and, for
        the cycles of the record window, ``log R_ii`` of the cycle just ended is
        stored here; "propagator", shape (k_end - k_record, k n), the vectors of
        the cycle just ended are stored here and reset to the unit vectors.
    propagate : bool
        With tangent vectors: record "propagator" (True) or "qr" (False) at the
        sections. The two integrate the same tangent vectors and differ only in
        this record; one compiled engine runs both, and states without vectors.
    vectors, scalars, ev_end : ndarray
        Workspaces: (MAX_STAGES + MAX_DENSE + 5, n), (N_SCALARS,) and
        (MAX_EVENTS,) int64. Compiled without numba's reference-counting
        runtime, the loop allocates nothing.

    Returns
    -------
    int
        Number of impacts recorded.
    """
    n = y.shape[0]
    n_base = N_BASE
    n_vectors = n // n_base - 1 if TANGENT else 0
    # a tangent engine also runs states without vectors (Composition.compiled): its
    # point contact's switches and shifts act on the vectors only
    shifted = LAW_SHIFTED and n_vectors > 0
    point_jumps = POINT_JUMPS and n_vectors > 0
    point_switch = POINT_SWITCH and n_vectors > 0
    period = p[P_PERIOD]
    t0 = p[P_PHASE0]
    capacity = imp.shape[0]
    two_ends = N_ENDS == 2

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
    if not GROUND_PERIODIC:
        t0 += k * period  # absolute time: t = t0 + tau
    h = clock[2]
    for i in range(N_STATS):
        stats[i] = 0
    if LAW_MEMORY and n_vectors > 0:
        reset_tangent_memory(p, n_vectors)  # the tangent starts at the packed memory

    clipped = False  # a point contact's no-pull force is clipped (tangent runs)
    if shifted:
        # Jankowski's point contact: the approach phase's tangent vectors are shifted
        # (clipped: separating or out of contact, no shift), decided before the first
        # derivative, which depends on it (docs/contact_laws.md section 7)
        model_ends(t0 + tau, y, p, ends_old)
        clipped = not ends_old[0] > 0.0 or law_point_switch(p, LAW, ends_old[0],
                                                            ends_old[2]) < 0.0
        law_on_switch(p, LAW, clipped)
        if not clipped and n_vectors > 0 and tau != 0.0:  # (at a section: shifted there)
            shift_tangent(p, ends_old[0], False, y, n_base, n_vectors, work2)
    rhs(t0 + tau, y, p, f0)
    stats[ST_RHS_EVALS] += 1
    if not ADAPTIVE:
        h = h_fixed
    elif h <= 0.0:
        h = initial_step(t0 + tau, y, f0, p, rtol, atol, work, work2)
        if not (h > 0.0 and np.isfinite(h)):  # the heuristic overflows for atol ~ 1e-155
            h = 1e-6 * max(1.0, period)
        stats[ST_RHS_EVALS] += 1

    model_ends(t0 + tau, y, p, ends_old)
    c0, c1 = ground_anchor(t0 + tau, p, GROUND)  # carried from step to step (step)
    inside_lo = ends_old[0] > 0.0
    inside_hi = ends_old[1] > 0.0 if two_ends else inside_lo
    active = inside_lo or inside_hi
    if LAW_JUMPS:  # the law's Jacobian follows the event flags (docs/contact_laws.md 7)
        law_on_sides(p, LAW, inside_lo, inside_hi)
    if point_jumps:
        clipped = inside_lo and law_point_switch(p, LAW, ends_old[0], ends_old[2]) < 0.0
        law_on_switch(p, LAW, clipped)
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
            if shifted and not clipped and attempts > 0:
                # the vectors are read and reset as themselves, not in the shifted form
                model_ends(t0, y, p, ends_tmp)
                shift_tangent(p, ends_tmp[0], True, y, n_base, n_vectors, work2)
            if n_vectors > 0 and attempts > 0:
                log_row = k - 1 - k_record
                if LAW_MEMORY:  # the vectors' memory sensitivities follow them
                    if propagate:
                        store_propagator_memory(y, p, LAW_DXI, n_base, n_vectors,
                                                tangent_log, log_row)
                    else:
                        orthonormalize_memory(y, p, LAW_DXI, n_base, n_vectors, tangent_log,
                                              log_row)
                elif propagate:
                    store_propagator(y, n_base, n_vectors, tangent_log, log_row)
                else:
                    orthonormalize(y, n_base, n_vectors, tangent_log, log_row)
                rhs(t0, y, p, f0)
                stats[ST_RHS_EVALS] += 1
            if k_record <= k <= k_end:
                row = k - k_record
                for i in range(n):
                    strobe[row, i] = y[i]
                if n_samples > 0 and n_traj < traj.shape[0]:
                    store_sample(traj, n_traj, t0 + k * period if GROUND_PERIODIC else t0, y, n)
                    n_traj += 1
            if k >= k_end:
                record_done = True
            seg_end = period
            if shifted and not clipped:  # back to the shifted form
                model_ends(t0, y, p, ends_tmp)
                shift_tangent(p, ends_tmp[0], False, y, n_base, n_vectors, work2)
                rhs(t0, y, p, f0)
                stats[ST_RHS_EVALS] += 1
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
        if GROUND_KINKS:  # land on the motion's samples, where u_g'' has kinks
            t_abs = t0 + tau
            to_kink = ground_next_kink(t_abs + KINK_SLACK * max(1.0, abs(t_abs)), p,
                                       GROUND) - t_abs
            if to_kink < to_end and h_try >= to_kink:
                h_try = to_kink
                reaches_end = False
        t_here = t0 + tau
        err, c0_new, c1_new = step(t_here, h_try, y, f0, p, rtol, atol, stage, y_new, f_new,
                                   c0, c1)
        stats[ST_RHS_EVALS] += NEW_EVALS
        if not np.isfinite(err) or not all_finite(y_new, n):
            if not ADAPTIVE or h_try < 1e-14 * max(1.0, period):
                status = STATUS_NONFINITE
                break
            stats[ST_REJECTED] += 1
            h = 0.25 * h_try
            rejected_last = True
            continue
        if ADAPTIVE and err > 1.0:
            stats[ST_REJECTED] += 1
            rejected_last = True
            h = h_try * min(1.0, controller(err, err_prev))
            if h < 1e-14 * max(1.0, period):
                status = STATUS_STEP_UNDERFLOW
                break
            continue

        # ---- events inside the accepted step
        model_ends(t_here + h_try, y_new, p, ends_new)
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
                turning = may_cross(ends_old[end], d_new, h_try * rate_old, h_try * rate_new)
            if not crossing and not turning:
                continue
            if not dense_ready:
                dense_prepare(t_here, h_try, y, f0, y_new, f_new, p, stage, dense)
                stats[ST_RHS_EVALS] += DENSE_EVALS
                dense_ready = True
            # value at theta = 0: the true one when on the side of `inside`, else a
            # conventional one (an end landed on exactly, or just short of, 0)
            d_old = ends_old[end]
            if d_old == 0.0 or (d_old > 0.0) != inside:
                d_old = 1e-300 if inside else -1e-300
            if crossing:
                theta = locate_root(dense, y, t_here, h_try, p, end, 0.0,
                                    d_old, 1.0, d_new, h_try * rate_new, work, ends_tmp)
                ev_theta[n_ev] = theta
                ev_end[n_ev] = end
                n_ev += 1
            else:
                theta_m = locate_extremum(dense, y, t_here, h_try, p, end,
                                          rate_old, rate_new, work, ends_tmp)
                d_m = end_value(dense, y, t_here, h_try, theta_m, p, end,
                                work, ends_tmp)
                if (d_m > 0.0) != inside:  # two crossings inside the step
                    theta = locate_root(dense, y, t_here, h_try, p, end, 0.0,
                                        d_old, theta_m, d_m, 0.0, work, ends_tmp)
                    ev_theta[n_ev] = theta
                    ev_end[n_ev] = end
                    n_ev += 1
                    theta2 = locate_root(dense, y, t_here, h_try, p, end,
                                         theta_m, d_m, 1.0, -d_m, 0.0, work, ends_tmp)
                    ev_theta[n_ev] = theta2
                    ev_end[n_ev] = end
                    n_ev += 1
        if point_switch and inside_lo:
            # in contact, the no-pull switch k d + c d' = 0 of a point contact (Jankowski:
            # d' = 0): the force is continuous there but its Jacobian jumps, which an
            # un-located step would integrate to first order only
            g_new = law_point_switch(p, LAW, ends_new[0], ends_new[2])
            if (g_new < 0.0) != clipped:
                if not dense_ready:
                    dense_prepare(t_here, h_try, y, f0, y_new, f_new, p, stage, dense)
                    stats[ST_RHS_EVALS] += DENSE_EVALS
                    dense_ready = True
                g_old = law_point_switch(p, LAW, ends_old[0], ends_old[2])
                if g_old == 0.0 or (g_old < 0.0) != clipped:
                    g_old = -1e-300 if clipped else 1e-300
                ev_theta[n_ev] = locate_root(dense, y, t_here, h_try, p, SWITCH, 0.0, g_old,
                                             1.0, g_new, 0.0, work, ends_tmp)
                ev_end[n_ev] = SWITCH_END
                n_ev += 1

        truncated_to_event = False
        short_next = -1
        if n_ev > 0:
            sort_events(ev_theta, ev_end, n_ev)
            stats[ST_EVENTS] += 1
            first = ev_theta[0]
            if (restart and first * h_try > MERGE_TOL and (1.0 - first) * h_try > MERGE_TOL
                    and ev_end[0] != short_end):
                # redo the step so that it ends on the earliest event (unless the last
                # step already landed short of this end's crossing: a poor interpolant,
                # e.g. a blown-up run, could make the landings creep forward forever)
                h_ev = first * h_try
                err2, c0_new, c1_new = step(t_here, h_ev, y, f0, p, rtol, atol, stage, y_new,
                                            f_new, c0, c1)
                stats[ST_RHS_EVALS] += NEW_EVALS
                if not np.isfinite(err2) or (ADAPTIVE and err2 > 1.0):
                    stats[ST_REJECTED] += 1
                    h = h_ev
                    rejected_last = True
                    continue
                model_ends(t_here + h_ev, y_new, p, ends_new)
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
            dense_prepare(t_here, h_try, y, f0, y_new, f_new, p, stage, dense)
            stats[ST_RHS_EVALS] += DENSE_EVALS
            dense_ready = True
        if sampling:
            n_traj = store_samples(dense, y, t0, k, period, tau, h_try, n_samples,
                                    traj, n_traj, work, n)

        # process the events in time order (interpolated states when not landed)
        peak_row = episode  # the episode running during this step, if recorded
        salted = False  # a point event changed y_new's vectors or their Jacobian's side
        for i in range(n_ev):
            theta = ev_theta[i]
            end = ev_end[i]
            if shifted and end == SWITCH_END:
                if inside_lo:  # (no switch after a release earlier in the step)
                    # Jankowski's d' = 0: the vectors change form (shifted while
                    # approaching) and the Jacobian its phase
                    clipped = not clipped
                    law_on_switch(p, LAW, clipped)
                    if theta < 1.0 and not salted:  # converted at the switch, carried
                        carry_shift(dense, y, t_here, h_try, theta, t_here + theta * h_try,
                                    p, True, clipped, y_new, n_base, n_vectors, work, work2)
                    else:  # landed (or a second event in the step): at the step's end
                        model_ends(t_here + h_try, y_new, p, ends_tmp)
                        shift_tangent(p, ends_tmp[0], clipped, y_new, n_base, n_vectors,
                                      work2)
                    salted = True
                continue
            if point_jumps and end == SWITCH_END:
                if inside_lo:  # (no switch after a release earlier in the step)
                    clipped = not clipped
                    law_on_switch(p, LAW, clipped)
                    if theta < 1.0 and not salted:  # the new Jacobian over the rest
                        carry_saltation(dense, y, t_here, h_try, theta, t_here + theta * h_try,
                                        p, 0.0, False, False, y_new, n_base, n_vectors, work,
                                        work2)
                    salted = True
                continue
            if theta >= 1.0:
                if landed_short(ends_new, end, inside_lo if end == 0 else inside_hi, y_new,
                                 n_base, rtol, atol):
                    short_next = end
                    continue  # the landed state is still clearly before the crossing
                # the landed state misses the surface by about the local error: the
                # event's time and state are moved onto it to first order
                shift = crossing_shift(ends_new[end], ends_new[end + 2], h_try)
                t_ev = t_here + h_try + shift
                for j in range(n):
                    work[j] = y_new[j] + shift * f_new[j]
            else:
                t_ev = t_here + theta * h_try
                end_value(dense, y, t_here, h_try, theta, p, 0, work, ends_tmp)
                if LAW_MEMORY and n_vectors > 0:  # the onset's tangent vectors too
                    dense_eval(DENSE_ROWS, dense, y, h_try, theta, work)
            if end == 0:
                inside_lo = not inside_lo
                if not two_ends:
                    inside_hi = inside_lo
            else:
                inside_hi = not inside_hi
            if LAW_JUMPS:
                law_on_sides(p, LAW, inside_lo, inside_hi)
            if shifted and clipped != (not inside_lo):
                # an onset starts an approach (d' >= 0), a release ends the contact: the
                # vectors keep their form (the shift is the identity at d = 0), the
                # Jacobian changes phase
                clipped = not inside_lo
                law_on_switch(p, LAW, clipped)
                if n_vectors > 0:
                    if theta < 1.0 and not salted:
                        carry_shift(dense, y, t_here, h_try, theta, t_ev, p, False, clipped,
                                    y_new, n_base, n_vectors, work, work2)
                    salted = True
            if point_jumps:
                # the point force jumps here: the saltation matrix maps the tangent
                # vectors (docs/contact_laws.md section 7)
                clipped = False  # from an onset (k d + c d' = c d' > 0), or out of contact
                law_on_switch(p, LAW, False)
                model_ends(t_ev, work, p, ends_tmp)
                if theta >= 1.0 or salted:
                    # landed: the vectors at the step's end are those at the event (a
                    # second event inside one step: mapped at the end, first order in
                    # the rest of the step)
                    saltation_tangent(p, ends_tmp[2], inside_lo, y_new, n_base, n_vectors,
                                      work2)
                else:
                    # inside the step (the state's error control makes a step across
                    # the force's jump tiny, so most are): the vectors interpolated at
                    # the event, mapped, and carried to the step's end with the new
                    # side's Jacobian (the step used the old side's throughout)
                    carry_saltation(dense, y, t_here, h_try, theta, t_ev, p, ends_tmp[2],
                                    inside_lo, True, y_new, n_base, n_vectors, work, work2)
                salted = True
            now_active = inside_lo or inside_hi
            if now_active and not active and LAW_MEMORY:
                # the law's per-episode memory (v0), at every onset, recorded or not
                model_ends(t_ev, work, p, ends_tmp)
                _, y_onset, v_onset = model_contact_point(t_ev, work, p, ends_tmp)
                law_on_onset(p, LAW, v_onset)
                if n_vectors > 0:  # d xi of each tangent vector (engine/memory.py)
                    onset_tangent(t_ev, work, p, y_onset, v_onset, n_base, n_vectors, work2)
            if now_active and not active:
                # onset of an episode
                if not record_done and k >= k_record and capacity > 0:
                    if n_imp >= capacity:
                        status = STATUS_OVERFLOW
                        break
                    record_onset(p, t_ev, k, period, t0, work, imp, imp_state, n_imp, n,
                                  ends_tmp)
                    episode = n_imp
                    if peak_row < 0:
                        peak_row = n_imp  # began inside this step (not landed on)
                    n_imp += 1
                else:
                    episode = -1
            elif active and not now_active:
                if episode >= 0:
                    duration = (t_ev + k * period if GROUND_PERIODIC else t_ev) - imp[
                        episode, IMP_TIME]
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
        if point_switch and salted:
            # the step's last derivative is the next step's first stage: the vectors'
            # part again, from the mapped vectors with the Jacobian of the new side
            rhs_vectors(t_here + h_try, y_new, p, f_new)

        # peak penetration and force of the episode that ran during this step
        if peak_row >= 0:
            if not dense_ready:
                dense_prepare(t_here, h_try, y, f0, y_new, f_new, p, stage, dense)
                stats[ST_RHS_EVALS] += DENSE_EVALS
                dense_ready = True
            update_peak(dense, y, y_new, t_here, h_try, p, ends_old, ends_new,
                         imp, peak_row, work, ends_tmp, forces, two_ends)

        stats[ST_ACCEPTED] += 1
        tau += h_try
        c0 = c0_new  # the ground's carried state at the new step start
        c1 = c1_new
        for i in range(n):
            y[i] = y_new[i]
            f0[i] = f_new[i]
        for i in range(4):
            ends_old[i] = ends_new[i]

        # ---- next step size
        if not ADAPTIVE:
            h = h_fixed
        else:
            fac = controller(err, err_prev)
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
                if not GROUND_PERIODIC:  # t0 is the section's absolute start
                    t0 += period
            tau = 0.0
            at_section = True
            c0, c1 = ground_anchor(t0, p, GROUND)
            rhs(t0, y, p, f0)
            stats[ST_RHS_EVALS] += 1
            model_ends(t0, y, p, ends_old)

    clock[0] = k
    clock[1] = tau
    clock[2] = h
    stats[ST_IMPACTS] = n_imp
    stats[ST_STATUS] = status
    return n_imp


@kernel
def carry_saltation(dense, y, t, h, theta, t_ev, p, rate, onset, jump, y_new, n_base,
                    n_vectors, work, buf):
    """The tangent vectors at the end of a step whose point contact switched inside it.

    The step integrated ``V' = J- V`` throughout (the Jacobian follows the
    engine's flags, flipped only after the step); the vectors that cross the
    event at ``t_ev = t + theta h`` are ``V(t + h) = Phi+(delta) S V(t_ev)``,
    ``delta = (1 - theta) h``. ``V(t_ev)`` is the step's interpolant, S the
    saltation matrix (:func:`saltation_tangent`, with ``rate`` and ``onset``,
    where the force jumps: ``jump``; else the identity: the no-pull switch) and
    ``Phi+(delta) = I + delta J+``, with ``J+`` the new side's Jacobian at the
    event: an error of ``O(delta^2 |J|^2)``, where applying S at the step's end
    would leave ``O(delta |J+ - J-|)`` (1e-7 of the monodromy for the pair model
    at rtol 1e-12: delta ~ 1e-10, |J+ - J-| ~ k = 1000). Call it with the flags
    already flipped. ``work`` and ``buf`` are workspaces of y's size; the vectors
    of ``y_new`` are overwritten.
    """
    n = y.shape[0]
    dense_eval(DENSE_ROWS, dense, y, h, theta, work)
    if jump:
        saltation_tangent(p, rate, onset, work, n_base, n_vectors, buf)
    rhs_vectors(t_ev, work, p, buf)
    delta = (1.0 - theta) * h
    for i in range(n_base, n):
        y_new[i] = work[i] + delta * buf[i]


@kernel
def carry_shift(dense, y, t, h, theta, t_ev, p, convert, clipped, y_new, n_base, n_vectors,
                work, buf):
    """The tangent vectors at the end of a step whose Jankowski point contact changed
    phase inside it (``LAW_SHIFTED``).

    As :func:`carry_saltation`: the step integrated the old phase's equations
    throughout; the vectors at the event ``t_ev = t + theta h`` (the step's
    interpolant) are converted to the new phase's form (``convert``: at the
    switch d' = 0, shifted while approaching, :func:`shift_tangent`; an onset or
    a release keeps the form, the shift being the identity at d = 0) and
    carried to the step's end by ``I + delta J+`` (``delta = (1 - theta) h``,
    J+ the new phase's, with the law's flag already written: ``clipped`` True
    when the new phase is separating). ``work`` and ``buf`` are workspaces of
    y's size; the vectors of ``y_new`` are overwritten.
    """
    n = y.shape[0]
    dense_eval(DENSE_ROWS, dense, y, h, theta, work)
    if convert:
        model_ends(t_ev, work, p, buf)
        shift_tangent(p, buf[0], clipped, work, n_base, n_vectors, buf)
    rhs_vectors(t_ev, work, p, buf)
    delta = (1.0 - theta) * h
    for i in range(n_base, n):
        y_new[i] = work[i] + delta * buf[i]


@kernel
def record_onset(p, t_force, k, period, t0, state, imp, imp_state, row, n, ends):
    """Fill one impact row at onset: time, phase, velocity, corner, state."""
    model_ends(t_force, state, p, ends)
    d_max = max(ends[0], ends[1])
    corner, y_at, velocity = model_contact_point(t_force, state, p, ends)
    x = (t_force if GROUND_PERIODIC else t_force - t0) / period
    if x >= 1.0:
        x -= 1.0
    imp[row, IMP_TIME] = t_force + k * period if GROUND_PERIODIC else t_force
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
def update_peak(dense, y, y_new, t, h, p, ends_old, ends_new, imp, row, work, ends_tmp,
                forces, two_ends):
    """Raise an episode's peak penetration and peak force with this step's maxima.

    Candidates: the step's end, the interior maxima of each end penetration
    (where its rate turns from + to -) and, for the line contact, the interior
    maximum of the force itself (where its analytic rate turns), all located on
    the step's dense output. A graze shorter than one step is covered: its
    maximum lies inside the step between the landed onset and release.

    A dissipative law's force peaks while the faces still approach, before the
    penetration's maximum, and its rate involves the accelerations, which the
    models' force rates leave out; so for these laws (a compile-time branch:
    the elastic engines are unchanged) the interior maximum of the force is
    also searched directly: when the force rises at the step's start and falls
    at its end (one-sided differences on the dense output), a golden-section
    search on the dense output to EXTREMUM_TOL in time.
    """
    pen = max(ends_new[0], ends_new[1])
    if pen > imp[row, IMP_PEAK_PEN]:
        imp[row, IMP_PEAK_PEN] = pen
    force = model_forces(t + h, y_new, p, forces)
    if force > imp[row, IMP_PEAK_FORCE]:
        imp[row, IMP_PEAK_FORCE] = force
    for end in range(2 if two_ends else 1):
        if ends_old[end + 2] > 0.0 and ends_new[end + 2] < 0.0:
            theta = locate_extremum(dense, y, t, h, p, end, ends_old[end + 2], ends_new[end + 2],
                                    work, ends_tmp)
            d_m = end_value(dense, y, t, h, theta, p, end, work, ends_tmp)
            if d_m > imp[row, IMP_PEAK_PEN]:
                imp[row, IMP_PEAK_PEN] = d_m
            f_m = model_forces(t + theta * h, work, p, forces)
            if f_m > imp[row, IMP_PEAK_FORCE]:
                imp[row, IMP_PEAK_FORCE] = f_m
    if two_ends:
        rate_old = model_force_rate(t, y, p, ends_old)
        rate_new = model_force_rate(t + h, y_new, p, ends_new)
        if rate_old > 0.0 and rate_new < 0.0:
            theta = locate_root(dense, y, t, h, p, FORCE_RATE, 0.0, rate_old, 1.0, rate_new, 0.0,
                                work, ends_tmp)
            end_value(dense, y, t, h, theta, p, 0, work, ends_tmp)
            f_m = model_forces(t + theta * h, work, p, forces)
            if f_m > imp[row, IMP_PEAK_FORCE]:
                imp[row, IMP_PEAK_FORCE] = f_m
    if LAW_DISSIPATIVE:
        f_m = force_maximum(dense, y, t, h, p, work, forces)
        if f_m > imp[row, IMP_PEAK_FORCE]:
            imp[row, IMP_PEAK_FORCE] = f_m


@kernel
def force_on_dense(dense, y, t, h, theta, p, work, forces):
    """The contact force on A at t + theta h, from the step's dense output."""
    dense_eval(DENSE_ROWS, dense, y, h, theta, work)
    return model_forces(t + theta * h, work, p, forces)


@kernel
def force_maximum(dense, y, t, h, p, work, forces):
    """The force's interior maximum in the step, or 0 when it does not rise then fall."""
    delta = 1e-7
    if not (force_on_dense(dense, y, t, h, delta, p, work, forces)
            > force_on_dense(dense, y, t, h, 0.0, p, work, forces)):
        return 0.0
    if not (force_on_dense(dense, y, t, h, 1.0 - delta, p, work, forces)
            > force_on_dense(dense, y, t, h, 1.0, p, work, forces)):
        return 0.0
    ratio = 0.6180339887498949
    lo = 0.0
    hi = 1.0
    a = hi - ratio * (hi - lo)
    b = lo + ratio * (hi - lo)
    f_a = force_on_dense(dense, y, t, h, a, p, work, forces)
    f_b = force_on_dense(dense, y, t, h, b, p, work, forces)
    theta_tol = EXTREMUM_TOL / h if h > 0.0 else 1e-15
    for _ in range(200):
        if hi - lo <= theta_tol:
            break
        if f_a >= f_b:
            hi = b
            b = a
            f_b = f_a
            a = hi - ratio * (hi - lo)
            f_a = force_on_dense(dense, y, t, h, a, p, work, forces)
        else:
            lo = a
            a = b
            f_a = f_b
            b = lo + ratio * (hi - lo)
            f_b = force_on_dense(dense, y, t, h, b, p, work, forces)
    return max(f_a, f_b)


@kernel
def store_samples(dense, y, t0, k, period, tau, h, n_samples, traj, n_traj, work, n):
    """Interpolated samples on the grid tau = j T / n_samples, 0 < j < n_samples, in (tau, tau + h].

    The sample at tau = 0 is the section state, stored at the section.
    """
    dt = period / n_samples
    j = int(np.floor(tau / dt)) + 1
    # tau / dt may round to an integer that j dt does not reach (a step that landed a
    # rounding error short of a record sample on the grid): the grid decides, not the
    # quotient, or that sample would be skipped (or stored twice)
    while j > 1 and (j - 1) * dt > tau:
        j -= 1
    while j * dt <= tau:
        j += 1
    while j < n_samples and j * dt <= tau + h and n_traj < traj.shape[0]:
        theta = min((j * dt - tau) / h, 1.0)
        dense_eval(DENSE_ROWS, dense, y, h, theta, work)
        store_sample(traj, n_traj, (t0 + k * period if GROUND_PERIODIC else t0) + j * dt, work, n)
        n_traj += 1
        j += 1
    return n_traj
