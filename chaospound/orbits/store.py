"""Continued branches in HDF5, written atomically.

Layout (format "chaospound-branches", version 1)::

    /                           attrs: format, version, chaospound_version, parameter,
                                       model, system, scene (TOML or ""), state_names (JSON)
    /branches/<j>               one group per branch, j = 0, 1, ...
        attrs: name, period (forcing cycles), stop_reasons (JSON)
        parameter        (N,)        parameter value of each point
        forcing_period   (N,)        T (normalised time)
        state            (N, n)      section state (model units: A_g, A_g omega_Ax, rad, ...)
        multipliers      (N, n)      complex Floquet multipliers, by decreasing modulus
        monodromy        (N, n, n)   d P^k / d x
        stable           (N,)        uint8, 1 if every |mu| < 1
        impacts_per_period (N,)      int
        corners          (N,)        str, corner labels of one period joined by spaces
        impact_velocity  (N, I)      velocities of one period (A_g omega_Ax), NaN-padded
        impact_phase     (N, I)      onset phases in [0, 1), NaN-padded
        impact_cycle     (N, I)      forcing cycle 0..k-1 of each onset, -1-padded
        residual, iterations (N,)    Newton's relative residual and iterations
        special/                     the located bifurcation points (M of them)
            kind (M,) str, note (M,) str, index (M,) int (between points index-1
            and index), bracket (M,) (final bracket width in the parameter),
            test (M,), eigenvector (M, n) complex (NaN without one), and the
            orbit at each point with the datasets above (parameter, state, ...)

A file is written to a temporary file beside the target, flushed and fsynced,
then renamed over the target (``os.replace``) and the directory fsynced: a
reader sees the old file or the new one, never a part.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .continuation import Branch, SpecialPoint
from .shooting import Orbit

__all__ = ["FORMAT", "BranchFile", "is_branch_file", "open_branches", "write_branches"]

FORMAT = "chaospound-branches"
VERSION = 1


def _str_dtype():
    import h5py

    return h5py.string_dtype("utf-8")


def _orbit_arrays(orbits: list[Orbit], n: int) -> dict[str, np.ndarray]:
    count = len(orbits)
    width = max([o.impacts_per_period for o in orbits] + [1])
    vel = np.full((count, width), np.nan)
    phase = np.full((count, width), np.nan)
    cycle = np.full((count, width), -1, dtype=np.int64)
    for i, o in enumerate(orbits):
        j = o.impacts_per_period
        vel[i, :j], phase[i, :j], cycle[i, :j] = o.impact_velocity, o.impact_phase, o.impact_cycle
    return {
        "parameter": np.array([o.value for o in orbits], dtype=float),
        "forcing_period": np.array([o.forcing_period for o in orbits], dtype=float),
        "state": np.array([o.state for o in orbits], dtype=float).reshape(count, n),
        "multipliers": np.array([o.multipliers for o in orbits], dtype=complex).reshape(count, n),
        "monodromy": np.array([o.monodromy for o in orbits], dtype=float).reshape(count, n, n),
        "stable": np.array([o.stable for o in orbits], dtype=np.uint8),
        "impacts_per_period": np.array([o.impacts_per_period for o in orbits], dtype=np.int64),
        "corners": np.array([" ".join(o.corners) for o in orbits], dtype=object),
        "impact_velocity": vel,
        "impact_phase": phase,
        "impact_cycle": cycle,
        "residual": np.array([o.residual for o in orbits], dtype=float),
        "iterations": np.array([o.iterations for o in orbits], dtype=np.int64),
    }


def _write_arrays(group, arrays: dict[str, np.ndarray]) -> None:
    for name, values in arrays.items():
        if values.dtype == object:
            group.create_dataset(name, data=values.astype(str).tolist() if values.size else [],
                                 dtype=_str_dtype(), shape=values.shape)
        else:
            group.create_dataset(name, data=values)


def write_branches(path, branches: list[Branch], *, scene_toml: str = "", model: str = "",
                   system: str = "", state_names: tuple[str, ...] = ()) -> None:
    """Write branches to ``path`` atomically (temporary file, fsync, ``os.replace``).

    Parameters
    ----------
    path : str or Path
        Target file (replaced if it exists).
    branches : list of Branch
        At least one; all of the same parameter.
    scene_toml, model, system : str
        Provenance: the scene as TOML (empty for a custom system), the model
        that ran, the system's name.
    state_names : tuple of str
        Names of the state components.
    """
    import h5py

    from .. import __version__

    if not branches:
        raise ValueError("no branch to write")
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    n = branches[0].orbits[0].state.shape[0]
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    os.close(fd)
    try:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["version"] = VERSION
            f.attrs["chaospound_version"] = __version__
            f.attrs["parameter"] = branches[0].parameter
            f.attrs["model"] = model
            f.attrs["system"] = system
            f.attrs["scene"] = scene_toml
            f.attrs["state_names"] = json.dumps(list(state_names))
            top = f.create_group("branches")
            for j, br in enumerate(branches):
                g = top.create_group(str(j))
                g.attrs["name"] = br.name
                g.attrs["period"] = br.period
                g.attrs["stop_reasons"] = json.dumps(br.stop_reasons)
                _write_arrays(g, _orbit_arrays(br.orbits, n))
                s = g.create_group("special")
                sp = br.special
                s.attrs["count"] = len(sp)
                if sp:
                    arrays = _orbit_arrays([p.orbit for p in sp], n)
                    arrays.update({
                        "kind": np.array([p.kind for p in sp], dtype=object),
                        "note": np.array([p.note for p in sp], dtype=object),
                        "index": np.array([p.index for p in sp], dtype=np.int64),
                        "bracket": np.array([p.bracket for p in sp], dtype=float),
                        "test": np.array([p.test for p in sp], dtype=float),
                        "eigenvector": np.array([
                            p.eigenvector if p.eigenvector is not None
                            else np.full(n, np.nan) for p in sp], dtype=complex),
                    })
                    arrays["parameter"] = np.array([p.value for p in sp], dtype=float)
                    _write_arrays(s, arrays)
        with open(tmp, "rb+") as stream:
            os.fsync(stream.fileno())
        os.replace(tmp, path)
        with contextlib.suppress(OSError):  # not every file system fsyncs directories
            dfd = os.open(directory, os.O_RDONLY)
            try:
                os.fsync(dfd)
            finally:
                os.close(dfd)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


@dataclass
class BranchFile:
    """A branch file read back: provenance and the branches with their special points."""

    path: Path
    parameter: str
    model: str
    system: str
    scene_toml: str
    state_names: list[str]
    branches: list[Branch]


def _orbits_from(g, parameter: str, period: int, names: tuple[str, ...]) -> list[Orbit]:
    count = g["parameter"].shape[0]
    data = {name: g[name][()] for name in g if name != "special" and hasattr(g[name], "shape")}
    corners = [c.decode() if isinstance(c, bytes) else str(c) for c in data["corners"]]
    orbits = []
    for i in range(count):
        j = int(data["impacts_per_period"][i])
        orbits.append(Orbit(
            parameter=parameter, value=float(data["parameter"][i]), period=period,
            forcing_period=float(data["forcing_period"][i]), state=data["state"][i].copy(),
            state_names=names, multipliers=data["multipliers"][i].copy(),
            monodromy=data["monodromy"][i].copy(),
            impact_velocity=data["impact_velocity"][i, :j].copy(),
            impact_phase=data["impact_phase"][i, :j].copy(),
            impact_cycle=data["impact_cycle"][i, :j].copy(),
            corners=tuple(corners[i].split()), residual=float(data["residual"][i]),
            iterations=int(data["iterations"][i])))
    return orbits


def is_branch_file(path) -> bool:
    """Whether ``path`` is an HDF5 file of :func:`write_branches` (False for anything else)."""
    try:
        import h5py

        with h5py.File(path, "r") as f:
            return f.attrs.get("format") == FORMAT
    except (OSError, ValueError):
        return False


def open_branches(path) -> BranchFile:
    """Read a branch file written by :func:`write_branches`.

    Raises
    ------
    ValueError
        Not a branch file (one line).
    """
    import h5py

    path = Path(path)
    if not is_branch_file(path):
        raise ValueError(f"{path}: not a chaospound branch file")
    with h5py.File(path, "r") as f:
        parameter = str(f.attrs["parameter"])
        names = tuple(json.loads(f.attrs["state_names"]))
        branches = []
        for key in sorted(f["branches"], key=int):
            g = f["branches"][key]
            period = int(g.attrs["period"])
            orbits = _orbits_from(g, parameter, period, names)
            special = []
            s = g["special"]
            if int(s.attrs["count"]):
                sorbits = _orbits_from(s, parameter, period, names)
                kinds = [k.decode() if isinstance(k, bytes) else str(k) for k in s["kind"][()]]
                notes = [k.decode() if isinstance(k, bytes) else str(k) for k in s["note"][()]]
                vecs = s["eigenvector"][()]
                for i, o in enumerate(sorbits):
                    vec = None if np.all(np.isnan(vecs[i].real)) else vecs[i].copy()
                    special.append(SpecialPoint(kind=kinds[i], value=o.value, orbit=o,
                                                index=int(s["index"][i]),
                                                bracket=float(s["bracket"][i]),
                                                test=float(s["test"][i]), eigenvector=vec,
                                                note=notes[i]))
            branches.append(Branch(parameter=parameter, period=period, orbits=orbits,
                                   special=special, name=str(g.attrs["name"]),
                                   stop_reasons=json.loads(g.attrs["stop_reasons"])))
        return BranchFile(path=path, parameter=parameter, model=str(f.attrs["model"]),
                          system=str(f.attrs["system"]), scene_toml=str(f.attrs["scene"]),
                          state_names=list(names), branches=branches)
