"""Scenes: the validated, frozen description of one pounding problem.

A :class:`Scene` holds every physical and numerical parameter of a run of
the two-tower pounding model (docs/model.md sections 3, 6, 9 and 13): two
:class:`Tower` objects, the :class:`Excitation`, the Hertz :class:`Contact`,
the :class:`Solver` settings and the :class:`Run` lengths. Scenes come from
presets (the paper's figures, ``load_preset``), from TOML files
(``load_scene``) or from Python, and are changed through *flat parameter
names* (``Scene.with_params(gap=0.5)``, ``--set gap=0.5`` on the command
line, sweep axes). ``Scene.pack()`` turns a scene into the float64 parameter
vector laid out in :mod:`chaospound.kernels.params`, and ``Scene.model_id()``
picks the smallest exact reduction of the equations of motion.

Units are those of docs/model.md section 2: lengths in units of the ground amplitude A_g,
time multiplied by omega_Ax (tower A's translational circular frequency).

Every validation failure raises :class:`SceneError` (a ``ValueError``) whose
message is one line naming the parameter, its value and the allowed range.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from typing import TYPE_CHECKING

import numpy as np

from chaospound.engine.compose import LAWS
from chaospound.kernels.params import (
    MODEL_NAMES,
    N_PARAMS,
    P_BETA,
    P_CHI,
    P_GAP,
    P_GROUND,
    P_HALF_L,
    P_PERIOD,
    P_PERIOD_RATIO,
    P_PHASE0,
    P_Y_C,
    P_Y_OFF,
    PAIR,
    T_CT,
    T_CX,
    T_CY,
    T_EX,
    T_EY,
    T_KTH,
    T_L,
    T_MU,
    T_MU_RHO2,
    T_OM2,
    T_OMT2,
    T_RHO2,
    T_W,
    TOWER_A,
    TOWER_B,
    TOWER_WALL,
    TOWERS,
    WALL,
)
from chaospound.messages import shorten

if TYPE_CHECKING:
    from importlib.abc import Traversable

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = [
    "Contact",
    "Excitation",
    "PARAMETERS",
    "Run",
    "STATE_INDEX",
    "STATE_NAMES",
    "SHORTHANDS",
    "Scene",
    "SceneError",
    "Solver",
    "Tower",
    "list_presets",
    "load_preset",
    "load_scene",
    "parameter_help",
    "save_scene",
]

# ------------------------------------------------------------- defaults
DEFAULT_LENGTH = 100.0  #: l / A_g (docs/model.md section 13)
DEFAULT_WIDTH_RATIO = 0.55  #: w / l
DEFAULT_ZETA = 0.03  #: every damping ratio
DEFAULT_BETA = 1000.0  #: Hertz stiffness
DEFAULT_CHI = 1.5  #: Hertz exponent
DEFAULT_PERIOD_RATIO = 0.7  #: T / T_Ax
DEFAULT_FREQ_RATIO = 1.5  #: T_Ax / T_Bx
DEFAULT_GAP = 1.0  #: a / A_g
DEFAULT_RTOL = 1e-5  #: chosen by the work-precision study (docs/accuracy.md)
ATOL_PER_RTOL = 1e-3  #: atol = ATOL_PER_RTOL * rtol unless atol is given
PAPER_RTOL = 1e-3  #: Press et al.'s Cash-Karp at 0.1 % error (docs/model.md section 10)
#: largest scene file read: a scene is about 1 kB, a [sweep] list of 10 million values
#: about 100 MB; TOML parses in about 0.1 s per MB
MAX_SCENE_BYTES = 128 * 2**20

GROUNDS = ("sine", "none", "record", "stochastic")
ENVELOPES = ("jennings", "saragoni-hart", "none")  #: a stochastic motion's envelopes
#: the stochastic motion's fields (SI; physics/ground/stochastic.py names them without the
#: ``ground_`` prefix): docs/ground_motions.md section 6
STOCHASTIC_FIELDS = ("ground_seed", "ground_duration", "ground_omega_g", "ground_zeta_g",
                     "ground_omega_f", "ground_zeta_f", "ground_intensity", "ground_pga",
                     "ground_envelope", "ground_t_rise", "ground_t_plateau", "ground_decay",
                     "ground_sh_b", "ground_sh_c", "ground_components")
#: the sine's y component (u_gy = y_ratio sin(t/r + y_phase)): docs/ground_motions.md 2
SINE_Y_FIELDS = ("ground_y_ratio", "ground_y_phase")
STANDARD_GRAVITY = 9.80665  #: g [m/s^2]
DEFAULT_STOCHASTIC_DT = 0.01  #: sample interval [s] of a stochastic motion
RECORD_UNITS = ("auto", "g", "m/s^2", "cm/s^2")  #: accelerogram units ("auto": the file's, else g)
CONTACT_LAWS = tuple(LAWS)  #: the contact laws (chaospound/physics/contact/, one module each)
DAMPING_VARIANTS = ("lankarani-nikravesh", "ye")  #: hertzdamp's damping formulas
DEFAULT_RESTITUTION = 0.65  #: concrete on concrete, about 0.5-0.7
OPPONENTS = ("tower", "wall")
TORSION_DAMPINGS = ("consistent", "as-printed")
METHODS = ("dopri5", "cash-karp", "rk4", "dop853")
METHOD_ALIASES = ("paper",)  #: "paper" = cash-karp at rtol 1e-3
MODELS = ("auto",) + MODEL_NAMES

# ----------------------------------------------------------- state layout
#: names of the 12 states, in the paper's order
FULL_STATE = (
    "X_A", "dX_A", "Y_A", "dY_A", "th_A", "dth_A",
    "X_B", "dX_B", "Y_B", "dY_B", "th_B", "dth_B",
)  # fmt: skip
#: model id -> indices of its states in the 12-state vector
STATE_INDEX: dict[int, tuple[int, ...]] = {
    WALL: (0, 1),
    TOWER_WALL: (0, 1, 2, 3, 4, 5),
    PAIR: (0, 1, 6, 7),
    TOWERS: tuple(range(12)),
}
#: model id -> names of its states
STATE_NAMES: dict[int, tuple[str, ...]] = {
    model: tuple(FULL_STATE[i] for i in index) for model, index in STATE_INDEX.items()
}
#: initial states that must vanish for tower A (B) to stay translational
_LATERAL_A = (2, 3, 4, 5)
_LATERAL_B = (8, 9, 10, 11)


# ================================================================ errors
class SceneError(ValueError):
    """An invalid scene parameter; the message is one line.

    Parameters
    ----------
    message : str
        Names the parameter, its value and the allowed range.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


def _law_module(law: str):
    """A contact law's module and the keyword inputs its ``block`` takes (``beta``,
    ``chi``, ``k``, ``m_eff``, ``variant``, ``no_pull``: :meth:`Scene.law_block`)."""
    import importlib
    import inspect

    module = importlib.import_module(LAWS[law])
    return module, inspect.signature(module.block).parameters


def _law_reads(law: str) -> dict[str, bool]:
    """Which of the contact inputs beside ``beta`` (read by every law) a law reads:
    what its module's ``block`` takes (``chi``, ``variant`` for ``damping_variant``,
    ``no_pull``), and ``restitution`` where it is dissipative."""
    module, accepted = _law_module(law)
    return {"chi": "chi" in accepted, "restitution": bool(module.DISSIPATIVE),
            "damping_variant": "variant" in accepted, "no_pull": "no_pull" in accepted}


def laws_reading(name: str) -> tuple[str, ...]:
    """The contact laws that read the contact input ``name`` (all of them for ``beta``
    and any other parameter)."""
    return tuple(law for law in LAWS if _law_reads(law).get(name, True))


def not_read_message(law: str, name: str) -> str:
    """Why a contact input ``name`` has no effect under ``law``, and which laws read it."""
    return (f"the {law} contact law does not read {name} (read by "
            f"{', '.join(laws_reading(name))}: set contact_law; docs/contact_laws.md)")


# ===================================================== parameter specs
@dataclass(frozen=True)
class _Spec:
    """How one flat parameter is parsed and checked."""

    kind: str  # "float", "int", "bool" or "choice"
    meaning: str
    low: float | None = None  # lower bound
    low_open: bool = False  # True: value > low, False: value >= low
    high: float | None = None  # exclusive upper bound
    choices: tuple[str, ...] = ()
    optional: bool = False  # None ("auto") allowed: a derived default

    def requirement(self) -> str:
        """The allowed range as text, e.g. ``must be >= 0``."""
        if self.kind == "choice":
            return "must be one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind == "bool":
            return "must be true or false (or yes/no, 1/0)"
        if self.kind == "path":
            return "must be a file path"
        if self.low is not None and self.high is not None:
            if self.kind == "int":  # the integers of [low, high), listed
                values = [f"{v:g}" for v in range(math.ceil(self.low), math.ceil(self.high))]
                return "must be " + (", ".join(values[:-1]) + " or " + values[-1]
                                     if 1 < len(values) <= 4 else
                                     f"an integer in [{self.low:g}, {self.high:g})")
            return f"must be in {'(' if self.low_open else '['}{self.low:g}, {self.high:g})"
        if self.low is not None:
            op = ">" if self.low_open else ">="
            kind = "an integer " if self.kind == "int" else ""
            return f"must be {kind}{op} {self.low:g}"
        return "must be finite"


def _pos(meaning: str, optional: bool = False) -> _Spec:
    return _Spec("float", meaning, low=0.0, low_open=True, optional=optional)


