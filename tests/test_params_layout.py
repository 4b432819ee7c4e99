"""The packed parameter vector: unique, contiguous slots, each read by a kernel.

The layout is generated from named blocks (chaospound/kernels/params.py);
these tests check what the generation promises, and that no slot is packed
for nothing: every field's name is read (``p[...]`` in a load) by some
kernel, and every tower block's start is used by one.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

from chaospound.dynamics.system import duffing, lorenz
from chaospound.kernels import params as P
from chaospound.scene import list_presets, load_preset

KERNELS = Path(P.__file__).resolve().parent
#: every package whose modules hold kernels or kernel templates
KERNEL_PACKAGES = [KERNELS] + [KERNELS.parent / name for name in ("physics", "solvers", "engine")]
#: slots a composition hands to a law or a ground motion as the base of its block
#: (``LAW = P_BETA``: the law reads ``p[base]``, ``p[base + 1]``); they count as read
#: when the composer binds them
BOUND_AS_BLOCKS = ("P_BETA", "P_CHI", "P_PERIOD_RATIO")
#: the packed record of the ground motion's kind: the composition chooses the motion
#: (System.ground), so no kernel reads it; a bare vector's consumer (a test's
#: adapter, the scipy benchmark) reads it in Python to name the motion
READ_IN_PYTHON = ("P_GROUND",)


def _slot(qualified: str) -> int:
    block, name = qualified.split(".")
    start = dict((b, s) for b, _, s in P.BLOCKS)[block]
    return getattr(P, name) + (getattr(P, start) if start else 0)


def _kernel_reads() -> tuple[set[str], set[str]]:
    """Names inside a loaded subscript ``p[...]``, and all names loaded, in the kernels."""
    in_subscripts, loaded = set(), set()
    for path in (f for package in KERNEL_PACKAGES for f in sorted(package.rglob("*.py"))):
        if path.name == "params.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Load):
                in_subscripts |= {n.id for n in ast.walk(node.slice) if isinstance(n, ast.Name)}
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
                loaded.add(node.id)
    return in_subscripts, loaded


def test_slots_are_unique_and_contiguous():
    slots = [_slot(q) for q in P.LAYOUT]
    assert sorted(slots) == list(range(P.N_PARAMS))
    assert slots == list(range(P.N_PARAMS))  # in block order
    assert len(set(P.LAYOUT)) == len(P.LAYOUT) == P.N_PARAMS
    assert P.TOWER_B == P.TOWER_A + len(P.TOWER_FIELDS)


def test_generated_constants_are_plain_integers():
    for qualified in P.LAYOUT:
        value = getattr(P, qualified.split(".")[1])
        assert type(value) is int  # numba freezes module-level ints as constants


def test_every_slot_is_read_by_a_kernel():
    in_subscripts, loaded = _kernel_reads()
    unread = [q for q in P.LAYOUT if q.split(".")[1] not in in_subscripts]
    assert sorted(unread) == sorted("globals." + name for name in READ_IN_PYTHON + BOUND_AS_BLOCKS)
    compose = (KERNELS.parent / "engine" / "compose.py").read_text()
    # the composer hands them to the law and the motion (law_base, ground_base)
    assert "return P_BETA if" in compose and "return P_PERIOD_RATIO" in compose
    starts = [s for _, _, s in P.BLOCKS if s is not None]
    assert [s for s in starts if s not in loaded] == []


def test_packed_vectors_fill_only_their_own_blocks():
    """A scene writes globals and towers only; a reference system its block only."""
    reference = {i for i, q in enumerate(P.LAYOUT) if q.startswith("reference.")}
    for name in list_presets():
        p = load_preset(name).pack()
        assert p.shape == (P.N_PARAMS,)
        assert not np.any(p[sorted(reference)]), name
    for system in (lorenz(), duffing()):
        outside = [i for i in range(P.N_PARAMS) if i not in reference and i != P.P_PERIOD]
        assert not np.any(system.params[outside]), system.name
