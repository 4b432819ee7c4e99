"""The model's units, as every output states them (docs/model.md section 2).

Everything is dimensionless: lengths in A_g (the ground displacement
amplitude), time t = tau omega_Ax, velocities in A_g omega_Ax, forces in
A_g k_Ax. The sweep files' ``units`` attribute and the ``units`` object of the
command line's JSON documents are this dictionary.
"""

import math
from collections.abc import Mapping
from dataclasses import dataclass

UNITS = {
    "time": "normalised, t = tau omega_Ax",
    "length": "A_g (ground displacement amplitude)",
    "velocity": "A_g omega_Ax",
    "force": "A_g k_Ax",
    "exponents": "per unit normalised time (multiply by the period T for per cycle)",
    "phase": "fraction of the excitation period, in [0, 1)",
}


# ============================================================== physical units

#: standard gravity g [m/s^2] (PGA in g)
GRAVITY = 9.80665
#: laws whose stiffness multiplies d itself (k, N/m), the others d^chi (beta, N/m^chi)
LINEAR_LAWS = ("linear", "kelvin-voigt")
#: default A_g [m] of a physical scene under a record or a stochastic motion (1 mm: the
#: dimensionless lengths are then millimetres)
DEFAULT_RECORD_LENGTH = 1e-3


class PhysicalUnitsError(ValueError):
    """A bad entry of a scene's [physical] table (one line)."""


@dataclass(frozen=True)
class PhysicalUnits:
    """The SI values of the model's units (docs/units.md).

    Parameters
    ----------
    length : float
        A_g [m], the unit of every length.
    period : float
        T_Ax [s], tower A's translational period: omega_Ax = 2 pi / T_Ax.
    mass : float, optional
        m_A [kg], tower A's mass: the force unit A_g K_Ax needs K_Ax = m_A omega_Ax^2.
    """

    length: float
    period: float
    mass: float | None = None

    @property
    def omega(self) -> float:
        """omega_Ax [rad/s]; the time unit is 1 / omega_Ax."""
        return 2.0 * math.pi / self.period

    @property
    def time(self) -> float:
        """The time unit 1 / omega_Ax [s]."""
        return 1.0 / self.omega

    @property
    def velocity(self) -> float:
        """The velocity unit A_g omega_Ax [m/s]."""
        return self.length * self.omega

    @property
    def acceleration(self) -> float:
        """The acceleration unit A_g omega_Ax^2 [m/s^2]."""
        return self.length * self.omega**2

    @property
    def stiffness(self) -> float:
        """K_Ax = m_A omega_Ax^2 [N/m], tower A's lateral stiffness."""
        if self.mass is None:
            raise PhysicalUnitsError("forces in SI need tower A's mass (tower_mass [kg], or "
                                     "mass_A in a [physical] table)")
        return self.mass * self.omega**2

    @property
    def force(self) -> float:
        """The force unit A_g K_Ax [N]."""
        return self.length * self.stiffness

    def contact_stiffness(self, chi: float) -> float:
        """The unit K_Ax A_g^(1 - chi) of beta [N/m^chi] (chi = 1: k in N/m)."""
        return self.stiffness * self.length ** (1.0 - chi)


def units_of(scene) -> PhysicalUnits | None:
    """The scene's physical units (``length_unit``, ``tower_period``, ``tower_mass``), or
    None when it has no ``length_unit`` or ``tower_period``."""
    ex = scene.excitation
    if ex.length_unit is None or ex.tower_period is None:
        return None
    return PhysicalUnits(ex.length_unit, ex.tower_period, ex.tower_mass)


def contact_exponent(law: str, chi: float) -> float:
    """The power of d the law's stiffness multiplies (1 for the linear laws, else chi)."""
    return 1.0 if law in LINEAR_LAWS else chi


# ------------------------------------------------------------ [physical] table
#: [physical] keys per tower (suffix _A, _B; without it: both) [unit]
_TOWER_LENGTHS = ("length", "width", "ecc_x", "ecc_y", "gyration")
_PHYSICAL_KEYS = {
    "period_A": "s", "period_B": "s", "mass_A": "kg", "mass_B": "kg",
    **{f"{n}{s}": "m" for n in _TOWER_LENGTHS for s in ("", "_A", "_B")},
    "offset_y": "m", "gap": "mm", "contact_stiffness": "N/m^chi", "restitution": "",
    "excitation_period": "s", "pga": "g", "amplitude": "m", "length_unit": "m",
}


def physical_keys() -> dict[str, str]:
    """The keys of a [physical] table and their units."""
    return dict(_PHYSICAL_KEYS)


def _number(table: Mapping, key: str, positive: bool = True) -> float:
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PhysicalUnitsError(f"[physical] {key} = {value!r}: must be a number "
                                 f"({_PHYSICAL_KEYS[key] or 'dimensionless'})")
    value = float(value)
    if not math.isfinite(value) or (positive and value <= 0.0):
        raise PhysicalUnitsError(f"[physical] {key} = {value!r}: must be "
                                 f"{'> 0' if positive else 'finite'} "
                                 f"({_PHYSICAL_KEYS[key] or 'dimensionless'})")
    return value


