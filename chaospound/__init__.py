"""chaospound: chaotic seismic torsional pounding between two single-storey towers.

The scene API is exported lazily, so that ``import chaospound`` stays light
(no numpy or numba until a name is used).
"""

from __future__ import annotations

__version__ = "0.1.0"

_SCENE_EXPORTS = (
    "Contact",
    "Excitation",
    "Run",
    "Scene",
    "SceneError",
    "Solver",
    "Tower",
    "list_presets",
    "load_preset",
    "load_scene",
    "save_scene",
)

_OTHER_EXPORTS = {
    "simulate": "chaospound.simulate",
    "open_sweep": "chaospound.store",
    "run_sweep": "chaospound.sweep",
    "lyapunov_spectrum": "chaospound.dynamics.lyapunov",
    "classify": "chaospound.dynamics.classify",
    "custom_system": "chaospound.dynamics.system",
    "evolve": "chaospound.dynamics.system",
    "stroboscopic_section": "chaospound.dynamics.poincare",
    "impact_map": "chaospound.dynamics.impact_map",
    "load_system": "chaospound.userfile",
    "find_orbit": "chaospound.orbits.shooting",
    "continue_branch": "chaospound.orbits.continuation",
    "open_branches": "chaospound.orbits.store",
}

__all__ = ["__version__", *_SCENE_EXPORTS, *_OTHER_EXPORTS]


def __getattr__(name: str) -> object:
    if name in _SCENE_EXPORTS:
        from chaospound import scene

        return getattr(scene, name)
    if name in _OTHER_EXPORTS:
        import importlib

        value = getattr(importlib.import_module(_OTHER_EXPORTS[name]), name)
        # importing chaospound.simulate bound the package attribute "simulate" to the
        # module; the function is the export
        globals()[name] = value
        return value
    raise AttributeError(f"module 'chaospound' has no attribute {name!r}")
