"""Test-session set-up: the files run longest first.

The suite runs on two workers, a file per worker at a time (``--dist loadfile``),
handed out in collection order. Alphabetical order left the long files (the
sweeps', whose first tests also compile their engines) for last, and one worker
ran on alone at the end. Sorting the files by their seconds on a cold cache (the
CI case: compilation included), longest first, is the classic longest-processing-
time rule: the short files fill the gaps at the end. The seconds are per file,
setup + call + teardown, from

    python -m pytest -p no:cacheprovider --durations=0     # empty caches

on this 2-core machine (2026-11-27); a file missing here counts as 0 and runs
last. Stale numbers only change the order, never what runs.
"""

from __future__ import annotations

import pytest

FILE_SECONDS = {
    "test_contact_tangent.py": 142,
    "test_orbits.py": 128,
    "test_simulate.py": 127,
    "test_sweep_system.py": 84,
    "test_contact_laws_engine.py": 77,
    "test_saltation.py": 66,
    "test_store_crash.py": 63,
    "test_jankowski_tangent.py": 63,
    "test_sweep.py": 60,
    "test_contact_laws.py": 57,
    "test_ground_engine.py": 55,
    "test_lyapunov.py": 54,
    "test_extremes.py": 45,
    "test_distributed.py": 42,
    "test_ground_y.py": 38,
    "test_cli.py": 32,
    "test_custom.py": 27,
    "test_monodromy.py": 20,
    "test_classify.py": 18,
    "test_converged.py": 18,
    "test_input_limits.py": 17,
    "test_basins.py": 17,
    "test_recipes.py": 15,
    "test_cli_sections.py": 11,
    "test_plot.py": 11,
    "test_ground_motions.py": 10,
    "test_reproduction.py": 10,
    "test_cli_quake.py": 10,
    "test_kernel_cache.py": 9,
    "test_ground_scene.py": 8,
    "test_layering.py": 7,
}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(session, config, items) -> None:
    """Longest files first; the tests of a file keep their order (a stable sort)."""
    items.sort(key=lambda item: -FILE_SECONDS.get(item.path.name, 0))
