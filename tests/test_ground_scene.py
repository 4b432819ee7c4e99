"""Stochastic ground motions in scenes: parameters, TOML, validation, reproducibility.

A stochastic scene (``ground = "stochastic"``) is given in SI and converted with
the scene's ``length_unit`` (A_g) and ``tower_period`` (T_Ax); the same seed
gives the same bits, another seed another motion (docs/ground_motions.md 6).
"""

import math

import numpy as np
import pytest

from chaospound import load_preset
from chaospound.physics.ground import record, stochastic
from chaospound.scene import STANDARD_GRAVITY, Scene, SceneError
from chaospound.simulate import simulate

SI = {"ground": "stochastic", "length_unit": 0.01, "tower_period": 0.5, "ground_pga": 0.3,
      "ground_duration": 4.0, "ground_t_rise": 0.5, "ground_t_plateau": 2.0,
      "transient": 0, "record": 14}


def _scene(**extra) -> Scene:
    return load_preset("wall").with_params(gap=0.5, **{**SI, **extra})


def test_same_seed_same_bits_other_seed_differs():
    first, again = simulate(_scene(ground_seed=7)), simulate(_scene(ground_seed=7))
    assert len(first.impacts) > 0
    assert np.array_equal(first.strobe.state, again.strobe.state)
    assert np.array_equal(first.impacts.time, again.impacts.time)
    assert np.array_equal(first.impacts.peak_force, again.impacts.peak_force)
    other = simulate(_scene(ground_seed=8))
    assert not np.array_equal(first.strobe.state, other.strobe.state)


def test_the_block_is_the_modules_realisation_in_model_units():
    """The scene's block: stochastic.generate of the SI spec converted to model units
    (frequencies / omega_Ax, times * omega_Ax, S0 / (A_g^2 omega_Ax^3)), integrated as a
    record; with ground_pga the peak of the x acceleration is the PGA."""
    scene = _scene(ground_intensity=2e-3, ground_pga=None, ground_seed=3)
    omega = 2.0 * math.pi / 0.5
    spec = {"omega_g": 15.6 / omega, "zeta_g": 0.6, "omega_f": 1.5 / omega, "zeta_f": 0.6,
            "intensity": 2e-3 / (0.01**2 * omega**3), "dt": 0.01 * omega,
            "duration": 4.0 * omega, "seed": 3, "envelope": "jennings",
            "t_rise": 0.5 * omega, "t_plateau": 2.0 * omega, "decay": 0.3 / omega}
    np.testing.assert_allclose(
        scene.excitation.ground_block(), stochastic.block(spec), rtol=1e-12, atol=1e-14)
    pga = _scene(ground_seed=3).excitation
    t, a_x, _ = stochastic.generate(pga.stochastic_spec())
    block = pga.ground_block()
    n = int(block[0])
    a = block[3 + 3 * n:3 + 4 * n]  # t, u, v, a: the corrected accelerations
    corrected = record.baseline_rest(t, a_x * (0.3 * STANDARD_GRAVITY / (0.01 * omega**2))
                                     / np.max(np.abs(a_x)))
    np.testing.assert_allclose(a, corrected, rtol=1e-12, atol=1e-12)


def test_toml_ground_table_and_round_trip():
    text = """
[structure]
opponent = "wall"
[ground]
motion = "stochastic"
pga = 0.25
seed = 11
envelope = "saragoni-hart"
sh_b = 3.0
sh_c = 1.0
length_unit = 0.02
tower_period = 0.4
"""
    scene = Scene.from_toml(text)
    assert scene.excitation.ground == "stochastic"
    assert scene.excitation.ground_seed == 11
    assert scene.excitation.ground_envelope == "saragoni-hart"
    again = Scene.from_toml(scene.to_toml())
    assert again == scene
    assert np.array_equal(again.pack(), scene.pack())


@pytest.mark.parametrize("change, words", [
    ({"ground_pga": None}, "exactly one of ground_intensity"),
    ({"ground_intensity": 1e-3}, "exactly one of ground_intensity"),
    ({"length_unit": None}, "needs length_unit"),
    ({"ground_envelope": "boxcar"}, "ground_envelope"),
    ({"ground_components": 3}, "ground_components"),
    ({"ground_t_plateau": 0.1}, "ground_t_plateau"),
    ({"ground_duration": 0.001}, "ground_duration"),
    ({"ground_zeta_g": 0.0}, "ground_zeta_g"),
])
def test_bad_stochastic_values_are_one_line_errors(change, words):
    with pytest.raises(SceneError) as info:
        _scene(**change)
    assert words in str(info.value) and "\n" not in str(info.value)


def test_unknown_key_in_the_ground_table():
    with pytest.raises(SceneError, match="unknown key in \\[ground\\]: 'pgaa'.*'pga'"):
        Scene.from_toml('[ground]\nmotion = "stochastic"\npgaa = 0.3\n')
