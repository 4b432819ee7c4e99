"""Write docs/examples/synthetic.AT2: the README's earthquake record, made here.

    python docs/examples/make_synthetic_record.py

One realisation (seed 15) of the Kanai-Tajimi / Clough-Penzien process of
:mod:`chaospound.physics.ground.stochastic` (omega_g = 5 pi rad/s, zeta_g = 0.6,
omega_f = 0.5 pi rad/s, zeta_f = 0.6, Jennings envelope 2 / 12 / 0.2 s^-1),
20 s at dt = 0.01 s, scaled to a peak ground acceleration of 0.35 g and
baseline-corrected to end at rest, written in the PEER NGA ``.AT2`` format
(four header lines, then the accelerations in g, five a line). It is synthetic:
nothing is downloaded, and the file in the repository is what this script writes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from chaospound.physics.ground import record, stochastic

G = 9.80665  #: m/s^2
SPEC_SI = {"omega_g": 5.0 * np.pi, "zeta_g": 0.6, "omega_f": 0.5 * np.pi, "zeta_f": 0.6,
           "intensity": 1.0, "dt": 0.01, "duration": 20.0, "seed": 15,
           "envelope": "jennings", "t_rise": 2.0, "t_plateau": 12.0, "decay": 0.2}
PGA_G = 0.35


def main(path: Path | None = None) -> Path:
    """Write the record to ``path`` (default: synthetic.AT2 beside this script)."""
    # the spec is in SI; model_parameters with A_g = 1 m and omega = 1 rad/s is the identity
    t, a, _ = stochastic.generate(stochastic.model_parameters(SPEC_SI, 1.0, 1.0))
    a = record.baseline_rest(t, a * (PGA_G * G / np.max(np.abs(a)))) / G
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD",
             "Synthetic Kanai-Tajimi / Clough-Penzien record, PGA 0.35 g "
             "(docs/examples/make_synthetic_record.py)",
             "ACCELERATION TIME SERIES IN UNITS OF G",
             f"NPTS= {a.size}, DT= {SPEC_SI['dt']:.4f} SEC"]
    lines += ["".join(f"{v:16.7E}" for v in a[i:i + 5]) for i in range(0, a.size, 5)]
    path = Path(__file__).resolve().parent / "synthetic.AT2" if path is None else Path(path)
    path.write_text("\n".join(lines) + "\n")
    print(f"{path}: {a.size} samples, dt {SPEC_SI['dt']} s, PGA {np.max(np.abs(a)):.3f} g")
    return path


if __name__ == "__main__":
    main()
