"""Periodic orbits, Floquet multipliers, continuation and bifurcation points (issue 16).

- :mod:`.maps`: the stroboscopic map P^k of a system or scene and its monodromy
  (pluggable provider: the variational equations by default, finite
  differences as the check and the fallback).
- :mod:`.shooting`: Newton shooting for P^k(x) = x, the :class:`Orbit` record.
- :mod:`.continuation`: pseudo-arclength continuation, fold / period-doubling /
  Neimark-Sacker / grazing points, branch switching at period doublings.
- :mod:`.grazing`: the clearance's minima along an orbit (the grazing test).
- :mod:`.floquet`: the exact Floquet exponents of a periodic response (for
  ``classify`` and the Lyapunov report).
- :mod:`.store`: branches in HDF5 (atomic writes).

docs/orbits.md gives the method and the choices.
"""

from __future__ import annotations

from .maps import StroboscopicMap, finite_difference_monodromy
from .shooting import Orbit, OrbitNotFound, find_orbit, orbit_trajectory

__all__ = ["Orbit", "OrbitNotFound", "StroboscopicMap", "find_orbit",
           "finite_difference_monodromy", "orbit_trajectory"]