def _nonneg(meaning: str) -> _Spec:
    return _Spec("float", meaning, low=0.0)


def _real(meaning: str) -> _Spec:
    return _Spec("float", meaning)


_GLOBAL_SPECS: dict[str, _Spec] = {
    "period_ratio": _pos("excitation period over tower A's, T/T_Ax"),
    "ground": _Spec("choice", "ground motion: u_g = sin(t/r), none, a recorded accelerogram, "
                    "or filtered white noise (stochastic)", choices=GROUNDS),
    "ground_file": _Spec("path", "accelerogram file (.AT2 or text: time, acceleration)",
                         optional=True),
    "ground_units": _Spec("choice", "units of the accelerogram ('auto': the file's, else g)",
                          choices=RECORD_UNITS),
    "ground_scale": _Spec("float", "factor on the recorded accelerations"),
    "ground_dt": _pos("sample interval [s] of a text record without a time column, or of a "
                      "stochastic motion (auto: 0.01 s)", True),
    "ground_seed": _Spec("int", "stochastic: seed of the white noise (same seed, same bits)",
                         low=0.0),
    "ground_duration": _pos("stochastic: length of the motion [s]"),
    "ground_omega_g": _pos("stochastic: Kanai-Tajimi ground frequency omega_g [rad/s]"),
    "ground_zeta_g": _pos("stochastic: Kanai-Tajimi ground damping ratio zeta_g"),
    "ground_omega_f": _pos("stochastic: Clough-Penzien high-pass frequency omega_f [rad/s]"),
    "ground_zeta_f": _pos("stochastic: Clough-Penzien high-pass damping ratio zeta_f"),
    "ground_intensity": _pos("stochastic: two-sided white-noise density S0 [m^2/s^3] "
                             "(give it or ground_pga)", True),
    "ground_pga": _pos("stochastic: peak ground acceleration [g] the realisation is scaled "
                       "to (give it or ground_intensity)", True),
    "ground_envelope": _Spec("choice", "stochastic: envelope (Jennings et al. 1968, "
                             "Saragoni & Hart 1974, or stationary)", choices=ENVELOPES),
    "ground_t_rise": _nonneg("stochastic, jennings: end of the quadratic rise [s]"),
    "ground_t_plateau": _nonneg("stochastic, jennings: end of the strong phase [s]"),
    "ground_decay": _pos("stochastic, jennings: decay rate of the tail [1/s]"),
    "ground_sh_b": _pos("stochastic, saragoni-hart: exponent b of t^b exp(-c t)"),
    "ground_sh_c": _pos("stochastic, saragoni-hart: rate c of t^b exp(-c t) [1/s]"),
    "ground_components": _Spec("int", "stochastic: 1 (x) or 2 (independent x and y) "
                               "components", low=1.0, high=3.0),
    "ground_y_ratio": _real("sine: amplitude of the y component over the x one, "
                            "u_gy = y_ratio sin(t/r + y_phase) (Gong & Hao 2005; 0: x only)"),
    "ground_y_phase": _real("sine: phase lead of the y component over the x one [rad]"),
    "length_unit": _pos("A_g in metres: the model's length unit, for a record", True),
    "tower_period": _pos("T_Ax in seconds: tower A's x period, for a record", True),
    "tower_mass": _pos("m_A in kilograms: tower A's mass, the force unit of --units si", True),
    "freq_ratio": _pos("frequency ratio Om = T_Ax/T_Bx = omega_Bx/omega_Ax"),
    "mass_ratio": _pos("mass ratio m = m_A/m_B; 'auto': freq_ratio**2", optional=True),
    "gap": _nonneg("clear gap at rest, in units of A_g"),
    "offset_y": _real("y of B's stiffness centre minus A's, in units of A_g"),
    "opponent": _Spec("choice", "what tower A pounds against", choices=OPPONENTS),
    "torsion_damping": _Spec(
        "choice", "torsional damping uses Om_ti or, as printed, Om_i", choices=TORSION_DAMPINGS
    ),
    "beta": _pos("Hertz contact stiffness, F = beta d^chi (the linear laws' k)"),
    "chi": _Spec("float", "Hertz contact exponent; the force must be C1", low=1.0),
    "contact_law": _Spec("choice", "contact law (docs/contact_laws.md)", choices=CONTACT_LAWS),
    "restitution": _pos("coefficient of restitution e of the dissipative laws, 0 < e <= 1"),
    "damping_variant": _Spec("choice", "hertzdamp's damping: Lankarani-Nikravesh or Ye et al.",
                             choices=DAMPING_VARIANTS),
    "no_pull": _Spec("bool", "kelvin-voigt: no tensile force (contact ends when F reaches 0)"),
}
_TOWER_SPECS: dict[str, _Spec] = {
    "length": _pos("plan length along the gap line (y), in units of A_g"),
    "width": _pos("plan width across the gap (x), in units of A_g"),
    "width_ratio": _pos("plan width over plan length, w/l"),
    "ecc_x": _real("x eccentricity, centre of mass minus stiffness centre, in units of A_g"),
    "ecc_x_ratio": _real("x eccentricity over plan length, e_x/l"),
    "ecc_y": _real("y eccentricity, centre of mass minus stiffness centre, in units of A_g"),
    "ecc_y_ratio": _real("y eccentricity over plan length, e_y/l"),
    "gyration": _pos("radius of gyration about the CM; 'auto': sqrt((l^2+w^2)/12)", True),
    "zeta_x": _nonneg("damping ratio in x"),
    "zeta_y": _nonneg("damping ratio in y"),
    "zeta_t": _nonneg("torsional damping ratio"),
}
_SOLVER_SPECS: dict[str, _Spec] = {
    "method": _Spec(
        "choice",
        "Runge-Kutta scheme; 'paper': cash-karp at rtol 1e-3",
        choices=METHODS + METHOD_ALIASES,
    ),
    "rtol": _Spec("float", "relative tolerance of the adaptive step", low=0.0, low_open=True,
                  high=1.0),
    "atol": _pos("absolute tolerance of the adaptive step"),
    "steps_per_cycle": _Spec("int", "fixed rk4 steps per excitation period", low=4),
    "max_steps": _Spec("int", "step budget of one integration", low=1),
    "restart_at_kinks": _Spec("bool", "end steps where a face end's penetration crosses 0"),
    "model": _Spec("choice", "reduction of the equations of motion", choices=MODELS),
}
_RUN_SPECS: dict[str, _Spec] = {
    "transient": _Spec("int", "excitation cycles discarded before recording", low=0),
    "record": _Spec("int", "excitation cycles recorded", low=1),
    "phase": _Spec("float", "stroboscopic section phase, a fraction of the period", 0.0, high=1.0),
}

_TOWER_FORMS = {  # quantity -> (absolute name, ratio-to-length name)
    "width": ("width", "width_ratio"),
    "ecc_x": ("ecc_x", "ecc_x_ratio"),
    "ecc_y": ("ecc_y", "ecc_y_ratio"),
}
_PARTNER = {n: pair[1 - i] for pair in _TOWER_FORMS.values() for i, n in enumerate(pair)}
_ZETAS = ("zeta_x", "zeta_y", "zeta_t")
_SUFFIXES = ("_A", "_B")

#: flat parameter name -> (component, field); component "scene" is the Scene itself
_TARGET: dict[str, tuple[str, str]] = {
    **{n: ("excitation", n) for n in ("period_ratio", "ground", "ground_file", "ground_units",
                                      "ground_scale", "ground_dt", "length_unit",
                                      "tower_period", "tower_mass", *STOCHASTIC_FIELDS,
                                      *SINE_Y_FIELDS)},
    **{
        n: ("scene", n)
        for n in ("freq_ratio", "mass_ratio", "gap", "offset_y", "opponent", "torsion_damping")
    },
    "beta": ("contact", "beta"),
    "chi": ("contact", "chi"),
    **{n: ("contact", n) for n in ("contact_law", "restitution", "damping_variant", "no_pull")},
    **{f"{n}{s}": (f"tower{s}", n) for s in _SUFFIXES for n in _TOWER_SPECS},
    **{n: ("solver", n) for n in _SOLVER_SPECS},
    **{n: ("run", n) for n in _RUN_SPECS},
}
#: every flat parameter name, in a stable order
PARAMETERS: tuple[str, ...] = tuple(_TARGET)
#: shorthand -> flat names it sets (a tower name without suffix sets both towers)
SHORTHANDS: dict[str, tuple[str, ...]] = {
    **{n: (f"{n}_A", f"{n}_B") for n in _TOWER_SPECS},
    "zeta": tuple(f"{z}{s}" for s in _SUFFIXES for z in _ZETAS),
}


def _spec(name: str) -> _Spec:
    """Spec of a flat or bare (tower, no suffix) parameter name."""
    for table in (_GLOBAL_SPECS, _SOLVER_SPECS, _RUN_SPECS, _TOWER_SPECS):
        if name in table:
            return table[name]
    if name[-2:] in _SUFFIXES and name[:-2] in _TOWER_SPECS:
        return _TOWER_SPECS[name[:-2]]
    raise _unknown(name)


def parameter_help() -> dict[str, str]:
    """Meaning and allowed range of every flat parameter and shorthand.

    Returns
    -------
    dict
        ``{name: "meaning; must be ..."}`` for :data:`PARAMETERS` then
        :data:`SHORTHANDS`.
    """
    out = {name: _describe(name) for name in PARAMETERS}
    for short, names in SHORTHANDS.items():
        out[short] = "sets " + ", ".join(names)
    return out


