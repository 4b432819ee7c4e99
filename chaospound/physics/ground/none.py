"""No ground motion: ``u_g = 0``.

The values:
``(0, 0)`` from :func:`at` and :func:`at_anchor`, and the carried state ``(0, 1)``
(the phase of ``sin, cos`` at zero) from :func:`anchor` and :func:`shifted`.
The block is empty.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from chaospound.kernels.jit import inline, kernel

NAME = "none"
PARAMETERS: tuple[str, ...] = ()
#: constant forcing is periodic with every period: any section interval is valid
#: (period() is None: no constraint), so today's ``ground = "none"`` runs keep working
PERIODIC = True
KINKS = False


def block(spec: Mapping[str, float] | None = None) -> np.ndarray:
    """The empty block (``spec`` is ignored)."""
    return np.zeros(0, dtype=np.float64)


def period(values: np.ndarray) -> None:
    """None: no forcing period to match (every section interval is one)."""
    return None


@inline
def at(t, p, base):
    """``(0, 0)``."""
    return 0.0, 0.0


@inline
def at_y(t, p, base):
    """``(0, 0)``."""
    return 0.0, 0.0


@inline
def acceleration(t, p, base):
    """``0``."""
    return 0.0


@inline
def anchor(t, p, base):
    """``(0, 1)``, as powers.ground_phase without ground motion."""
    return 0.0, 1.0


@inline
def shifted(c0, c1, shift, p, base):
    """``(0, 1)``, as powers.phase_shifted without ground motion."""
    return 0.0, 1.0


@inline
def at_anchor(c0, c1, p, base):
    """``(0, 0)``."""
    return 0.0, 0.0


@kernel
def next_kink(t, p, base):
    """No kinks: ``inf``."""
    return math.inf
