"""The generated engine modules: what Python may call in them, and what it gets.

An engine's kernels other than its loop are compiled for other kernels only
(:class:`chaospound.kernels.jit.InternalDispatcher`: no CPython wrapper, not on
the disk cache). A call from Python still works, through a twin compiled with
its wrapper, and returns what the same function gives run as plain Python.
"""

from __future__ import annotations

import numpy as np

from chaospound import load_preset
from chaospound.dynamics.system import System
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