def _describe(name: str) -> str:
    spec = _spec(name)
    return f"{spec.meaning}; {spec.requirement()}"


# ------------------------------------------------------------- coercion
_TRUE = ("true", "yes", "1", "on")
_FALSE = ("false", "no", "0", "off")
_AUTO = ("auto", "none", "default")


def _show(value: object) -> str:
    """A value as it appears in an error message."""
    if isinstance(value, float | np.floating):
        return repr(float(value))
    if isinstance(value, str):
        return shorten(value, quote=True)
    if isinstance(value, int) and value.bit_length() > 64:  # repr: 4300 digits at most
        return f"an integer of {value.bit_length()} bits"
    try:
        text = repr(value)
    except (ValueError, RecursionError):  # a huge integer inside a list, deep nesting
        return f"a {type(value).__name__}"
    return text if len(text) <= 60 else text[:57] + "..."


def _bad(name: str, value: object, spec: _Spec, requirement: str | None = None) -> SceneError:
    req = requirement or spec.requirement()
    return SceneError(f"{name} = {_show(value)}: {req} ({spec.meaning})")


def _coerce(name: str, value: object, shown: str | None = None) -> object:
    """Parse and check one parameter value.

    Parameters
    ----------
    name : str
        Flat or bare parameter name (selects the spec).
    value : object
        Python value, or text from the command line.
    shown : str, optional
        Name used in the error message (defaults to ``name``).

    Returns
    -------
    float, int, bool, str or None
        The normalised value.
    """
    spec = _spec(name)
    shown = shown or name
    if spec.optional and (
        value is None or (isinstance(value, str) and value.strip().lower() in _AUTO)
    ):
        return None
    parse = {"float": _as_float, "int": _as_int, "bool": _as_bool, "choice": _as_choice,
             "path": _as_path}
    return parse[spec.kind](shown, value, spec)


def _as_float(name: str, value: object, spec: _Spec) -> float:
    number = _number(name, value, spec)
    if not math.isfinite(number):
        raise _bad(name, number, spec, "must be finite")
    _check_range(name, number, spec)
    return number


def _number(name: str, value: object, spec: _Spec) -> float:
    if isinstance(value, bool | np.bool_):
        raise _bad(name, value, spec, "must be a number")
    if isinstance(value, int | float | np.integer | np.floating):
        try:
            return float(value)
        except OverflowError:  # an integer beyond float64 (TOML has no size limit)
            raise _bad(name, value, spec, "must be finite") from None
    if isinstance(value, str):
        try:
            return float(value.strip())
        except ValueError:
            pass
    raise _bad(name, value, spec, "must be a number")


def _as_int(name: str, value: object, spec: _Spec) -> int:
    if isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_):
        number = int(value)
        _number(name, number, spec)  # raises beyond float64: the kernels take floats
    else:
        real = _number(name, value, spec)
        if not (math.isfinite(real) and real.is_integer()):
            raise _bad(name, value, spec, "must be an integer")
        number = int(real)
    _check_range(name, number, spec)
    return number


def _check_range(name: str, number: float, spec: _Spec) -> None:
    too_low = spec.low is not None and (number <= spec.low if spec.low_open else number < spec.low)
    too_high = spec.high is not None and number >= spec.high
    if too_low or too_high:
        raise _bad(name, number, spec)


def _as_bool(name: str, value: object, spec: _Spec) -> bool:
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, int) and value in (0, 1):
        return bool(value)
    if isinstance(value, str):
        word = value.strip().lower()
        if word in _TRUE:
            return True
        if word in _FALSE:
            return False
    raise _bad(name, value, spec)


def _as_path(name: str, value: object, spec: _Spec) -> str:
    if isinstance(value, str | os.PathLike) and str(value).strip():
        text = str(value).strip()
        if len(text) <= 4096 and "\0" not in text:
            return text
    raise _bad(name, value, spec, "must be a file path")


def _as_choice(name: str, value: object, spec: _Spec) -> str:
    if isinstance(value, str):
        word = value.strip().lower().replace("_", "-")
        if word in spec.choices:
            return word
    raise _bad(name, value, spec)


KNOWN_LISTED_CHARS = 300  #: an unknown name's error lists the known ones up to this length


def _unknown(
    name: str, known: Iterable[str] | None = None, what: str = "parameter", listing: bool = False
) -> SceneError:
    """Error for an unknown name, with the nearest known names as hints.

    ``listing``: always list the known names (else only when none is close).
    """
    known = list(known) if known is not None else list(PARAMETERS) + list(SHORTHANDS)
    close = difflib.get_close_matches(str(name), known, n=3, cutoff=0.6)
    hints = ["did you mean " + " or ".join(repr(c) for c in close) + "?"] if close else []
    if listing or not close:
        listed = ", ".join(known)
        if listing or len(listed) <= KNOWN_LISTED_CHARS:
            hints.append("known: " + listed)
        else:  # every scene parameter: a line of 1000 characters nobody reads
            hints.append("'chaospound params' lists them all")
    return SceneError(f"unknown {what} {shorten(name, quote=True)} ({'; '.join(hints)})")


# ============================================================ components
@dataclass(frozen=True)
class Tower:
    """One single-storey tower: a rigid slab on four identical corner columns.

    Width and eccentricities are stored in the form they were given:
    absolutely (``width``, ``ecc_x``, ``ecc_y``, in units of A_g) or relative
    to the length (``width_ratio`` = w/l, ``ecc_x_ratio``, ``ecc_y_ratio``),
    so that relative ones follow ``length`` when it changes. After
    construction exactly one form of each quantity is set, the other is
    ``None``; read the resolved values from :attr:`w`, :attr:`e_x`,
    :attr:`e_y` and :attr:`rho`.

    Parameters
    ----------
    length : float
        l, plan dimension along the gap line (y), > 0. Default 100.
    width : float, optional
        w, plan dimension across the gap (x), > 0.
    ecc_x, ecc_y : float, optional
        e = centre of mass minus stiffness centre (global axes).
    gyration : float, optional
        rho, radius of gyration about the CM, > 0; ``None``:
        sqrt((l^2 + w^2)/12), the uniform slab (follows l and w).
    zeta_x, zeta_y, zeta_t : float
        Damping ratios in x, y and torsion, >= 0. Default 0.03.
    width_ratio : float, optional
        w/l; the default when neither width form is given is 0.55.
    ecc_x_ratio, ecc_y_ratio : float, optional
        e_x/l and e_y/l; the default when neither form is given is e = 0
        (stored as the absolute form).
    """

    length: float = DEFAULT_LENGTH
    width: float | None = None
    ecc_x: float | None = None
    ecc_y: float | None = None
    gyration: float | None = None
    zeta_x: float = DEFAULT_ZETA
    zeta_y: float = DEFAULT_ZETA
    zeta_t: float = DEFAULT_ZETA
    width_ratio: float | None = None
    ecc_x_ratio: float | None = None
    ecc_y_ratio: float | None = None

    def __post_init__(self) -> None:
        for name, value in _normalise_tower(_fields(self), "").items():
            object.__setattr__(self, name, value)

    @property
    def w(self) -> float:
        """Resolved plan width w (x), in units of A_g."""
        return self.width if self.width is not None else self.width_ratio * self.length

    @property
    def e_x(self) -> float:
        """Resolved eccentricity e_x, in units of A_g."""
        return self.ecc_x if self.ecc_x is not None else self.ecc_x_ratio * self.length

    @property
    def e_y(self) -> float:
        """Resolved eccentricity e_y, in units of A_g."""
        return self.ecc_y if self.ecc_y is not None else self.ecc_y_ratio * self.length

    @property
    def rho2(self) -> float:
        """Squared radius of gyration about the CM, rho^2, in units of A_g^2."""
        if self.gyration is not None:
            return self.gyration**2
        return (self.length**2 + self.w**2) / 12.0

    @property
    def rho(self) -> float:
        """Resolved radius of gyration rho, in units of A_g."""
        return self.gyration if self.gyration is not None else math.sqrt(self.rho2)

    def torsion_frequency2(self, om: float) -> float:
        """Uncoupled torsional frequency squared, Om_t^2 (docs/model.md section 4).

        Parameters
        ----------
        om : float
            The tower's translational frequency Om_i (1 for A, Om for B),
            in units of omega_Ax.

        Returns
        -------
        float
            Om_t^2 = Om_i^2 (l^2 + w^2 + 4 |e|^2) / (4 rho^2).
        """
        arm2 = self.length**2 + self.w**2 + 4.0 * (self.e_x**2 + self.e_y**2)
        return om**2 * arm2 / (4.0 * self.rho2)


def _fields(obj: object) -> dict[str, object]:
    """Shallow field dict of a dataclass instance."""
    return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}


def _normalise_tower(fields: Mapping[str, object], suffix: str) -> dict[str, object]:
    """Check a tower's fields; error names carry ``suffix`` (``_A``, ``_B``)."""
    out: dict[str, object] = {"length": _coerce("length", fields["length"], "length" + suffix)}
    for quantity, (absolute, ratio) in _TOWER_FORMS.items():
        given = {n: fields[n] for n in (absolute, ratio) if fields[n] is not None}
        if len(given) == 2:
            raise _both_forms(absolute + suffix, ratio + suffix, "length" + suffix)
        if not given:
            given = {ratio: DEFAULT_WIDTH_RATIO} if quantity == "width" else {absolute: 0.0}
        out[absolute] = out[ratio] = None
        for name, value in given.items():
            out[name] = _coerce(name, value, name + suffix)
    for name in ("gyration",) + _ZETAS:
        out[name] = _coerce(name, fields[name], name + suffix)
    return out


