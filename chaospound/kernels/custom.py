"""The cycle integrator specialised to a user's own jitted system.

A user system supplies three numba-jitted functions (docs/model.md section 12 does
not care which oscillator it integrates)::

    rhs(t, y, q, out)       # out[:] = dy/dt
    jacobian(t, y, q, jac)  # jac[i, j] = d rhs_i / d y_j
    gap(t, y, q) -> (g, dg/dt)   # optional: contact when g < 0

with ``q`` the user's parameter vector. :func:`compile_engine` returns a copy
of the integrator of :mod:`chaospound.kernels.integrate` (events, landing on
contact kinks, sections, impact table, tangent vectors and QR) in which the
model layer is replaced by these functions: every kernel of the engine's
modules is re-created from its Python source with its global names rebound
(``rhs``, ``rhs_grounded``, ``contact_ends``, ... and ``MODEL_DIMS``), so
there is one integrator, not a second one to keep in step. The built-in
kernels stay cached on disk; a user engine is compiled once per process
(numba cannot cache functions that call other dispatchers through globals
set at run time), which takes some 20 s.

Packed vector of a user system (``p``): the usual header of
:mod:`.params` (``P_PERIOD``, ``P_PHASE0``; ``P_GROUND`` = 0), then the user's
``q`` from ``N_PARAMS``, then an ``n x n`` scratch block that receives the
Jacobian during a tangent run (the kernels allocate nothing).

Impacts of a user system: onsets of ``g < 0`` with the velocity ``-dg/dt``
(the closing speed) and the corner label "face"; peaks of the contact force
are not known (0).
"""

from __future__ import annotations

import itertools
import types

import numpy as np
from numba import njit
from numba.core.registry import CPUDispatcher

from . import contact, events, integrate, models, powers, reference, rk, tangent
from .params import (
    CUSTOM,
    MODEL_DIMS,
    N_PARAMS,
    P_GROUND,
    P_PERIOD,
    P_PERIOD_RATIO,
    TANGENT,
)

#: the modules of the engine, callees first
ENGINE_MODULES = (powers, contact, reference, tangent, models, rk, events, integrate)


def pack_custom(period: float, q: np.ndarray, n: int) -> np.ndarray:
    """The packed vector of a user system: header, ``q``, Jacobian scratch."""
    p = np.zeros(N_PARAMS + q.shape[0] + n * n)
    p[P_PERIOD] = period
    p[P_PERIOD_RATIO] = period / (2.0 * np.pi)
    p[P_GROUND] = 0.0
    p[N_PARAMS:N_PARAMS + q.shape[0]] = q
    return p


def compile_engine(rhs: CPUDispatcher, jacobian: CPUDispatcher, gap: CPUDispatcher | None,
                   n: int, n_params: int) -> types.SimpleNamespace:
    """The integrator bound to a user system of ``n`` states and ``n_params`` parameters.

    Returns
    -------
    types.SimpleNamespace
        ``run_cycles`` (same signature as
        :func:`chaospound.kernels.integrate.run_cycles`, model id ``CUSTOM`` or
        ``TANGENT + CUSTOM``) and ``has_gap``.
        Nothing is compiled until the first call.
    """
    wrappers = _wrappers(rhs, jacobian, gap, n, n_params)
    dims = tuple(MODEL_DIMS[:CUSTOM]) + (n,)
    # a fresh namespace per module, then every kernel re-created in it
    serial = next(_ENGINES)
    spaces = {m.__name__: dict(vars(m)) for m in ENGINE_MODULES}
    replace = {}  # original kernel -> its clone, or the user-system wrapper
    for m in ENGINE_MODULES:
        for obj in vars(m).values():
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == m.__name__:
                replace[obj] = _recreate(obj, spaces[m.__name__], serial)
    for name, wrapper in wrappers.items():
        replace[getattr(models, name)] = wrapper
    for space in spaces.values():
        for name, obj in list(space.items()):
            if isinstance(obj, CPUDispatcher) and obj in replace:
                space[name] = replace[obj]
        if "MODEL_DIMS" in space:
            space["MODEL_DIMS"] = dims
    return types.SimpleNamespace(run_cycles=replace[integrate.run_cycles],
                                 has_gap=gap is not None)


_ENGINES = itertools.count(1)  #: engine serial numbers, part of the clones' symbol names


def _recreate(dispatcher: CPUDispatcher, space: dict, serial: int) -> CPUDispatcher:
    """A new, uncached dispatcher of the same Python function over ``space``.

    The clone gets its own qualified name: machine-code symbols are named
    after it, and a clone sharing a name (and numba's per-process serial)
    with a kernel loaded from the disk cache would be linked in its place.
    """
    fn = dispatcher.py_func
    clone = types.FunctionType(fn.__code__, space, fn.__name__, fn.__defaults__,
                               fn.__closure__)
    clone.__doc__ = fn.__doc__
    clone.__qualname__ = f"{fn.__qualname__}__custom{serial}"
    options = {k: v for k, v in dispatcher.targetoptions.items()
               if k not in ("cache", "nopython")}
    return njit(**options)(clone)


#: as :data:`.jit.kernel`, uncached (the wrappers close over the user's functions)
_kernel = njit(_nrt=False, error_model="numpy")


def _wrappers(user_rhs, user_jac, user_gap, n: int, n_params: int) -> dict:
    """Model-layer functions (the names :mod:`.models` exports) over the user's."""
    q_lo = N_PARAMS
    q_hi = N_PARAMS + n_params

    @_kernel
    def rhs(model, t, y, p, out):
        q = p[q_lo:q_hi]
        user_rhs(t, y[:n], q, out[:n])
        if model >= TANGENT:
            jac = p[q_hi:q_hi + n * n].reshape((n, n))
            user_jac(t, y[:n], q, jac)
            for v in range(1, y.shape[0] // n):
                a = v * n
                for i in range(n):
                    acc = 0.0
                    for j in range(n):
                        acc += jac[i, j] * y[a + j]
                    out[a + i] = acc

    @_kernel
    def rhs_grounded(model, t, y, p, ug, vg, out):
        rhs(model, t, y, p, out)

    if user_gap is None:
        @_kernel
        def contact_ends(model, t, y, p, out):
            out[0] = -1.0
            out[1] = -1.0
            out[2] = 0.0
            out[3] = 0.0

        @_kernel
        def penetration_rate(model, t, y, p, y_at):
            return 0.0
    else:
        @_kernel
        def contact_ends(model, t, y, p, out):
            g, rate = user_gap(t, y[:n], p[q_lo:q_hi])
            out[0] = -g
            out[1] = -g
            out[2] = -rate
            out[3] = -rate

        @_kernel
        def penetration_rate(model, t, y, p, y_at):
            _, rate = user_gap(t, y[:n], p[q_lo:q_hi])
            return -rate

    @_kernel
    def contact_forces(model, t, y, p, q_out):
        for i in range(q_out.shape[0]):
            q_out[i] = 0.0
        return 0.0

    @_kernel
    def contact_force_rate(model, t, y, p, ends):
        return 0.0

    return {
        "rhs": rhs,
        "rhs_grounded": rhs_grounded,
        "contact_ends": contact_ends,
        "penetration_rate": penetration_rate,
        "contact_forces": contact_forces,
        "contact_force_rate": contact_force_rate,
    }
