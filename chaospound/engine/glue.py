"""The right-hand side of a composition: model, contact law and ground motion joined.

A template (:mod:`.compose`). ``rhs(t, y, p, out)`` evaluates the ground motion
and calls ``rhs_grounded``, which the composition binds to
:func:`rhs_tangent` (the state, followed by the tangent vectors if it has any: the
variational equations ``V' = J V`` of docs/model.md section 12, with the model's
linearisation computed once per call and applied to each vector), or, where the
composition's tangent dynamics are refused, :func:`rhs_plain` (the state alone).
"""

from chaospound.kernels.free import (
    GROUND,
    LAW_DXI,
    LAW_MEMORY,
    N_BASE,
    ground_at,
    model_jvp,
    model_linearize,
    model_memory_jvp,
    model_memory_linearize,
    model_rhs,
    rhs_grounded,
)
from chaospound.kernels.jit import inline, kernel

# ==== template ====


@kernel
def rhs(t, y, p, out):
    """Time derivative of the state (and tangent vectors), into ``out``."""
    ug, vg = ground_at(t, p, GROUND)
    rhs_grounded(t, y, p, ug, vg, out)


@kernel
def rhs_plain(t, y, p, ug, vg, out):
    """:func:`rhs` with the ground motion ``(u_g, u_g')`` at t given.

    Lets a stepper that evaluates twice at one time (Dormand-Prince's last
    stage and its FSAL stage) compute the ground once. One out-of-line copy
    with the model body inlined, not inlined itself into each of the seven
    Dormand-Prince stages, which would double the compile time.
    """
    model_rhs(t, y, p, ug, vg, out)


@kernel
def rhs_tangent(t, y, p, ug, vg, out):
    """State and tangent vectors: ``y' = f(y)``, ``V' = J(y) V``.

    A law with memory adds ``(df/dxi) dxi_i`` to vector i, ``dxi_i`` its memory
    sensitivity written at the episode's onset (:mod:`chaospound.engine.memory`).
    A state without vectors is :func:`rhs_plain`'s arithmetic: the tangent module
    runs plain states too (:meth:`chaospound.engine.compose.Composition.compiled`).
    """
    model_rhs(t, y, p, ug, vg, out)
    if y.shape[0] > N_BASE:
        _vectors_rhs(t, y, p, out)


@kernel
def rhs_vectors(t, y, p, out):
    """The tangent vectors' part of :func:`rhs_tangent` alone, ``out[N_BASE:]``.

    The loop recomputes it where a saltation has changed the vectors at the end of
    an accepted step (the step's last derivative is the next one's first stage),
    leaving the state's part, ``out[:N_BASE]``, as the step computed it.
    """
    _vectors_rhs(t, y, p, out)


@inline
def _vectors_rhs(t, y, p, out):
    """``V' = J(y) V`` (and the memory's term) for every tangent vector after the state."""
    n = N_BASE
    lin = model_linearize(t, y, p)
    for i in range(1, y.shape[0] // n):
        model_jvp(p, lin, y[i * n:(i + 1) * n], out[i * n:(i + 1) * n])
    if LAW_MEMORY:
        mem = model_memory_linearize(t, y, p)
        for i in range(1, y.shape[0] // n):
            model_memory_jvp(p, mem, p[LAW_DXI + i - 1], out[i * n:(i + 1) * n])