def _both_forms(absolute: str, ratio: str, length: str) -> SceneError:
    return SceneError(
        f"{absolute} and {ratio} both given: give the value absolutely or relative "
        f"to {length}, not both"
    )


def _make_tower(fields: Mapping[str, object], suffix: str) -> Tower:
    """Build a Tower, naming its parameters with ``suffix`` in errors."""
    return Tower(**_normalise_tower(fields, suffix))


@dataclass(frozen=True)
class Excitation:
    """The ground motion (docs/ground_motions.md), normalised by A_g and omega_Ax.

    Parameters
    ----------
    period_ratio : float
        r = T / T_Ax, > 0: the harmonic motion u_g(t) = sin(t / r) has period
        T = 2 pi r, the interval of the stroboscopic sections; with a record the
        sections keep that interval (transient and record windows count it).
    ground : {"sine", "none", "record"}
        "none": u_g = 0 (free, and with zero damping conservative, motion);
        "record": the accelerogram ``ground_file``, integrated exactly.
    ground_file : str, optional
        The accelerogram: a PEER ``.AT2`` or a text file of (time [s],
        acceleration) rows, or one acceleration column with ``ground_dt``.
    ground_units : {"auto", "g", "m/s^2", "cm/s^2"}
        Units of its accelerations ("auto": the .AT2 header's, else g).
    ground_scale : float
        Factor on the accelerations (incremental dynamic analysis).
    ground_dt : float, optional
        Sample interval [s] of a text file without a time column.
    length_unit, tower_period : float, optional
        A_g [m] and T_Ax [s]: the physical length and time of the model's
        units, which convert a record or a stochastic motion to them (required
        with either). With ``tower_mass`` m_A [kg] they are the scene's physical
        units (docs/units.md): ``--units si`` reports in m/s, kN and mm.
    tower_mass : float, optional
        m_A [kg]: with ``length_unit`` and ``tower_period``, the force unit
        A_g K_Ax = A_g m_A omega_Ax^2 (not used by the dynamics).
    ground_seed, ground_duration, ground_omega_g, ground_zeta_g, ground_omega_f,
    ground_zeta_f, ground_intensity, ground_pga, ground_envelope, ground_t_rise,
    ground_t_plateau, ground_decay, ground_sh_b, ground_sh_c, ground_components
        The stochastic motion (``ground = "stochastic"``, docs/ground_motions.md
        section 5), in SI: seed, duration [s], Kanai-Tajimi omega_g [rad/s] and
        zeta_g, Clough-Penzien omega_f [rad/s] and zeta_f, either the white-noise
        density S0 [m^2/s^3] or a peak ground acceleration [g] the realisation is
        scaled to, the envelope ("jennings": t_rise [s], t_plateau [s], decay
        [1/s]; "saragoni-hart": b, c [1/s]; "none") and 1 or 2 components.
        ``ground_dt`` [s] is the sample interval (default 0.01 s), ``ground_scale``
        a factor on the accelerations.
    ground_y_ratio, ground_y_phase : float
        The sine's y component ``u_gy = y_ratio sin(t / r + y_phase)`` (the
        bi-directional harmonic input of Gong & Hao 2005): its amplitude over
        the x one and its phase lead [rad]. 0 (the default): x only. Only with
        ``ground = "sine"``.
    """

    period_ratio: float = DEFAULT_PERIOD_RATIO
    ground: str = "sine"
    ground_file: str | None = None
    ground_units: str = "auto"
    ground_scale: float = 1.0
    ground_dt: float | None = None
    length_unit: float | None = None
    tower_period: float | None = None
    tower_mass: float | None = None
    ground_seed: int = 0
    ground_duration: float = 20.0
    ground_omega_g: float = 15.6
    ground_zeta_g: float = 0.6
    ground_omega_f: float = 1.5
    ground_zeta_f: float = 0.6
    ground_intensity: float | None = None
    ground_pga: float | None = None
    ground_envelope: str = "jennings"
    ground_t_rise: float = 2.0
    ground_t_plateau: float = 10.0
    ground_decay: float = 0.3
    ground_sh_b: float = 2.0
    ground_sh_c: float = 0.5
    ground_components: int = 1
    ground_y_ratio: float = 0.0
    ground_y_phase: float = 0.0

    def __post_init__(self) -> None:
        _check_fields(self, _GLOBAL_SPECS)
        if self.ground_y_ratio != 0.0 and self.ground != "sine":
            raise SceneError(f"ground_y_ratio = {self.ground_y_ratio:g}: a y component of "
                             f"the sine only, not of ground = {self.ground} (a record's or a "
                             "stochastic motion's second component is its own)")
        if self.ground == "record":
            missing = [n for n in ("ground_file", "length_unit", "tower_period")
                       if getattr(self, n) is None]
            if missing:
                raise SceneError(f"ground = record needs {', '.join(missing)} "
                                 "(the file and the model's length and time units)")
        if self.ground == "stochastic":
            self._check_stochastic()

    def _check_stochastic(self) -> None:
        missing = [n for n in ("length_unit", "tower_period") if getattr(self, n) is None]
        if missing:
            raise SceneError(f"ground = stochastic needs {', '.join(missing)} (the model's "
                             "length and time units: the motion is given in SI)")
        if (self.ground_intensity is None) == (self.ground_pga is None):
            raise SceneError("ground = stochastic needs exactly one of ground_intensity "
                             "(S0 [m^2/s^3]) and ground_pga (peak acceleration [g])")
        dt = self.stochastic_dt
        if not self.ground_duration >= dt:
            raise SceneError(f"ground_duration = {self.ground_duration:g} s: must cover at "
                             f"least one sample interval (ground_dt = {dt:g} s)")
        if self.ground_envelope == "jennings" and self.ground_t_plateau < self.ground_t_rise:
            raise SceneError(f"ground_t_plateau = {self.ground_t_plateau:g} s: must be >= "
                             f"ground_t_rise = {self.ground_t_rise:g} s")
        if self.ground_seed >= 2**63:
            raise SceneError(f"ground_seed = {self.ground_seed}: must be < 2**63")

    @property
    def stochastic_dt(self) -> float:
        """Sample interval [s] of a stochastic motion (``ground_dt``, default 0.01 s)."""
        return DEFAULT_STOCHASTIC_DT if self.ground_dt is None else self.ground_dt

    def stochastic_spec(self) -> dict:
        """The spec of :mod:`chaospound.physics.ground.stochastic` in model units.

        The SI fields converted with A_g = ``length_unit`` and omega_Ax =
        2 pi / ``tower_period`` (``stochastic.model_parameters``). With
        ``ground_pga`` the density is a nominal 1 m^2/s^3 (the realisation is
        rescaled afterwards, :meth:`stochastic_block`).
        """
        from chaospound.physics.ground import stochastic

        envelope = {"jennings": {"t_rise": self.ground_t_rise, "t_plateau": self.ground_t_plateau,
                                 "decay": self.ground_decay},
                    "saragoni-hart": {"b": self.ground_sh_b, "c": self.ground_sh_c},
                    "none": {}}[self.ground_envelope]
        si = {"omega_g": self.ground_omega_g, "zeta_g": self.ground_zeta_g,
              "omega_f": self.ground_omega_f, "zeta_f": self.ground_zeta_f,
              "intensity": self.ground_intensity if self.ground_pga is None else 1.0,
              "dt": self.stochastic_dt, "duration": self.ground_duration,
              "seed": self.ground_seed, "envelope": self.ground_envelope,
              "components": self.ground_components, **envelope}
        return stochastic.model_parameters(si, self.length_unit, 2.0 * math.pi / self.tower_period)

    def stochastic_block(self) -> np.ndarray:
        """The block of the stochastic motion: one realisation, in model units.

        ``stochastic.generate`` (seeded: the same fields give the same bits), the
        accelerations multiplied by ``ground_scale`` and, with ``ground_pga``, by the
        factor that makes the peak of |u_g''| of x (before the baseline correction)
        that PGA (y keeps its ratio to x); then the record's baseline correction and
        exact integration (``record.block_from_samples``).
        """
        from chaospound.physics.ground import record, stochastic

        t, a_x, a_y = stochastic.generate(self.stochastic_spec())
        factor = self.ground_scale
        if self.ground_pga is not None:
            omega = 2.0 * math.pi / self.tower_period
            target = self.ground_pga * STANDARD_GRAVITY / (self.length_unit * omega**2)
            factor *= target / float(np.max(np.abs(a_x)))
        a_y = None if a_y is None else a_y * factor
        return record.block_from_samples(t, a_x * factor, a_y)

    def ground_block(self) -> np.ndarray | None:
        """The block a record, a stochastic motion or a sine with a y component
        appends to the packed vector (None: the x-only sine's block is the scene's
        ``P_PERIOD_RATIO`` slot, and "none" has none)."""
        if self.ground == "record":
            return self.record_block()
        if self.ground == "stochastic":
            return self.stochastic_block()
        if self.ground == "sine" and self.ground_y_ratio != 0.0:
            from chaospound.physics.ground import sine

            return sine.block({"period_ratio": self.period_ratio, "y_ratio": self.ground_y_ratio,
                               "y_phase": self.ground_y_phase})
        return None

    @property
    def has_y(self) -> bool:
        """Whether the motion has a y component, which then drives the towers' Y.

        The sine with ``ground_y_ratio != 0``, a stochastic motion with
        ``ground_components = 2``, a record whose file holds two components
        (read once per Excitation).
        """
        if self.ground == "sine":
            return self.ground_y_ratio != 0.0
        if self.ground == "stochastic":
            return self.ground_components == 2
        if self.ground == "record":
            known = self.__dict__.get("_record_components")
            if known is None:
                known = int(self.record_block()[1])
                object.__setattr__(self, "_record_components", known)
            return known == 2
        return False

    def record_block(self) -> np.ndarray:
        """The block of a recorded ground motion (its samples in model units)."""
        from chaospound.physics.ground import record

        spec = {"file": self.ground_file, "scale": self.ground_scale,
                "length_scale": self.length_unit, "omega": 2.0 * math.pi / self.tower_period}
        if self.ground_units != "auto":
            spec["units"] = self.ground_units
        if self.ground_dt is not None:
            spec["dt"] = self.ground_dt
        try:
            return record.block(spec)
        except (ValueError, OSError) as exc:
            raise SceneError(shorten(str(exc), 200)) from None


