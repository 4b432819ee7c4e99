"""chaospound: chaotic seismic torsional pounding between two single-storey towers.

The scene API is exported lazily, so that ``import chaospound`` stays light
(no numpy or numba until a name is used).
"""

from __future__ import annotations

import sys
import types

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
        globals()[name] = value
        return value
    raise AttributeError(f"module 'chaospound' has no attribute {name!r}")


class _Package(types.ModuleType):
    """The package, whose exported function ``simulate`` shares its name with the
    submodule ``chaospound.simulate``.

    Importing a submodule binds it as an attribute of its package, so whoever
    imported ``chaospound.simulate`` first used to decide what ``from chaospound
    import simulate`` gave: the function, or the module ("'module' object is not
    callable"). The binding of that submodule is refused, so the name is always
    the function; the module is ``sys.modules["chaospound.simulate"]``, and
    ``from chaospound.simulate import ...`` works as ever.
    """

    def __setattr__(self, name: str, value: object) -> None:
        if name == "simulate" and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
