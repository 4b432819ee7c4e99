"""Comparison of sweep stores shared by the store, sweep and Dask tests."""

import h5py
import numpy as np

from chaospound.store import TIMING_FIELDS


def bitwise(a, b) -> bool:
    """Same dtype, shape and bytes (NaN payloads and signed zeros included)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def store_contents(path) -> dict:
    """Every attribute and dataset of a file, keyed by HDF5 path, timing fields left out."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            for key, value in obj.attrs.items():
                if key not in TIMING_FIELDS:
                    out[f"{name}@{key}"] = value
            if isinstance(obj, h5py.Dataset) and name.rsplit("/", 1)[-1] not in TIMING_FIELDS:
                out[name] = obj[()]

        visit("/", f)
        f.visititems(visit)
    return out


def assert_same_store(path_a, path_b) -> None:
    """Two sweep files hold bitwise the same data and attributes (timing fields aside)."""
    a, b = store_contents(path_a), store_contents(path_b)
    assert sorted(a) == sorted(b)
    different = [key for key in a if not bitwise(a[key], b[key])]
    assert not different, f"differ: {different}"