@dataclass(frozen=True)
class Contact:
    """The contact law along the faces' line contact (docs/contact_laws.md).

    Parameters
    ----------
    beta : float
        Contact stiffness, > 0: Hertz's beta of F = beta d^chi, in units of
        k_Ax A_g^(1 - chi); the linear laws' k (chi is then not used).
    chi : float
        Contact exponent, >= 1 (the force is then continuous).
    contact_law : str
        One of :data:`CONTACT_LAWS`: "hertz" (elastic, the paper's), "linear",
        "kelvin-voigt", "hertzdamp", "hunt-crossley", "jankowski".
    restitution : float
        Coefficient of restitution e, 0 < e <= 1, from which the dissipative
        laws' damping follows (not used by the elastic laws).
    damping_variant : str
        hertzdamp's formula for its damping: "lankarani-nikravesh" or "ye".
    no_pull : bool
        kelvin-voigt: clip the force at 0 (no pulling near separation).
    """

    beta: float = DEFAULT_BETA
    chi: float = DEFAULT_CHI
    contact_law: str = "hertz"
    restitution: float = DEFAULT_RESTITUTION
    damping_variant: str = "lankarani-nikravesh"
    no_pull: bool = False

    def __post_init__(self) -> None:
        _check_fields(self, _GLOBAL_SPECS)
        if not self.restitution <= 1.0:
            raise SceneError(f"restitution = {self.restitution:g}: must be in (0, 1]")


@dataclass(frozen=True)
class Solver:
    """Numerical integration settings.

    Parameters
    ----------
    method : {"dopri5", "cash-karp", "rk4", "dop853", "paper"}
        Runge-Kutta scheme. "paper" is stored as "cash-karp" with rtol 1e-3
        unless rtol is given.
    rtol, atol : float
        Tolerances of the adaptive schemes, > 0. Default rtol 1e-5 (the
        work-precision study, docs/accuracy.md); atol defaults to 1e-3 rtol and
        follows rtol when rtol is changed, unless atol itself was given.
    steps_per_cycle : int
        Fixed steps per excitation period for "rk4", >= 4. Default 400.
    max_steps : int
        Step budget of one integration, >= 1.
    restart_at_kinks : bool
        End steps exactly where a face end's penetration crosses 0.
    model : {"auto", "wall", "tower-wall", "pair", "towers"}
        Reduction of the equations of motion; "auto" picks the smallest
        exact one (docs/model.md section 9).
    """

    method: str = "dopri5"
    rtol: float | None = None
    atol: float | None = None
    steps_per_cycle: int = 400
    max_steps: int = 20_000_000
    restart_at_kinks: bool = True
    model: str = "auto"

    def __post_init__(self) -> None:
        method = _coerce("method", self.method)
        default_rtol = PAPER_RTOL if method == "paper" else DEFAULT_RTOL
        object.__setattr__(self, "method", "cash-karp" if method == "paper" else method)
        if self.rtol is None:
            object.__setattr__(self, "rtol", default_rtol)
        auto = self.atol is None
        if auto:
            object.__setattr__(self, "atol", ATOL_PER_RTOL * float(_coerce("rtol", self.rtol)))
        object.__setattr__(self, "_atol_auto", auto)  # not a field: atol follows rtol
        _check_fields(self, _SOLVER_SPECS, skip=("method",))

    @property
    def atol_is_auto(self) -> bool:
        """Whether atol is the default 1e-3 rtol (then it follows rtol)."""
        return bool(getattr(self, "_atol_auto", False))


@dataclass(frozen=True)
class Run:
    """Lengths of a steady-state run, in excitation cycles.

    Parameters
    ----------
    transient : int
        Cycles discarded first, >= 0. Default 40 (the paper).
    record : int
        Cycles recorded, >= 1. Default 8 (the paper).
    phase : float
        Stroboscopic section phase as a fraction of the period, in [0, 1):
        the section samples t = (phase + k) T.
    """

    transient: int = 40
    record: int = 8
    phase: float = 0.0

    def __post_init__(self) -> None:
        _check_fields(self, _RUN_SPECS)


def _check_fields(obj: object, specs: Mapping[str, _Spec], skip: Sequence[str] = ()) -> None:
    """Coerce and check every field of a frozen component in place."""
    for name, value in _fields(obj).items():
        if name in specs and name not in skip:
            object.__setattr__(obj, name, _coerce(name, value))