def from_physical(table: Mapping, *, ground: str = "sine", law: str = "hertz",
                  chi: float = 1.5) -> tuple[dict[str, object], PhysicalUnits]:
    """Convert a scene's [physical] table (SI) to flat dimensionless parameters.

    Parameters
    ----------
    table : mapping
        ``period_A`` [s] and ``mass_A`` [kg] (required: the time and mass units);
        ``period_B`` [s], ``mass_B`` [kg]; per tower (suffix ``_A``/``_B``, none: both)
        ``length``, ``width``, ``ecc_x``, ``ecc_y``, ``gyration`` [m]; ``offset_y``
        [m]; ``gap`` [mm]; ``contact_stiffness`` [N/m^chi, N/m for the linear laws];
        ``restitution``; the length unit A_g from exactly one of ``pga`` [g] (sine:
        A_g = PGA g / omega^2, omega = 2 pi / ``excitation_period``), ``amplitude``
        (the sine's A_g [m]) or ``length_unit`` [m] (any motion; default 1 mm under a
        record or a stochastic motion); ``excitation_period`` [s] (the sine's period T,
        also the section interval).
    ground, law, chi : str, str, float
        The scene's ground motion, contact law and exponent (from its other tables).

    Returns
    -------
    (flat, units)
        Flat parameters for ``Scene.with_params`` (including ``length_unit``,
        ``tower_period`` and ``tower_mass``) and the :class:`PhysicalUnits`.
    """
    unknown = [k for k in table if k not in _PHYSICAL_KEYS]
    if unknown:
        import difflib

        close = difflib.get_close_matches(str(unknown[0]), list(_PHYSICAL_KEYS), n=2)
        hint = f"did you mean {' or '.join(map(repr, close))}?" if close else (
            "known: " + ", ".join(_PHYSICAL_KEYS))
        raise PhysicalUnitsError(f"unknown key in [physical]: {unknown[0]!r} ({hint})")
    for key in ("period_A", "mass_A"):
        if key not in table:
            raise PhysicalUnitsError(f"[physical] needs {key} ({_PHYSICAL_KEYS[key]}): tower "
                                     "A's period and mass are the model's time and mass units")
    t_a, m_a = _number(table, "period_A"), _number(table, "mass_A")
    given = [k for k in ("pga", "amplitude", "length_unit") if k in table]
    if len(given) > 1:
        raise PhysicalUnitsError(f"[physical] {' and '.join(given)} both given: the length "
                                 "unit A_g comes from one of pga, amplitude, length_unit")
    flat: dict[str, object] = {}
    if "excitation_period" in table:
        flat["period_ratio"] = _number(table, "excitation_period") / t_a
    if "pga" in table:
        if ground != "sine":
            raise PhysicalUnitsError(f"[physical] pga sets the sine's amplitude (ground = "
                                     f"{ground}): give length_unit [m] instead")
        if "excitation_period" not in table:
            raise PhysicalUnitsError("[physical] pga needs excitation_period [s] (A_g = "
                                     "PGA g / omega^2)")
        omega = 2.0 * math.pi / _number(table, "excitation_period")
        a_g = _number(table, "pga") * GRAVITY / omega**2
    elif given:
        a_g = _number(table, given[0])
    elif ground in ("record", "stochastic"):
        a_g = DEFAULT_RECORD_LENGTH
    else:
        raise PhysicalUnitsError("[physical] needs the ground amplitude: pga [g] with "
                                 "excitation_period [s], or amplitude [m] (A_g)")
    units = PhysicalUnits(a_g, t_a, m_a)
    if "period_B" in table:
        flat["freq_ratio"] = t_a / _number(table, "period_B")
    if "mass_B" in table:
        flat["mass_ratio"] = m_a / _number(table, "mass_B")
    for key in table:
        name = key.removesuffix("_A").removesuffix("_B")
        if name in _TOWER_LENGTHS or key == "offset_y":
            flat[key] = _number(table, key, positive=name in ("length", "width", "gyration")) / a_g
    if "gap" in table:
        gap = _number(table, "gap", positive=False)
        if gap < 0.0:
            raise PhysicalUnitsError(f"[physical] gap = {gap!r}: must be >= 0 (mm)")
        flat["gap"] = gap / (1e3 * a_g)
    if "contact_stiffness" in table:
        exponent = contact_exponent(law, chi)
        flat["beta"] = _number(table, "contact_stiffness") / units.contact_stiffness(exponent)
    if "restitution" in table:
        flat["restitution"] = _number(table, "restitution")
    flat.update(length_unit=a_g, tower_period=t_a, tower_mass=m_a)
    return flat, units


