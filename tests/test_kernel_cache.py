"""Numba's disk cache never serves a kernel compiled from older sources.

Numba stamps a cached function with the hash of its own source file only: a
kernel of ``reference.py`` keeps the constants of the ``params.py`` it was
compiled with. The kernels package compares a hash of all its modules with a
stamp beside the cache and clears the cache when they differ
(:func:`chaospound.kernels.cache.invalidate_stale_cache`). Each test works on a copy
of the package, in fresh processes.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from chaospound.kernels.cache import STAMP_NAME, source_digest

PACKAGE = Path(__file__).resolve().parents[1] / "chaospound"

#: Lorenz's right-hand side at y = (1, 2, 4) with p[i] = i + 1: out[0] = p[REF_0] (y1 - y0)
PROBE = """
import sys
import numpy as np
from chaospound.kernels import params, reference
assert reference.__file__.startswith(sys.argv[1]), reference.__file__
p = np.arange(params.N_PARAMS, dtype=np.float64) + 1.0
out = np.zeros(3)
reference.lorenz_rhs(0.0, np.array([1.0, 2.0, 4.0]), p, out)
print(repr(float(out[0])), params.REF_0 + 1.0)
"""


def _copy(tmp_path: Path, cache_dir: Path | None):
    root = tmp_path / "tree"
    shutil.copytree(PACKAGE, root / "chaospound",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(root)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = str(cache_dir)
    return root, env


def _start(root: Path, env: dict) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", PROBE, str(root)], cwd=root, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _result(process: subprocess.Popen) -> tuple[float, float]:
    out, err = process.communicate(timeout=300)
    assert process.returncode == 0, err
    kernel, expected = out.split()
    return float(kernel), float(expected)


@pytest.mark.parametrize("where", ["__pycache__", "NUMBA_CACHE_DIR"])
def test_an_edit_in_a_callee_module_is_never_served_stale(tmp_path, where):
    root, env = _copy(tmp_path, tmp_path / "numba-cache" if where == "NUMBA_CACHE_DIR" else None)
    search = root if where == "__pycache__" else tmp_path / "numba-cache"

    before, expected = _result(_start(root, env))  # compiles and caches lorenz_rhs
    assert before == expected
    (stamp,) = search.rglob(STAMP_NAME)
    assert list(stamp.parent.glob("reference.lorenz_rhs-*.nbi"))
    old_stamp = stamp.read_text()

    # an edit in params.py only: reference.py, the cached function's own file, is unchanged
    params = root / "chaospound" / "kernels" / "params.py"
    params.write_text(params.read_text() + "\nREF_0, REF_1 = REF_1, REF_0  # edited\n")

    # the premise: numba alone (a stamp claiming the sources are current) serves stale code
    stamp.write_text(source_digest(params.parent) + "\n")
    stale, _ = _result(_start(root, env))
    assert stale == before

    # the real situation after an edit: the old stamp. Three processes start together
    stamp.write_text(old_stamp)
    processes = [_start(root, env) for _ in range(3)]
    results = [_result(p) for p in processes]
    assert all(kernel == expected for kernel, expected in results), results
    assert results[0][0] != before
    assert stamp.read_text().strip() == source_digest(params.parent)
    assert not list(stamp.parent.glob(f"{STAMP_NAME}.*"))  # no temporary stamp left behind

    # and the next process loads the new code from the cache without clearing it
    index = next(stamp.parent.glob("reference.lorenz_rhs-*.nbi"))
    written = index.stat().st_mtime_ns
    again, expected = _result(_start(root, env))
    assert again == expected and index.stat().st_mtime_ns == written