# ================================================================= scene
@dataclass(frozen=True)
class Scene:
    """A complete, validated pounding problem (docs/model.md sections 3-9).

    Parameters
    ----------
    name, description : str
        Label and one-line description.
    freq_ratio : float
        Om = T_Ax / T_Bx = omega_Bx / omega_Ax, > 0.
    mass_ratio : float, optional
        m = m_A / m_B, > 0; ``None``: Om**2 (equal column stiffness).
    gap : float
        a, clear gap between the facing faces at rest, >= 0 (A_g units).
    offset_y : float
        y of B's stiffness centre minus A's (A_g units); the rest faces
        must overlap, |offset_y| < (l_A + l_B)/2.
    opponent : {"tower", "wall"}
        Tower A pounds against tower B or a rigid ground-borne wall.
    torsion_damping : {"consistent", "as-printed"}
        Torsional damping 2 zeta_t Om_ti th' or, as printed, 2 zeta_t Om_i th'.
    tower_A, tower_B : Tower
    contact : Contact
    excitation : Excitation
    solver : Solver
    run : Run
    initial_state : tuple of 12 floats, optional
        (X_A, X_A', Y_A, Y_A', th_A, th_A', X_B, ..., th_B'); ``None``: at
        rest. Tower B's entries are ignored against a wall.
    sweep : tuple of (str, str)
        Sweep axes: (flat parameter name, grid string), the grid unparsed.
    """

    name: str = "custom"
    description: str = ""
    freq_ratio: float = DEFAULT_FREQ_RATIO
    mass_ratio: float | None = None
    gap: float = DEFAULT_GAP
    offset_y: float = 0.0
    opponent: str = "tower"
    torsion_damping: str = "consistent"
    tower_A: Tower = field(default_factory=Tower)
    tower_B: Tower = field(default_factory=Tower)
    contact: Contact = field(default_factory=Contact)
    excitation: Excitation = field(default_factory=Excitation)
    solver: Solver = field(default_factory=Solver)
    run: Run = field(default_factory=Run)
    initial_state: tuple[float, ...] | None = None
    sweep: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        for label in ("name", "description"):
            if not isinstance(getattr(self, label), str):
                raise SceneError(f"{label} = {_show(getattr(self, label))}: must be a string")
        _check_fields(self, _GLOBAL_SPECS)
        self._check_components()
        self._check_overlap()
        object.__setattr__(self, "initial_state", _normalise_initial(self.initial_state))
        object.__setattr__(self, "sweep", _normalise_sweep(self.sweep))
        if self.solver.model != "auto":
            self._check_model(MODEL_NAMES.index(self.solver.model), "model")

    # ------------------------------------------------------- derived values
    @property
    def period(self) -> float:
        """Excitation period T = 2 pi r, in normalised time."""
        return 2.0 * math.pi * self.excitation.period_ratio

    @property
    def effective_mass_ratio(self) -> float:
        """m = m_A / m_B, resolved (Om**2 when not given)."""
        return self.freq_ratio**2 if self.mass_ratio is None else self.mass_ratio

    @property
    def overlap(self) -> tuple[float, float]:
        """(y_lo, y_hi): the faces' common extent at rest, global y (A_g units)."""
        half_a = 0.5 * self.tower_A.length
        if self.opponent == "wall":
            return -half_a, half_a
        half_b = 0.5 * self.tower_B.length
        return max(-half_a, self.offset_y - half_b), min(half_a, self.offset_y + half_b)

    @property
    def model_name(self) -> str:
        """Name of the reduction used ("wall", "tower-wall", "pair", "towers")."""
        return MODEL_NAMES[self.model_id()]

    def model_id(self) -> int:
        """Model id (kernels.params) of the equations this scene is solved with.

        Returns
        -------
        int
            ``solver.model`` if forced, else the smallest exact reduction
            (docs/model.md section 9).
        """
        if self.solver.model == "auto":
            return self._auto_model_id()
        return MODEL_NAMES.index(self.solver.model)

    # ------------------------------------------------------------- packing
    def pack(self, model_id: int | None = None) -> np.ndarray:
        """Packed float64 parameter vector (layout: :mod:`chaospound.kernels.params`).

        Parameters
        ----------
        model_id : int, optional
            Model the vector is meant for; checked to be exact for this scene.
            The vector itself does not depend on it.

        Returns
        -------
        numpy.ndarray
            Shape (N_PARAMS,) for the Hertz law (unused entries are 0); other
            laws append their block (:meth:`law_block`).
        """
        if model_id is not None:
            self._check_model(model_id, "model_id")
        p = np.zeros(N_PARAMS, dtype=np.float64)
        period = self.period
        y_lo, y_hi = self.overlap
        p[P_PERIOD_RATIO] = self.excitation.period_ratio
        p[P_GROUND] = 1.0 if self.excitation.ground == "sine" else 0.0
        p[P_GAP] = self.gap
        p[P_BETA] = self.contact.beta
        p[P_CHI] = self.contact.chi
        p[P_Y_C] = 0.5 * (y_lo + y_hi)
        p[P_HALF_L] = 0.5 * (y_hi - y_lo)
        p[P_Y_OFF] = self.offset_y
        p[P_PHASE0] = self.run.phase * period
        p[P_PERIOD] = period
        consistent = self.torsion_damping == "consistent"
        _pack_tower(p, TOWER_A, self.tower_A, 1.0, 1.0, consistent)
        _pack_tower(
            p, TOWER_B, self.tower_B, self.freq_ratio, self.effective_mass_ratio, consistent
        )
        if self.contact.contact_law != "hertz":  # Hertz's block is (P_BETA, P_CHI)
            p = np.concatenate((p, self.law_block()))
        ground = self.excitation.ground_block()
        if ground is not None:  # after the law's block
            p = np.concatenate((p, ground))
        return p

    def unused_contact_inputs(self, *, changed_only: bool = False) -> tuple[str, ...]:
        """The contact inputs that the scene's law does not read.

        ``beta`` is read by every law (as ``k`` by the linear ones); ``chi`` only
        by the Hertz-type laws, ``restitution`` only by the dissipative ones,
        ``damping_variant`` only by hertzdamp and ``no_pull`` only by
        kelvin-voigt (:meth:`law_block`: what the law module's ``block`` takes).

        Parameters
        ----------
        changed_only : bool
            Only those whose value differs from its default (what a user set in
            vain, e.g. ``restitution`` with the elastic ``hertz`` law).

        Returns
        -------
        tuple of str
            Flat parameter names, in the order of :data:`PARAMETERS`.
        """
        reads = _law_reads(self.contact.contact_law)
        defaults = {f.name: f.default for f in dataclasses.fields(Contact)}
        return tuple(name for name, read in reads.items() if not read and not (
            changed_only and getattr(self.contact, name) == defaults[name]))

    def law_block(self) -> np.ndarray:
        """The contact law's block of the packed vector: its parameters, then its memory.

        The law module's ``block(e, ...)`` turns the scene's physical inputs into
        them; it takes what it needs of: ``beta``, ``chi``, ``k`` (= beta),
        ``m_eff`` (the pair's effective mass in units of m_A: ``1 / (1 + m)``
        between the towers, 1 against a wall, docs/contact_laws.md), ``variant``
        and ``no_pull``.
        """
        contact = self.contact
        module, accepted = _law_module(contact.contact_law)
        from chaospound.physics.contact.dissipation import effective_mass

        if self.opponent == "wall":
            m_eff = effective_mass(1.0)
        else:
            m_eff = effective_mass(1.0, self.effective_mass_ratio)
        offered = {"beta": contact.beta, "chi": contact.chi, "k": contact.beta, "m_eff": m_eff,
                   "variant": contact.damping_variant, "no_pull": contact.no_pull}
        try:
            e = contact.restitution if module.DISSIPATIVE else 1.0  # elastic: e = 1
            values = module.block(e, **{k: v for k, v in offered.items() if k in accepted})
        except ValueError as exc:
            raise SceneError(f"contact law {contact.contact_law}: {exc}") from None
        return np.array([values[name] for name in module.PARAMETERS + module.MEMORY],
                        dtype=np.float64)

    def initial_vector(self, model_id: int | None = None) -> np.ndarray:
        """Initial state restricted to a model's states.

        Parameters
        ----------
        model_id : int, optional
            Defaults to :meth:`model_id`.

        Returns
        -------
        numpy.ndarray
            float64, in the order of ``STATE_NAMES[model_id]``; zeros when
            ``initial_state`` is None (both towers at rest).
        """
        model = self.model_id() if model_id is None else model_id
        if not _is_model_id(model):
            raise _bad_model_id(model)
        full = np.zeros(12) if self.initial_state is None else np.array(self.initial_state)
        return full[list(STATE_INDEX[model])].astype(np.float64)

    # ----------------------------------------------------------- overrides
    def with_params(self, **flat: object) -> Scene:
        """A new scene with flat parameters changed.

        Parameters
        ----------
        **flat
            Flat names (:data:`PARAMETERS`) or shorthands (:data:`SHORTHANDS`:
            ``length`` sets ``length_A`` and ``length_B``, ``zeta`` all six
            damping ratios). Values may be text, parsed to the parameter's
            type; ``mass_ratio`` and ``gyration_*`` accept "auto" (derived
            default). Specific names win over shorthands. Setting one form of
            width or eccentricity (absolute or ``*_ratio``) drops the other.
            ``initial_state`` (a sequence of 12 numbers) is also accepted.

        Returns
        -------
        Scene
            Validated.
        """
        updates = _expand(flat)
        parts: dict[str, dict[str, object]] = {}
        for name, value in updates.items():
            component, attr = _TARGET.get(name, ("scene", name))
            parts.setdefault(component, {})[attr] = value
        changes = parts.pop("scene", {})
        for component, values in parts.items():
            changes[component] = _updated(getattr(self, component), component, values)
        return dataclasses.replace(self, **changes)

    def with_assignments(self, assignments: Iterable[str]) -> Scene:
        """A new scene from ``name=value`` texts (the CLI's ``--set``).

        Parameters
        ----------
        assignments : iterable of str
            Each ``name=value``; a later assignment of the same name wins.

        Returns
        -------
        Scene
        """
        flat: dict[str, str] = {}
        for item in assignments:
            name, sep, value = str(item).partition("=")
            name = name.strip()
            if not sep or not name or not value.strip():
                raise SceneError(f"malformed assignment {shorten(item, quote=True)}: "
                                 "expected name=value")
            if name == "initial_state":
                raise SceneError(
                    "initial_state can only be set from a scene file ([initial] state = [...])"
                )
            flat[name] = value.strip()
        return self.with_params(**flat)

    def physical_changes(self, other: Scene) -> dict[str, tuple[object, object]]:
        """The physical parameters in which this scene differs from ``other``.

        Parameters
        ----------
        other : Scene
            E.g. the preset this scene was made from.

        Returns
        -------
        dict
            Flat name -> (other's value, this scene's value), resolved, in the
            order of :data:`PARAMETERS`; solver and run settings are left out.
        """
        pairs = {name: (other._resolved(name), self._resolved(name)) for name in PARAMETERS
                 if _TARGET[name][0] not in ("solver", "run")}
        return {name: pair for name, pair in pairs.items() if pair[0] != pair[1]}

    # -------------------------------------------------------------- export
    def to_dict(self) -> dict[str, object]:
        """Every flat parameter, resolved, plus derived values (JSON-serialisable).

        Returns
        -------
        dict
            ``name``, ``description``, all :data:`PARAMETERS` with width,
            eccentricity (both forms), gyration and mass ratio resolved, except
            that ``model`` is the reduction actually used (the requested
            setting is ``model_requested``), ``model_id``, derived ``Om_tA``,
            ``Om_tB``, ``period`` (T = 2 pi r), ``y_lo``, ``y_hi``, ``L_ref``,
            ``initial_state`` (list or None) and ``sweep`` (dict).
        """
        out: dict[str, object] = {"name": self.name, "description": self.description}
        for name in PARAMETERS:
            out[name] = self._resolved(name)
        out["model_requested"] = self.solver.model
        out["model"] = self.model_name
        out["model_id"] = self.model_id()
        y_lo, y_hi = self.overlap
        out.update(
            Om_tA=math.sqrt(self.tower_A.torsion_frequency2(1.0)),
            Om_tB=math.sqrt(self.tower_B.torsion_frequency2(self.freq_ratio)),
            period=self.period,
            y_lo=y_lo,
            y_hi=y_hi,
            L_ref=y_hi - y_lo,
        )
        out["initial_state"] = None if self.initial_state is None else list(self.initial_state)
        out["sweep"] = dict(self.sweep)
        return out

    def to_toml(self) -> str:
        """The scene as TOML text (the layout :func:`load_scene` reads)."""
        return _toml_document(self)

    @classmethod
    def from_toml(cls, text: str, source: str = "<string>") -> Scene:
        """Build a scene from TOML text.

        Parameters
        ----------
        text : str
            Layout as written by :meth:`to_toml`.
        source : str
            File or preset name used in error messages.

        Returns
        -------
        Scene
        """
        try:
            data = tomllib.loads(text)
        except RecursionError:  # tomllib recurses into nested arrays and tables
            raise SceneError(f"{source}: malformed TOML: nested too deeply") from None
        except ValueError as exc:  # TOMLDecodeError, or an integer of > 4300 digits
            raise SceneError(f"{source}: malformed TOML: {_toml_error(exc)}") from None
        try:
            return _scene_from_tables(data)
        except SceneError as exc:
            raise SceneError(f"{source}: {exc}") from None

    # ------------------------------------------------------------- helpers
    def _resolved(self, name: str) -> object:
        """Value of one flat parameter with derived defaults resolved."""
        component, attr = _TARGET[name]
        if component == "scene":
            return self.effective_mass_ratio if attr == "mass_ratio" else getattr(self, attr)
        if not component.startswith("tower"):
            return getattr(getattr(self, component), attr)
        tower: Tower = getattr(self, component)
        resolved = {
            "width": tower.w,
            "ecc_x": tower.e_x,
            "ecc_y": tower.e_y,
            "gyration": tower.rho,
            "width_ratio": tower.w / tower.length,
            "ecc_x_ratio": tower.e_x / tower.length,
            "ecc_y_ratio": tower.e_y / tower.length,
        }
        return resolved.get(attr, getattr(tower, attr))

    def _check_components(self) -> None:
        kinds = {
            "tower_A": Tower,
            "tower_B": Tower,
            "contact": Contact,
            "excitation": Excitation,
            "solver": Solver,
            "run": Run,
        }
        for label, kind in kinds.items():
            if not isinstance(getattr(self, label), kind):
                raise SceneError(
                    f"{label} = {_show(getattr(self, label))}: must be a {kind.__name__}"
                )

    def _check_overlap(self) -> None:
        if self.opponent == "wall":
            return
        l_a, l_b = self.tower_A.length, self.tower_B.length
        if not abs(self.offset_y) < 0.5 * (l_a + l_b):
            raise SceneError(
                f"no overlap at rest: l_A = {l_a:g}, l_B = {l_b:g}, offset_y = "
                f"{self.offset_y:g} (need |offset_y| < (l_A + l_B)/2)"
            )

    def _auto_model_id(self) -> int:
        """Smallest exact reduction (docs/model.md section 9)."""
        if self.opponent == "wall":
            return TOWER_WALL if self._torsion_reasons(("A",)) else WALL
        return TOWERS if self._torsion_reasons(("A", "B")) else PAIR

    def _torsion_reasons(self, towers: Sequence[str]) -> list[str]:
        """Why Y and th of the given towers may not stay zero (empty: they do)."""
        reasons = []
        for label in towers:
            e_y = getattr(self, f"tower_{label}").e_y
            if e_y != 0.0:
                reasons.append(f"ecc_y_{label} = {e_y:g} != 0")
        if "B" in towers and self.offset_y != 0.0:
            reasons.append(f"offset_y = {self.offset_y:g} != 0")
        if self.excitation.has_y:
            reasons.append("the ground motion has a y component ("
                           + _y_component_text(self.excitation) + "), which drives Y")
        state = self.initial_state or (0.0,) * 12
        for label, index in (("A", _LATERAL_A), ("B", _LATERAL_B)):
            if label in towers and any(state[i] != 0.0 for i in index):
                reasons.append(f"initial Y_{label}, Y_{label}', th_{label}, th_{label}' not zero")
        return reasons

    def _check_model(self, model_id: object, label: str) -> None:
        """Raise unless ``model_id`` is exact for this scene."""
        if model_id not in STATE_INDEX or isinstance(model_id, bool):
            raise _bad_model_id(model_id)
        name = MODEL_NAMES[model_id]
        wall_models = (WALL, TOWER_WALL)
        if (model_id in wall_models) != (self.opponent == "wall"):
            fits = [
                MODEL_NAMES[m] for m in (wall_models if self.opponent == "wall" else (PAIR, TOWERS))
            ]
            raise SceneError(
                f"{label} = {name!r}: not available with opponent = {self.opponent!r} "
                f"(use {fits[0]!r}, {fits[1]!r} or 'auto')"
            )
        if model_id in (WALL, PAIR):
            reasons = self._torsion_reasons(("A",) if model_id == WALL else ("A", "B"))
            if reasons:
                bigger = MODEL_NAMES[TOWER_WALL if model_id == WALL else TOWERS]
                raise SceneError(
                    f"{label} = {name!r}: not exact for this scene ({'; '.join(reasons)}); "
                    f"use {bigger!r} or 'auto'"
                )


