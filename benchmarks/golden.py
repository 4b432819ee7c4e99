"""Bitwise golden record of the engine's results, to compare two commits.

``python benchmarks/golden.py capture OUT.npz`` runs a fixed set of scenes through
every public analysis (every preset with every method, ground "none", sections,
Lyapunov spectra by QR and by two trajectories, the reference oscillators and a
user system) and stores every array it returns. ``python benchmarks/golden.py
compare OLD.npz`` reruns them and reports every key whose bytes differ (exit 1)
or none (exit 0). Run it from the tree to check (``PYTHONPATH=.``).
"""

from __future__ import annotations

import sys

import numpy as np
from numba import njit

from chaospound import load_preset, simulate
from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory, lyapunov_spectrum
from chaospound.dynamics.poincare import stroboscopic_section
from chaospound.dynamics.system import custom_system, duffing, lorenz

PRESETS = ("fig3a", "fig3b", "fig4", "fig4-translational", "fig5", "wall", "tower-wall")
METHODS = ("dopri5", "cash-karp", "rk4", "dop853")


@njit
def _duffing_rhs(t, y, q, out):
    out[0] = y[1]
    out[1] = -q[0] * y[1] - q[1] * y[0] - q[2] * y[0] ** 3 + q[3] * np.cos(q[4] * t)


@njit
def _duffing_jac(t, y, q, jac):
    jac[0, 0] = 0.0
    jac[0, 1] = 1.0
    jac[1, 0] = -q[1] - 3.0 * q[2] * y[0] ** 2
    jac[1, 1] = -q[0]


def _simulation(out: dict, key: str, sim) -> None:
    imp = sim.impacts
    for name in ("time", "phase", "velocity", "corner", "contact_y", "peak_penetration",
                 "peak_force", "duration", "cycle", "state"):
        out[f"{key}/impacts/{name}"] = np.asarray(getattr(imp, name))
    out[f"{key}/strobe"] = np.asarray(sim.strobe.state)
    out[f"{key}/final"] = np.asarray(sim.final_state)
    out[f"{key}/steps"] = np.asarray([sim.stats.steps, sim.stats.rejected,
                                      sim.stats.rhs_evals, sim.stats.events])
    if sim.trajectory is not None:
        out[f"{key}/trajectory"] = np.asarray(sim.trajectory.state)


def capture() -> dict:
    out: dict = {}
    for name in PRESETS:
        scene = load_preset(name)
        for method in METHODS:
            s = scene.with_params(method=method) if method != "dopri5" else scene
            sim = simulate(s, transient=4, record=3, samples_per_cycle=16)
            _simulation(out, f"sim/{name}/{method}", sim)
    scene = load_preset("fig3a").with_params(ground="none")
    state = load_preset("fig3a").initial_vector(load_preset("fig3a").model_id())
    state = state + 0.5
    _simulation(out, "sim/fig3a/none", simulate(scene, transient=0, record=3,
                                                  initial_state=state))
    for name in ("fig3a", "fig4"):
        sec = stroboscopic_section(load_preset(name), transient=5, cycles=10)
        out[f"section/{name}"] = np.asarray(sec.states)
        spec = lyapunov_spectrum(load_preset(name), transient=5, tangent_transient=2,
                                 cycles=20, n_blocks=4)
        out[f"lyap/{name}"] = np.asarray(spec.exponents)
        out[f"lyap/{name}/errors"] = np.asarray(spec.errors)
        two = largest_exponent_two_trajectory(load_preset(name), transient=5, cycles=20,
                                              n_blocks=4)
        out[f"two/{name}"] = np.asarray([two.exponent, two.error])
    for label, system in (("lorenz", lorenz()), ("duffing", duffing())):
        spec = lyapunov_spectrum(system, transient=5, tangent_transient=2, cycles=20,
                                 n_blocks=4)
        out[f"lyap/{label}"] = np.asarray(spec.exponents)
        sec = stroboscopic_section(system, transient=2, cycles=5)
        out[f"section/{label}"] = np.asarray(sec.states)
    user = custom_system(_duffing_rhs, _duffing_jac, period=2 * np.pi,
                         initial_state=(1.0, 0.0), params=(0.05, 0.0, 1.0, 7.5, 1.0),
                         transient=100)
    spec = lyapunov_spectrum(user, transient=5, tangent_transient=2, cycles=20, n_blocks=4)
    out["lyap/user-duffing"] = np.asarray(spec.exponents)
    out["section/user-duffing"] = np.asarray(
        stroboscopic_section(user, transient=2, cycles=5).states)
    return out


def main(argv: list[str]) -> int:
    if len(argv) != 2 or argv[0] not in ("capture", "compare"):
        print(__doc__)
        return 2
    got = capture()
    if argv[0] == "capture":
        np.savez(argv[1], **got)
        print(f"{len(got)} arrays written to {argv[1]}")
        return 0
    ref = np.load(argv[1])
    bad = []
    for key in sorted(set(ref.files) | set(got)):
        if key not in ref.files or key not in got:
            bad.append(f"{key}: only in {'new' if key in got else 'old'}")
            continue
        a, b = ref[key], got[key]
        if a.shape != b.shape or a.tobytes() != b.tobytes():
            diff = (np.nanmax(np.abs(a - b)) if a.shape == b.shape else "shape")
            bad.append(f"{key}: differs (max |diff| {diff})")
    for line in bad:
        print(line)
    print(f"{len(got)} arrays, {len(bad)} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
