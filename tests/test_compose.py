"""The generated engine modules: what Python may call in them, and what it gets.

An engine's kernels other than its loop are compiled for other kernels only
(:class:`chaospound.kernels.jit.InternalDispatcher`: no CPython wrapper, not on
the disk cache, no machine code of their own: their optimised code is linked into
the loop's). A call from Python still works, through a twin compiled with its
wrapper, and returns what the same function gives run as plain Python.

The first process to load an engine compiles its loop under a lock beside the
module's file, so that others starting on it together wait and load the cache.
"""

from __future__ import annotations

import multiprocessing
import time

import numba
import numpy as np
import pytest

from chaospound import load_preset, simulate
from chaospound.dynamics.system import System
from chaospound.engine.compose import _machine_lock
from chaospound.kernels.jit import InternalDispatcher, KernelDispatcher


def test_internal_kernels_answer_python_like_their_python_source():
    system = System.from_scene(load_preset("fig3a"))
    module = system.engine().module
    assert isinstance(module.run, KernelDispatcher)
    assert not isinstance(module.run, InternalDispatcher)  # the loop keeps its wrapper
    ends = module.model_ends
    assert isinstance(ends, InternalDispatcher)
    rng = np.random.default_rng(5)
    for _ in range(20):
        y = rng.normal(scale=[2.0, 1.0, 0.2] * 4)  # some states in contact, some not
        t = float(rng.uniform(0.0, system.period))
        compiled, python = np.empty(4), np.empty(4)
        ends(t, y, system.params, compiled)
        ends.py_func(t, y, system.params, python)
        np.testing.assert_allclose(compiled, python, rtol=1e-13, atol=1e-15)
    assert type(ends._twin) is KernelDispatcher  # compiled once, with its wrapper


def test_internal_kernels_emit_no_machine_code_of_their_own():
    system = System.from_scene(load_preset("fig3a"))
    simulate(system, transient=0, cycles=1)  # the loop: compiled, or loaded from the cache
    module = system.engine().module
    ends = module.model_ends
    args = (0.0, system.initial_state, system.params, np.empty(4))
    ends.compile(tuple(numba.typeof(a) for a in args))  # as the loop's compile would
    (result,) = ends.overloads.values()
    engine = result.library.codegen._engine
    assert "define " in result.library.get_llvm_str()  # its IR, to link (and optimise there)
    assert not engine.is_symbol_defined(result.fndesc.mangled_name)  # no machine code
    (loop,) = module.run.overloads.values()
    assert loop.library.get_pointer_to_function(loop.fndesc.llvm_cpython_wrapper_name)


def _hold(path, log):
    with _machine_lock(path):
        with open(log, "a") as f:
            f.write("acquired\n")
        time.sleep(0.3)
        with open(log, "a") as f:
            f.write("released\n")


def test_the_compile_lock_excludes_other_processes(tmp_path):
    lock, log = tmp_path / "engine_x.lock", tmp_path / "log"
    child = multiprocessing.get_context("spawn").Process(target=_hold, args=(lock, log))
    child.start()
    while not (log.exists() and "acquired" in log.read_text()):
        time.sleep(0.01)
    with _machine_lock(lock):  # waits for the child
        assert log.read_text().split() == ["acquired", "released"]
    child.join()
    assert child.exitcode == 0
    with _machine_lock(None):  # no path: no lock, no error
        pass


def test_qr_and_propagator_share_one_module_and_keep_their_records():
    """The two tangent modes run one compiled module (the loop's ``propagate`` argument
    chooses the record at a section), and a run of one leaves the other as it was: the
    QR log after a propagator run equals the QR log before it, bit for bit, and the
    propagators' product maps a tangent vector as the QR run's vector moves."""
    from chaospound.dynamics.system import evolve

    # tight tolerances: the two runs' step sequences differ (their tangent components
    # differ and enter the error norm), so they agree to the integration error only
    system = System.from_scene(load_preset("fig4")).with_solver(rtol=1e-11, atol=1e-13)
    qr, propagator = system.engine("qr"), system.engine("propagator")
    assert qr.module is propagator.module and qr is not propagator
    assert (qr.propagate, propagator.propagate) == (False, True)
    n = system.dim
    state = evolve(system, cycles=20).state
    augmented = np.zeros(2 * n)
    augmented[:n] = state
    augmented[n] = 1.0
    before = evolve(system, augmented, cycles=6, tangent="qr")
    stored = evolve(system, state, cycles=6, tangent="propagator")
    after = evolve(system, augmented, cycles=6, tangent="qr")
    assert before.tangent_log.tobytes() == after.tangent_log.tobytes()
    assert before.augmented_state.tobytes() == after.augmented_state.tobytes()
    # the same vector carried by the propagators: its growth is the sum of the QR logs
    v = augmented[n:].copy()
    for row in stored.tangent_log:
        v = row.reshape(n, n).T @ v  # row i holds column i of the cycle's propagator
    assert np.log(np.linalg.norm(v)) == pytest.approx(before.tangent_log.sum(), rel=1e-7)
    np.testing.assert_allclose(v / np.linalg.norm(v), after.augmented_state[n:], rtol=1e-6,
                               atol=1e-9)