def _y_component_text(excitation: Excitation) -> str:
    """What gives a ground motion its y component, for a reduction's refusal."""
    if excitation.ground == "sine":
        return f"ground_y_ratio = {excitation.ground_y_ratio:g}"
    if excitation.ground == "stochastic":
        return "ground_components = 2"
    return f"two components in ground_file {excitation.ground_file}"


def _is_model_id(model_id: object) -> bool:
    integral = isinstance(model_id, int | np.integer) and not isinstance(model_id, bool)
    return integral and int(model_id) in STATE_INDEX


def _bad_model_id(model_id: object) -> SceneError:
    known = ", ".join(f"{i} ({n})" for i, n in enumerate(MODEL_NAMES))
    return SceneError(f"model_id = {model_id!r}: must be one of {known}")


def _pack_tower(
    p: np.ndarray, base: int, tower: Tower, om: float, mu: float, consistent: bool
) -> None:
    """Fill one tower block of the packed vector (kernels.params offsets).

    Parameters
    ----------
    p : numpy.ndarray
        Packed vector, written in place.
    base : int
        TOWER_A or TOWER_B.
    tower : Tower
    om : float
        Om_i, translational frequency in units of omega_Ax (1 for A, Om for B).
    mu : float
        mu_i, factor on the contact forces (1 for A, m for B).
    consistent : bool
        Torsional damping with Om_ti (True) or Om_i ("as-printed").
    """
    rho2 = tower.rho2
    omt2 = tower.torsion_frequency2(om)
    p[base + T_OM2] = om**2
    p[base + T_MU] = mu
    p[base + T_CX] = 2.0 * tower.zeta_x * om
    p[base + T_CY] = 2.0 * tower.zeta_y * om
    p[base + T_CT] = 2.0 * tower.zeta_t * (math.sqrt(omt2) if consistent else om)
    p[base + T_EX] = tower.e_x
    p[base + T_EY] = tower.e_y
    p[base + T_RHO2] = rho2
    p[base + T_OMT2] = omt2
    p[base + T_L] = tower.length
    p[base + T_W] = tower.w
    p[base + T_KTH] = om**2 / rho2
    p[base + T_MU_RHO2] = mu / rho2


def _normalise_initial(state: object) -> tuple[float, ...] | None:
    """Check the 12-state initial condition; None stays None (at rest)."""
    if state is None:
        return None
    if isinstance(state, str | bytes) or not isinstance(state, Iterable):
        raise SceneError(f"initial_state = {_show(state)}: must be a list of 12 numbers")
    values = list(state)
    if len(values) != 12:
        raise SceneError(
            f"initial_state has {len(values)} values: need 12 ({', '.join(FULL_STATE)})"
        )
    spec = _Spec("float", "initial state, A_g and A_g omega_Ax units")
    return tuple(
        _as_float(f"initial_state[{i}] ({FULL_STATE[i]})", v, spec) for i, v in enumerate(values)
    )


def _normalise_sweep(sweep: object) -> tuple[tuple[str, str], ...]:
    """Sweep axes as ((name, grid), ...); names checked, grids kept as text."""
    items = list(sweep.items()) if isinstance(sweep, Mapping) else list(sweep)
    out = []
    for item in items:
        if not (isinstance(item, tuple | list) and len(item) == 2):
            raise SceneError(f"sweep item {_show(item)}: must be a (parameter, grid) pair")
        name, grid = item
        if name not in _TARGET and name not in SHORTHANDS:
            raise _unknown(name, what="sweep parameter")
        if not isinstance(grid, str):
            raise SceneError(
                f"sweep {name} = {_show(grid)}: the grid must be a string, "
                "e.g. '0.3:2.0#1000' or '0.3:2.0:0.005'"
            )
        out.append((name, grid))
    return tuple(out)


def _expand(flat: Mapping[str, object]) -> dict[str, object]:
    """Resolve shorthands (specific names win) and check names and forms."""
    for name in flat:
        if name not in _TARGET and name not in SHORTHANDS and name != "initial_state":
            raise _unknown(name)
    origin: dict[str, str] = {}
    values: dict[str, object] = {}
    for rank in (("zeta",), tuple(n for n in SHORTHANDS if n != "zeta"), None):
        for name, value in flat.items():
            in_rank = name in rank if rank is not None else name not in SHORTHANDS
            if not in_rank:
                continue
            for target in SHORTHANDS.get(name, (name,)):
                values[target], origin[target] = value, name
    for target in values:
        partner = _PARTNER.get(target[:-2]) if target[-2:] in _SUFFIXES else None
        if partner is not None and partner + target[-2:] in values:
            other = partner + target[-2:]
            first, second = sorted((origin[target], origin[other]))
            raise SceneError(
                f"{first} and {second} both given: give {target[:-2].removesuffix('_ratio')}"
                f"{target[-2:]} absolutely or relative to length{target[-2:]}, not both"
            )
    if "method" in values and "rtol" not in values:
        if _coerce("method", values["method"]) == "paper":
            values["rtol"] = None
    return values


def _updated(component: object, label: str, values: Mapping[str, object]) -> object:
    """A component with some fields changed (towers: forms swapped, named)."""
    if label.startswith("tower"):
        fields = _fields(component)
        for name, value in values.items():
            fields[name] = value
            if name in _PARTNER:
                fields[_PARTNER[name]] = None
        return _make_tower(fields, label[-2:])
    if label == "solver" and "rtol" in values and "atol" not in values and (
            component.atol_is_auto):
        values = {**values, "atol": None}
    return dataclasses.replace(component, **values)