def conversion_rows(scene) -> list[tuple[str, str, str, str]]:
    """The conversion table of a scene with physical units: (quantity, SI, model, rule).

    Every row is computed from the scene (whatever form it was written in), so the
    table also checks a dimensionless scene given ``length_unit``, ``tower_period``
    and ``tower_mass``. Empty when the scene has no physical units.
    """
    units = units_of(scene)
    if units is None:
        return []
    values = scene.to_dict()
    rows = [
        ("A_g (length unit)", f"{units.length * 1e3:.6g} mm", "1", "lengths / A_g"),
        ("T_Ax (tower A, x)", f"{units.period:.6g} s", "2 pi", "t = tau omega_Ax"),
        ("omega_Ax", f"{units.omega:.6g} rad/s", "1", "2 pi / T_Ax"),
        ("velocity unit", f"{units.velocity:.6g} m/s", "1", "A_g omega_Ax"),
        ("acceleration unit", f"{units.acceleration / GRAVITY:.6g} g", "1",
         "A_g omega_Ax^2"),
    ]
    if units.mass is not None:
        rows += [
            ("m_A (tower A)", f"{units.mass:.6g} kg", "1", "masses / m_A"),
            ("K_Ax (tower A, x)", f"{units.stiffness / 1e3:.6g} kN/m", "1", "m_A omega_Ax^2"),
            ("force unit", f"{units.force / 1e3:.6g} kN", "1", "A_g K_Ax"),
            ("m_B (tower B)", f"{units.mass / values['mass_ratio']:.6g} kg",
             f"{values['mass_ratio']:.6g}", "mass_ratio = m_A / m_B"),
        ]
    omega_b = units.omega * values["freq_ratio"]
    rows.append(("T_Bx (tower B, x)", f"{2.0 * math.pi / omega_b:.6g} s",
                 f"{values['freq_ratio']:.6g}", "freq_ratio = T_Ax / T_Bx"))
    if scene.excitation.ground == "sine":
        period = values["period_ratio"] * units.period
        pga = units.length * (2.0 * math.pi / period) ** 2 / GRAVITY
        rows += [("excitation period T", f"{period:.6g} s", f"{values['period_ratio']:.6g}",
                  "period_ratio = T / T_Ax"),
                 ("PGA of the sine", f"{pga:.6g} g", f"{1.0 / values['period_ratio']**2:.6g}",
                  "A_g (2 pi / T)^2 / g")]
    rows.append(("gap a", f"{values['gap'] * units.length * 1e3:.6g} mm", f"{values['gap']:.6g}",
                 "a / A_g"))
    for label in ("A", "B"):
        if label == "B" and scene.opponent == "wall":
            continue
        for name in ("length", "width", "ecc_x", "ecc_y", "gyration"):
            value = values[f"{name}_{label}"]
            rows.append((f"{name}_{label}", f"{value * units.length:.6g} m", f"{value:.6g}",
                         f"{name} / A_g"))
    if scene.opponent != "wall":
        rows.append(("offset_y", f"{values['offset_y'] * units.length:.6g} m",
                     f"{values['offset_y']:.6g}", "offset_y / A_g"))
    if units.mass is not None:
        exponent = contact_exponent(scene.contact.contact_law, scene.contact.chi)
        unit = "N/m" if exponent == 1.0 else f"N/m^{exponent:g}"
        beta_si = values["beta"] * units.contact_stiffness(exponent)
        rows.append(("contact stiffness", f"{beta_si:.6g} {unit}", f"{values['beta']:.6g}",
                     f"beta / (K_Ax A_g^(1 - {exponent:g}))"))
    if scene.contact.contact_law not in ("hertz", "linear"):
        rows.append(("restitution e", f"{values['restitution']:.6g}",
                     f"{values['restitution']:.6g}", "dimensionless"))
    return rows


def si_value(units: PhysicalUnits, kind: str, value: float) -> float:
    """A model value in SI: kind "time" [s], "velocity" [m/s], "force" [kN],
    "length" [mm] (penetrations, displacements), "rotation" [rad]."""
    factor = {"time": units.time, "velocity": units.velocity, "force": units.force / 1e3,
              "length": units.length * 1e3, "rotation": 1.0}[kind]
    return value * factor


#: units of :func:`si_value`'s kinds
SI_UNITS = {"time": "s", "velocity": "m/s", "force": "kN", "length": "mm", "rotation": "rad"}


def si_impacts(impacts, units: PhysicalUnits) -> dict:
    """A run's impact table in SI: onset ``time`` [s], ``velocity`` [m/s],
    ``peak_penetration`` [mm], ``peak_force`` [kN], ``duration`` [s] (arrays).

    Parameters
    ----------
    impacts : chaospound.simulate.Impacts
    units : PhysicalUnits
        With the mass (the force unit).
    """
    return {"time": si_value(units, "time", impacts.time),
            "velocity": si_value(units, "velocity", impacts.velocity),
            "peak_penetration": si_value(units, "length", impacts.peak_penetration),
            "peak_force": si_value(units, "force", impacts.peak_force),
            "duration": si_value(units, "time", impacts.duration)}


def require_si(scene) -> PhysicalUnits:
    """The scene's physical units with a mass, else a one-line :class:`PhysicalUnitsError`
    (what ``--units si`` needs)."""
    units = units_of(scene)
    if units is None or units.mass is None:
        raise PhysicalUnitsError("--units si needs the scene's length_unit [m], tower_period "
                                 "[s] and tower_mass [kg] (--set NAME=VALUE, or a [physical] "
                                 "table: docs/units.md)")
    return units
