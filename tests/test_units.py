"""Physical units: a scene written in SI converts to the dimensionless model exactly.

The [physical] table of a scene (docs/units.md) gives periods in s, masses in kg,
plan dimensions in m, the gap in mm, the contact stiffness in N/m^chi and the
ground amplitude (PGA in g with the excitation period, or A_g in m); the scene
built from it packs to the dimensionless preset's vector, and model results
convert back with the hand formulas of docs/model.md section 2.
"""

import math

import numpy as np
import pytest

from chaospound import load_preset
from chaospound.scene import Scene, SceneError
from chaospound.simulate import simulate
from chaospound.units import (
    GRAVITY,
    PhysicalUnits,
    PhysicalUnitsError,
    conversion_rows,
    require_si,
    si_impacts,
    si_value,
    units_of,
)

T_A, A_G, M_A = 0.5, 0.01, 1.0e6
K_A = M_A * (2.0 * math.pi / T_A) ** 2


def _fig3a_si(ground: str = "amplitude = 0.01") -> str:
    """The paper's fig3a written in SI (A_g = 10 mm, T_Ax = 0.5 s, m_A = 1000 t)."""
    return f"""
name = "fig3a-si"
[physical]
period_A = 0.5
period_B = {0.5 / 1.5!r}
mass_A = 1.0e6
mass_B = {1.0e6 / 2.25!r}
excitation_period = 0.35
{ground}
length = 1.0
width = 0.55
ecc_y_A = 0.1
gap = 10.0
contact_stiffness = {1000.0 * K_A * A_G**-0.5!r}
[tower_A]
zeta_x = 0.03
"""


def test_an_si_fig3a_packs_to_the_preset():
    si, preset = Scene.from_toml(_fig3a_si()), load_preset("fig3a")
    np.testing.assert_allclose(si.pack(), preset.pack(), rtol=1e-15, atol=0.0)
    assert si.model_id() == preset.model_id()
    # the PGA form: A_g = PGA g / omega^2 with omega = 2 pi / 0.35 s
    pga = A_G * (2.0 * math.pi / 0.35) ** 2 / GRAVITY
    by_pga = Scene.from_toml(_fig3a_si(f"pga = {pga!r}"))
    np.testing.assert_allclose(by_pga.pack(), preset.pack(), rtol=1e-14, atol=0.0)
    assert by_pga.excitation.length_unit == pytest.approx(A_G, rel=1e-15)


def test_the_converted_scene_round_trips_through_toml():
    si = Scene.from_toml(_fig3a_si())
    again = Scene.from_toml(si.to_toml())
    assert again == si and np.array_equal(again.pack(), si.pack())
    assert units_of(again) == PhysicalUnits(A_G, T_A, M_A)


def test_conversions_against_hand_formulas():
    units = PhysicalUnits(A_G, T_A, M_A)
    omega = 2.0 * math.pi / T_A
    assert si_value(units, "velocity", 2.5) == pytest.approx(2.5 * A_G * omega, rel=1e-15)
    assert si_value(units, "force", 3.0) == pytest.approx(3.0 * A_G * M_A * omega**2 / 1e3,
                                                          rel=1e-15)
    assert si_value(units, "length", 0.25) == pytest.approx(0.25 * A_G * 1e3, rel=1e-15)
    assert si_value(units, "time", 7.0) == pytest.approx(7.0 / omega, rel=1e-15)
    assert units.contact_stiffness(1.5) == pytest.approx(K_A / math.sqrt(A_G), rel=1e-15)


def test_si_force_is_the_si_hertz_law_of_the_si_penetration():
    """A translational (pair) impact: the peak force converted to kN equals
    beta_SI d_SI^chi with the peak penetration converted to m, and the impact velocity
    in m/s is V A_g omega_Ax: the force, length and stiffness units agree."""
    text = _fig3a_si().replace("ecc_y_A = 0.1\n", "")
    scene = Scene.from_toml(text).with_params(transient=10, record=4)
    assert scene.model_name == "pair"
    run = simulate(scene)
    assert len(run.impacts) > 0
    units = units_of(scene)
    beta_si = 1000.0 * K_A * A_G**-0.5
    d_si = si_value(units, "length", run.impacts.peak_penetration) / 1e3
    np.testing.assert_allclose(si_value(units, "force", run.impacts.peak_force),
                               beta_si * d_si**1.5 / 1e3, rtol=1e-12)
    table = si_impacts(run.impacts, require_si(scene))
    omega = 2.0 * math.pi / T_A
    np.testing.assert_allclose(table["velocity"], run.impacts.velocity * A_G * omega, rtol=1e-15)
    np.testing.assert_allclose(table["time"], run.impacts.time / omega, rtol=1e-15)
    with pytest.raises(PhysicalUnitsError, match="needs the scene's length_unit"):
        require_si(load_preset("fig3a").with_params(length_unit=0.01, tower_period=0.5))


def test_conversion_table_rows():
    rows = {r[0]: r for r in conversion_rows(Scene.from_toml(_fig3a_si()))}
    assert rows["gap a"][1:3] == ("10 mm", "1")
    assert rows["T_Bx (tower B, x)"][1] == "0.333333 s"
    assert rows["force unit"][1] == f"{A_G * K_A / 1e3:.6g} kN"
    assert rows["contact stiffness"][2] == "1000"
    assert conversion_rows(load_preset("fig3a")) == []


@pytest.mark.parametrize("change, words", [
    (("mass_A = 1.0e6\n", ""), "needs mass_A"),
    (("gap = 10.0", "gap = -1.0"), "gap = -1.0: must be >= 0"),
    (("gap = 10.0", "gapp = 10.0"), "did you mean 'gap'"),
    (("amplitude = 0.01", "amplitude = 0.01\nlength_unit = 0.01"), "both given"),
    (("amplitude = 0.01", ""), "needs the ground amplitude"),
    (("length = 1.0", "length = \"big\""), "must be a number"),
    (("[tower_A]\nzeta_x = 0.03", "[structure]\ngap = 1.0"), "gap given in [physical]"),
])
def test_bad_physical_tables_are_one_line_errors(change, words):
    text = _fig3a_si().replace(*change)
    with pytest.raises(SceneError) as info:
        Scene.from_toml(text)
    assert words in str(info.value) and "\n" not in str(info.value)