# ================================================================== TOML
_TABLES: dict[str, tuple[str, ...]] = {
    "excitation": ("period_ratio", "ground", "ground_file", "ground_units", "ground_scale",
                   "ground_dt", "length_unit", "tower_period", "tower_mass", *STOCHASTIC_FIELDS,
                   *SINE_Y_FIELDS),
    "ground": (),  # [ground] motion = "...", file = "...": the ground_* names without prefix
    "structure": ("freq_ratio", "mass_ratio", "gap", "offset_y", "opponent", "torsion_damping"),
    "tower_A": tuple(_TOWER_SPECS),
    "tower_B": tuple(_TOWER_SPECS),
    "contact": ("beta", "chi", "contact_law", "restitution", "damping_variant", "no_pull"),
    "solver": tuple(_SOLVER_SPECS),
    "run": tuple(_RUN_SPECS),
    "initial": ("state",),
    "sweep": (),  # any flat parameter name
    "physical": (),  # SI quantities (chaospound.units.from_physical)
}
_TOP_KEYS = ("name", "description")


#: the [ground] table's keys that are not the ground_* names without their prefix
_GROUND_KEYS = {"motion": "ground", "length_unit": "length_unit", "tower_period": "tower_period",
                "period_ratio": "period_ratio"}
#: the short keys of the [contact] table: law = "hertzdamp", variant = "ye"
_CONTACT_KEYS = {"law": "contact_law", "variant": "damping_variant"}


def _scene_from_tables(data: Mapping[str, object]) -> Scene:
    """Scene from parsed TOML tables (layout of :data:`_TABLES`)."""
    for key, value in data.items():
        if key in _TOP_KEYS:
            continue
        if key not in _TABLES:
            raise _unknown(key, list(_TOP_KEYS) + list(_TABLES), "table or key")
        if not isinstance(value, dict):
            raise SceneError(f"[{key}] must be a table, got {_show(value)}")
    flat: dict[str, object] = {}
    for key, value in data.get("ground", {}).items():
        name = _GROUND_KEYS.get(key, "ground_" + key)
        if name not in _TABLES["excitation"] or key == "ground":
            known = list(_GROUND_KEYS) + [n.removeprefix("ground_") for n in _TABLES["excitation"]
                                          if n.startswith("ground_")]
            raise _unknown(key, known, "key in [ground]:")
        flat[name] = value
    for table, keys in _TABLES.items():
        if table in ("initial", "sweep", "ground", "physical"):
            continue
        for key, value in data.get(table, {}).items():
            if table == "excitation" and key in flat:
                raise SceneError(f"{key} given in [excitation] and in [ground]: give it once")
            if table == "contact" and key in _CONTACT_KEYS:
                key = _CONTACT_KEYS[key]
            if key not in keys:
                raise _unknown(key, keys, f"key in [{table}]:")
            flat[key + table[-2:] if table.startswith("tower") else key] = value
    if "physical" in data:
        _add_physical(data["physical"], flat)
    initial = data.get("initial", {})
    for key in initial:
        if key != "state":
            raise _unknown(key, ("state",), "key in [initial]:")
    base = Scene(
        name=data.get("name", "custom"),
        description=data.get("description", ""),
        sweep=tuple(data.get("sweep", {}).items()),
    )
    if "state" in initial:
        flat["initial_state"] = initial["state"]
    return base.with_params(**flat)


def _add_physical(table: Mapping[str, object], flat: dict[str, object]) -> None:
    """Convert a [physical] table (SI, :func:`chaospound.units.from_physical`) into ``flat``.

    The law, exponent and ground motion it needs come from the other tables; a
    parameter given both in SI and dimensionless is an error.
    """
    from chaospound.units import PhysicalUnitsError, from_physical

    law = _coerce("contact_law", flat.get("contact_law", "hertz"))
    chi = _coerce("chi", flat.get("chi", DEFAULT_CHI))
    ground = _coerce("ground", flat.get("ground", "sine"))
    try:
        converted, _ = from_physical(table, ground=ground, law=law, chi=chi)
    except PhysicalUnitsError as exc:
        raise SceneError(str(exc)) from None
    for name, value in converted.items():
        covered = {name, *(n for n, targets in SHORTHANDS.items() if name in targets),
                   *SHORTHANDS.get(name, ())}
        clash = sorted(covered & set(flat))
        if clash:
            raise SceneError(f"{clash[0]} given in [physical] (SI) and in another table: "
                             "give it once")
        flat[name] = value


def _toml_document(scene: Scene) -> str:
    """TOML text of a scene; only given forms and non-default Nones are written."""
    tables: dict[str, dict[str, object]] = {
        "excitation": {k: v for k, v in _fields(scene.excitation).items()
                       if k in ("period_ratio", "ground") or v != getattr(Excitation(), k)
                       or (scene.excitation.ground == "stochastic" and k in STOCHASTIC_FIELDS)
                       or (scene.excitation.ground in ("record", "stochastic")
                           and k in ("ground_file", "ground_units", "ground_scale",
                                     "ground_dt", "length_unit", "tower_period"))},
        "structure": {n: getattr(scene, n) for n in _TABLES["structure"]},
        "tower_A": _tower_table(scene.tower_A),
        "tower_B": _tower_table(scene.tower_B),
        "contact": _contact_table(scene.contact),
        "solver": {k: v for k, v in _fields(scene.solver).items()
                   if not (k == "atol" and scene.solver.atol_is_auto)},
        "run": _fields(scene.run),
    }
    if scene.initial_state is not None:
        tables["initial"] = {"state": list(scene.initial_state)}
    if scene.sweep:
        tables["sweep"] = dict(scene.sweep)
    lines = [f"name = {_toml_value(scene.name)}", f"description = {_toml_value(scene.description)}"]
    for table, entries in tables.items():
        lines += ["", f"[{table}]"]
        lines += [
            f"{key} = {_toml_value(value)}" for key, value in entries.items() if value is not None
        ]
    return "\n".join(lines) + "\n"


def _contact_table(contact: Contact) -> dict[str, object]:
    """The [contact] table: beta and chi, and the law's fields unless the default Hertz's."""
    short = {v: k for k, v in _CONTACT_KEYS.items()}
    default = Contact(beta=contact.beta, chi=contact.chi)
    return {short.get(k, k): v for k, v in _fields(contact).items()
            if k in ("beta", "chi") or contact != default}


def _tower_table(tower: Tower) -> dict[str, object]:
    """A tower's fields in reading order: length, width, eccentricities, ..."""
    fields = _fields(tower)
    return {name: fields[name] for name in _TOWER_SPECS}


def _toml_value(value: object) -> str:
    """One TOML value (str, bool, int, float or list of them), exact for floats."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} as TOML")


_TOML_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def _toml_string(text: str) -> str:
    """TOML basic string with the required escapes."""
    out = []
    for char in text:
        if char in _TOML_ESCAPES:
            out.append(_TOML_ESCAPES[char])
        elif ord(char) < 0x20 or ord(char) == 0x7F:
            out.append(f"\\u{ord(char):04x}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def save_scene(scene: Scene, path: str | os.PathLike[str]) -> None:
    """Write a scene as TOML (UTF-8).

    Parameters
    ----------
    scene : Scene
    path : str or path-like
    """
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(scene.to_toml())


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Read a scene from a TOML file.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        Unreadable file, malformed TOML, unknown tables or keys, invalid
        values; the message starts with the file name.
    """
    try:
        with open(path, "rb") as handle:
            raw = handle.read(MAX_SCENE_BYTES + 1)
        text = raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{os.fspath(path)}: cannot read scene file: {exc}") from None
    if len(raw) > MAX_SCENE_BYTES:
        raise SceneError(f"{os.fspath(path)}: not a scene file: more than "
                         f"{MAX_SCENE_BYTES // 2**20} MB")
    return Scene.from_toml(text, source=os.fspath(path))


def _toml_error(exc: ValueError) -> str:
    """A TOML parser's message, with any quoted key cut short but the position kept."""
    text = str(exc)
    where = text.rfind(" (at ")
    if len(text) <= 160 or where < 0:
        return shorten(text, 160)
    return shorten(text[:where], 120) + text[where:]


# =============================================================== presets
_PRESET_SUFFIX = ".toml"


def _preset_dir() -> Traversable:
    return resources.files("chaospound").joinpath("presets")


def list_presets() -> list[str]:
    """Names of the bundled presets (chaospound/presets/*.toml), sorted."""
    return sorted(
        entry.name[: -len(_PRESET_SUFFIX)]
        for entry in _preset_dir().iterdir()
        if entry.name.endswith(_PRESET_SUFFIX)
    )


def load_preset(name: str) -> Scene:
    """Load a bundled preset scene (the paper's Fig. 3-5, Davis's wall, ...).

    Parameters
    ----------
    name : str
        One of :func:`list_presets` (a trailing ".toml" is ignored).

    Returns
    -------
    Scene
    """
    name = str(name).removesuffix(_PRESET_SUFFIX)
    available = list_presets()
    if name not in available:
        raise _unknown(name, available, "preset", listing=True)
    text = _preset_dir().joinpath(name + _PRESET_SUFFIX).read_text(encoding="utf-8")
    return Scene.from_toml(text, source=f"preset {name}")
