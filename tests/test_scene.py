"""Scenes: presets, validation, flat overrides, TOML, reductions and packing."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from chaospound.kernels import params as P
from chaospound.scene import (
    CONTACT_LAWS,
    PARAMETERS,
    STATE_NAMES,
    Scene,
    SceneError,
    Solver,
    Tower,
    laws_reading,
    list_presets,
    load_preset,
    load_scene,
    save_scene,
)

DATA = Path(__file__).parent / "data" / "towers_vectors.json"
PRESETS = ("fig3a", "fig3b", "fig4", "fig4-translational", "fig5", "wall", "tower-wall")

# conformance-file scene names -> flat parameter names
CONFORMANCE_NAMES = {
    "r": "period_ratio",
    "ground": "ground",
    "Om": "freq_ratio",
    "m": "mass_ratio",
    "a": "gap",
    "y_off": "offset_y",
    "opponent": "opponent",
    "torsion_damping": "torsion_damping",
    "beta": "beta",
    "chi": "chi",
    **{
        f"{sym}_{t}": f"{name}_{t}"
        for t in "AB"
        for sym, name in (
            ("l", "length"),
            ("w", "width"),
            ("rho", "gyration"),
            ("zx", "zeta_x"),
            ("zy", "zeta_y"),
            ("zt", "zeta_t"),
        )
    },
    **{f"e_{t}{axis}": f"ecc_{axis}_{t}" for t in "AB" for axis in "xy"},
}


def block(p: np.ndarray, base: int, offset: int) -> float:
    return float(p[base + offset])


def conformance_scenes() -> list[dict]:
    cases = json.loads(DATA.read_text())["cases"]
    unique = {json.dumps(c["scene"], sort_keys=True): c["scene"] for c in cases}
    return list(unique.values())


def scene_from_conformance(values: dict) -> Scene:
    flat = {CONFORMANCE_NAMES[k]: v for k, v in values.items() if k in CONFORMANCE_NAMES}
    return Scene().with_params(**flat)


# ----------------------------------------------------------------- presets
def test_every_preset_loads_with_paper_values():
    assert set(PRESETS) <= set(list_presets())
    for name in list_presets():
        scene = load_preset(name)
        flat = scene.to_dict()
        assert scene.name == name and scene.description and "\n" not in scene.description
        assert flat["freq_ratio"] == 1.5 and flat["mass_ratio"] == 2.25
        assert flat["gap"] == 1.0 and flat["beta"] == 1000.0 and flat["chi"] == 1.5
        for t in "AB":
            assert flat[f"length_{t}"] == 100.0
            assert flat[f"width_{t}"] == pytest.approx(55.0, rel=1e-15)
            assert all(flat[f"{z}_{t}"] == 0.03 for z in ("zeta_x", "zeta_y", "zeta_t"))
        assert flat["ecc_y_B"] == 0.0


@pytest.mark.parametrize(
    ("name", "r", "e_ay", "opponent", "model", "swept"),
    [
        ("fig3a", 0.7, 10.0, "tower", "towers", False),
        ("fig3b", 0.7, -10.0, "tower", "towers", False),
        ("fig4", 1.0, 10.0, "tower", "towers", True),
        ("fig4-translational", 1.0, 0.0, "tower", "pair", True),
        ("fig5", 1.0, 20.0, "tower", "towers", True),
        ("wall", 0.7, 0.0, "wall", "wall", False),
        ("tower-wall", 0.7, 10.0, "wall", "tower-wall", False),
    ],
)
def test_preset_specifics(name, r, e_ay, opponent, model, swept):
    scene = load_preset(name)
    assert scene.excitation.period_ratio == r
    assert scene.tower_A.e_y == pytest.approx(e_ay, rel=1e-15, abs=0)
    assert scene.opponent == opponent
    assert scene.model_name == model
    assert scene.sweep == ((("period_ratio", "0.3:2.0#1000"),) if swept else ())


def test_unknown_preset_lists_available():
    with pytest.raises(SceneError) as err:
        load_preset("fig3c")
    message = str(err.value)
    assert "fig3c" in message and all(n in message for n in PRESETS)
    assert "\n" not in message


# ----------------------------------------------------------- packed vector
def test_fig3a_torsional_frequency_and_packing_by_hand():
    scene = load_preset("fig3a")
    assert scene.to_dict()["Om_tA"] == pytest.approx(1.7584454834410321, rel=1e-15)
    p = scene.pack()
    assert p.shape == (P.N_PARAMS,) and p.dtype == np.float64
    l, w, e_y, om, m = 100.0, 55.0, 10.0, 1.5, 2.25
    rho2 = (l**2 + w**2) / 12.0
    omt2_a = (l**2 + w**2 + 4 * e_y**2) / (4 * rho2)
    omt2_b = om**2 * (l**2 + w**2) / (4 * rho2)
    A, B = P.TOWER_A, P.TOWER_B
    expected = {
        (A, P.T_OM2): 1.0,
        (A, P.T_MU): 1.0,
        (A, P.T_CX): 0.06,
        (A, P.T_CY): 0.06,
        (A, P.T_CT): 0.06 * math.sqrt(omt2_a),
        (A, P.T_EX): 0.0,
        (A, P.T_EY): e_y,
        (A, P.T_RHO2): rho2,
        (A, P.T_OMT2): omt2_a,
        (A, P.T_L): l,
        (A, P.T_W): w,
        (A, P.T_KTH): 1.0 / rho2,
        (A, P.T_MU_RHO2): 1.0 / rho2,
        (B, P.T_OM2): om**2,
        (B, P.T_MU): m,
        (B, P.T_CX): 0.06 * om,
        (B, P.T_CY): 0.06 * om,
        (B, P.T_CT): 0.06 * math.sqrt(omt2_b),
        (B, P.T_EY): 0.0,
        (B, P.T_RHO2): rho2,
        (B, P.T_OMT2): omt2_b,
        (B, P.T_L): l,
        (B, P.T_W): w,
        (B, P.T_KTH): om**2 / rho2,
        (B, P.T_MU_RHO2): m / rho2,
    }
    for (base, offset), value in expected.items():
        assert block(p, base, offset) == pytest.approx(value, rel=1e-14), (base, offset)
    assert math.sqrt(block(p, A, P.T_OMT2)) == pytest.approx(1.7584454834410321, rel=1e-15)
    T = 2 * math.pi * 0.7
    assert p[P.P_PERIOD_RATIO] == 0.7 and p[P.P_GROUND] == 1.0 and p[P.P_GAP] == 1.0
    assert p[P.P_BETA] == 1000.0 and p[P.P_CHI] == 1.5 and p[P.P_PERIOD] == pytest.approx(T)
    assert p[P.P_Y_C] == 0.0 and p[P.P_HALF_L] == 50.0 and p[P.P_Y_OFF] == 0.0
    assert p[P.P_PHASE0] == 0.0
    used = {
        P.P_PERIOD_RATIO,
        P.P_GROUND,
        P.P_GAP,
        P.P_BETA,
        P.P_CHI,
        P.P_Y_C,
        P.P_HALF_L,
        P.P_Y_OFF,
        P.P_PHASE0,
        P.P_PERIOD,
    }
    used |= {b + k for b in (A, B) for k in range(len(P.TOWER_FIELDS))}
    assert not np.any(p[[i for i in range(P.N_PARAMS) if i not in used]])


def test_as_printed_damping_and_phase_and_ground():
    scene = load_preset("fig3a").with_params(
        torsion_damping="as-printed", phase=0.25, ground="none", zeta_t_B=0.05
    )
    p = scene.pack()
    assert block(p, P.TOWER_A, P.T_CT) == pytest.approx(0.06)
    assert block(p, P.TOWER_B, P.T_CT) == pytest.approx(2 * 0.05 * 1.5)
    assert p[P.P_PHASE0] == pytest.approx(0.25 * 2 * math.pi * 0.7)
    assert p[P.P_GROUND] == 0.0


def test_explicit_gyration_and_mass_ratio_are_packed():
    scene = load_preset("fig3a").with_params(gyration_B=20.0, mass_ratio=3.0)
    p = scene.pack()
    assert block(p, P.TOWER_B, P.T_RHO2) == 400.0
    assert block(p, P.TOWER_B, P.T_MU) == 3.0
    assert block(p, P.TOWER_B, P.T_KTH) == pytest.approx(2.25 / 400.0)
    assert block(p, P.TOWER_B, P.T_OMT2) == pytest.approx(2.25 * (100**2 + 55**2) / 1600)
    # "auto" restores the derived defaults
    back = scene.with_assignments(["gyration_B=auto", "mass_ratio=auto"])
    assert back == load_preset("fig3a")


@pytest.mark.parametrize("values", conformance_scenes(), ids=lambda v: str(v["r"]))
def test_conformance_scenes_build_and_pack(values):
    scene = scene_from_conformance(values)
    flat = scene.to_dict()
    p = scene.pack()
    y_lo = p[P.P_Y_C] - p[P.P_HALF_L]
    y_hi = p[P.P_Y_C] + p[P.P_HALF_L]
    assert (y_lo, y_hi, 2 * p[P.P_HALF_L]) == (values["y_lo"], values["y_hi"], values["L_ref"])
    assert (flat["y_lo"], flat["y_hi"], flat["L_ref"]) == (
        values["y_lo"],
        values["y_hi"],
        values["L_ref"],
    )
    for key in ("Om_tA", "Om_tB"):
        assert flat[key] == pytest.approx(values[key], rel=1e-14)
    assert flat["period"] == pytest.approx(values["T"], rel=1e-15)
    # distances from each CM to its facing face
    assert block(p, P.TOWER_A, P.T_W) / 2 - block(p, P.TOWER_A, P.T_EX) == pytest.approx(
        values["cA"], rel=1e-14
    )
    assert block(p, P.TOWER_B, P.T_W) / 2 + block(p, P.TOWER_B, P.T_EX) == pytest.approx(
        values["cB"], rel=1e-14
    )
    assert block(p, P.TOWER_B, P.T_MU) == values["mu_B"]


def test_offset_overlap_and_wall_overlap():
    scene = Scene().with_params(length_A=100, length_B=60, offset_y=30)
    assert scene.overlap == (0.0, 50.0)
    scene = Scene().with_params(length_A=100, length_B=60, offset_y=-45)
    assert scene.overlap == (-50.0, -15.0)
    wall = load_preset("wall").with_params(length_A=40, offset_y=500)  # offset unused
    assert wall.overlap == (-20.0, 20.0)
    assert wall.pack()[P.P_HALF_L] == 20.0


# ------------------------------------------------------- flat parameters
def test_ratio_forms_follow_length():
    scene = load_preset("fig3a").with_params(length_A=30)
    flat = scene.to_dict()
    assert flat["ecc_y_A"] == pytest.approx(3.0) and flat["width_A"] == pytest.approx(16.5)
    assert flat["gyration_A"] == pytest.approx(math.sqrt((30**2 + 16.5**2) / 12))
    assert flat["length_B"] == 100.0 and flat["width_B"] == pytest.approx(55.0)
    # an absolute value stays put when the length changes
    fixed = load_preset("fig3a").with_params(ecc_y_A=10.0, width_A=40.0).with_params(length_A=30)
    assert fixed.tower_A.e_y == 10.0 and fixed.tower_A.w == 40.0
    # and switching forms drops the other one
    assert fixed.tower_A.ecc_y_ratio is None and fixed.tower_A.width_ratio is None
    again = fixed.with_params(ecc_y_ratio_A=0.2)
    assert again.tower_A.ecc_y is None and again.tower_A.e_y == pytest.approx(6.0)


def test_shorthands_set_both_towers_and_specific_names_win():
    scene = Scene().with_params(length=50, zeta=0.05, zeta_t_B=0.01, ecc_y_ratio=0.1)
    flat = scene.to_dict()
    assert flat["length_A"] == flat["length_B"] == 50.0
    assert flat["ecc_y_A"] == flat["ecc_y_B"] == pytest.approx(5.0)
    zetas = [flat[f"{z}_{t}"] for t in "AB" for z in ("zeta_x", "zeta_y", "zeta_t")]
    assert zetas == [0.05] * 5 + [0.01]


def test_assignments_parse_text_to_field_types():
    scene = Scene().with_assignments(
        [
            "gap=0.5",
            "restart_at_kinks=no",
            "steps_per_cycle=800",
            "method=RK4",
            "opponent = wall",
            "transient=100",
            "model=tower_wall",
            "phase=0.5",
        ]
    )
    assert scene.gap == 0.5 and scene.solver.restart_at_kinks is False
    assert scene.solver.steps_per_cycle == 800 and scene.solver.method == "rk4"
    assert scene.opponent == "wall" and scene.run.transient == 100
    assert scene.model_name == "tower-wall" and scene.run.phase == 0.5
    assert Scene().with_assignments(["restart_at_kinks=1"]).solver.restart_at_kinks is True


def test_paper_solver_alias():
    solver = Scene().with_params(method="paper").solver
    assert (solver.method, solver.rtol) == ("cash-karp", 1e-3)
    solver = Scene().with_params(method="paper", rtol=1e-5).solver
    assert (solver.method, solver.rtol) == ("cash-karp", 1e-5)
    assert Solver().rtol == 1e-5 and Solver().atol == pytest.approx(1e-8)
    # atol follows rtol unless given (the work-precision rule atol = 1e-3 rtol)
    scene = load_preset("fig3a").with_params(rtol=1e-9)
    assert scene.solver.atol == pytest.approx(1e-12)
    fixed = load_preset("fig3a").with_params(atol=1e-7).with_params(rtol=1e-9)
    assert fixed.solver.atol == 1e-7
    assert Scene.from_toml(scene.to_toml()) == scene
    assert Scene.from_toml(fixed.to_toml()).solver.atol == 1e-7


def test_to_dict_is_json_and_complete():
    scene = load_preset("fig4").with_params(offset_y=5.0)
    flat = scene.to_dict()
    assert json.loads(json.dumps(flat)) == flat
    assert set(PARAMETERS) <= set(flat)
    assert flat["model"] == "towers" and flat["model_id"] == P.TOWERS
    assert flat["y_lo"] == -45.0 and flat["y_hi"] == 50.0 and flat["L_ref"] == 95.0
    assert flat["period"] == pytest.approx(2 * math.pi)
    assert flat["width_ratio_A"] == pytest.approx(0.55) and flat["initial_state"] is None


# ------------------------------------------------------------------ TOML
def test_toml_round_trip_through_text_and_file(tmp_path):
    state = [0.1, -0.2, 0.0, 0.3, 1e-3, 0.0, -0.5, 0.0, 0.01, 0.0, 0.0, -1e-4]
    scene = dataclasses.replace(
        load_preset("fig5").with_params(
            width_B=40.0, gyration_A=30.0, mass_ratio=2.0, method="dop853", offset_y=-3.5
        ),
        initial_state=state,
        description='quote " backslash \\ tab\t done',
    )
    assert Scene.from_toml(scene.to_toml()) == scene
    path = tmp_path / "scene.toml"
    save_scene(scene, path)
    loaded = load_scene(path)
    assert loaded == scene and loaded.initial_state == tuple(state)
    assert loaded.sweep == (("period_ratio", "0.3:2.0#1000"),)


def test_malformed_toml_names_file(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("name = \n[structure\n")
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert "broken.toml" in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("[structur]\ngap = 1.0\n", "structur"),
        ("[structure]\ngapp = 1.0\n", "gapp"),
        ("[tower_A]\nlenght = 1.0\n", "lenght"),
        ("[initial]\nstates = [0.0]\n", "states"),
        ("colour = 'red'\n", "colour"),
        ("[sweep]\nperiod = '0:1:3'\n", "period"),
        ("[structure]\ngap = -2.0\n", "gap"),
        ("[tower_B]\nwidth = 50.0\nwidth_ratio = 0.5\n", "width_B"),
        ("[initial]\nstate = [0.0, 1.0]\n", "initial_state"),
    ],
)
def test_bad_scene_files_are_named(tmp_path, text, named):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as err:
        load_scene(path)
    message = str(err.value)
    assert named in message and "bad.toml" in message and "\n" not in message


def test_missing_file_is_a_scene_error(tmp_path):
    with pytest.raises(SceneError, match="nowhere.toml"):
        load_scene(tmp_path / "nowhere.toml")


overrides = st.fixed_dictionaries(
    {},
    optional={
        "period_ratio": st.floats(0.01, 10.0),
        "freq_ratio": st.floats(0.1, 5.0),
        "mass_ratio": st.floats(0.1, 10.0),
        "gap": st.floats(0.0, 5.0),
        "offset_y": st.floats(-40.0, 40.0),
        "torsion_damping": st.sampled_from(["consistent", "as-printed"]),
        "ground": st.sampled_from(["sine", "none"]),
        "beta": st.floats(1.0, 1e6),
        "chi": st.floats(1.0, 3.0),
        "length_A": st.floats(1.0, 1e3),
        "width_B": st.floats(1e-3, 1e3),
        "width_ratio_A": st.floats(0.01, 10.0),
        "ecc_y_A": st.floats(-50.0, 50.0),
        "ecc_x_ratio_B": st.floats(-0.5, 0.5),
        "gyration_B": st.floats(0.1, 100.0),
        "zeta_t_B": st.floats(0.0, 1.0),
        "method": st.sampled_from(["dopri5", "cash-karp", "rk4", "dop853", "paper"]),
        "rtol": st.floats(1e-14, 1e-1),
        "steps_per_cycle": st.integers(4, 100_000),
        "restart_at_kinks": st.booleans(),
        "transient": st.integers(0, 10_000),
        "phase": st.floats(0.0, 1.0, exclude_max=True),
        "initial_state": st.lists(st.floats(-10.0, 10.0), min_size=12, max_size=12),
    },
)


@settings(max_examples=150, deadline=None)
@given(overrides)
def test_any_valid_override_set_round_trips_through_toml(flat):
    scene = load_preset("fig4").with_params(**flat)
    text = scene.to_toml()
    assert Scene.from_toml(text) == scene
    assert Scene.from_toml(text).to_toml() == text
    assert np.array_equal(Scene.from_toml(text).pack(), scene.pack())


# ------------------------------------------------------------ validation
INVALID = [
    ({"chi": 0.5}, "chi"),
    ({"beta": 0.0}, "beta"),
    ({"beta": -5.0}, "beta"),
    ({"length_A": 0.0}, "length_A"),
    ({"length": -1.0}, "length_A"),
    ({"width_B": -1.0}, "width_B"),
    ({"width_ratio": 0.0}, "width_ratio_A"),
    ({"gyration_A": 0.0}, "gyration_A"),
    ({"zeta_x_A": -0.01}, "zeta_x_A"),
    ({"zeta_t_B": -1.0}, "zeta_t_B"),
    ({"zeta": -0.1}, "zeta_x_A"),
    ({"period_ratio": 0.0}, "period_ratio"),
    ({"period_ratio": -0.7}, "period_ratio"),
    ({"gap": -1.0}, "gap"),
    ({"freq_ratio": 0.0}, "freq_ratio"),
    ({"mass_ratio": 0.0}, "mass_ratio"),
    ({"mass_ratio": -2.25}, "mass_ratio"),
    ({"length": 10.0, "offset_y": 30.0}, "offset_y"),
    ({"offset_y": -100.0}, "offset_y"),
    ({"gap": float("nan")}, "gap"),
    ({"beta": float("inf")}, "beta"),
    ({"ecc_y_A": "nan"}, "ecc_y_A"),
    ({"offset_y": "-inf"}, "offset_y"),
    ({"ecc_x_ratio_B": float("nan")}, "ecc_x_ratio_B"),
    ({"gap": "wide"}, "gap"),
    ({"gap": True}, "gap"),
    ({"ground": "cosine"}, "ground"),
    ({"opponent": "building"}, "opponent"),
    ({"torsion_damping": "viscous"}, "torsion_damping"),
    ({"method": "euler"}, "method"),
    ({"model": "full"}, "model"),
    ({"rtol": 0.0}, "rtol"),
    ({"atol": -1e-9}, "atol"),
    ({"steps_per_cycle": 3}, "steps_per_cycle"),
    ({"steps_per_cycle": 4.5}, "steps_per_cycle"),
    ({"max_steps": 0}, "max_steps"),
    ({"transient": -1}, "transient"),
    ({"record": 0}, "record"),
    ({"restart_at_kinks": "maybe"}, "restart_at_kinks"),
    ({"phase": 1.0}, "phase"),
    ({"phase": -0.1}, "phase"),
    ({"gapp": 1.0}, "gapp"),
    ({"width_A": 50.0, "width_ratio_A": 0.5}, "width_ratio_A"),
    ({"ecc_y": 1.0, "ecc_y_ratio_B": 0.1}, "ecc_y_ratio_B"),
    ({"initial_state": [0.0] * 11}, "initial_state"),
    ({"initial_state": [0.0] * 11 + [math.inf]}, "initial_state"),
    ({"initial_state": "0 0 0"}, "initial_state"),
    ({"model": "pair"}, "model"),  # fig3a is asymmetric
    ({"model": "wall"}, "model"),  # a wall model against a tower
]


@pytest.mark.parametrize(("flat", "named"), INVALID, ids=[str(f) for f, _ in INVALID])
def test_invalid_parameters_raise_one_line_errors(flat, named):
    with pytest.raises(SceneError) as err:
        load_preset("fig3a").with_params(**flat)
    message = str(err.value)
    assert isinstance(err.value, ValueError)
    assert named in message and "\n" not in message


def test_error_messages_follow_the_house_format():
    with pytest.raises(SceneError) as err:
        Scene().with_params(gap=-1.0)
    assert str(err.value) == "gap = -1.0: must be >= 0 (clear gap at rest, in units of A_g)"
    with pytest.raises(SceneError) as err:
        Scene().with_params(gapp=1.0)
    assert str(err.value) == "unknown parameter 'gapp' (did you mean 'gap'?)"
    with pytest.raises(SceneError) as err:
        Scene().with_params(length=10, offset_y=30)
    assert str(err.value) == (
        "no overlap at rest: l_A = 10, l_B = 10, offset_y = 30 (need |offset_y| < (l_A + l_B)/2)"
    )
    with pytest.raises(SceneError, match=r"^chi = 0\.5: must be >= 1"):
        Scene().with_params(chi=0.5)


@pytest.mark.parametrize("item", ["gap", "=1", "gap=", "initial_state=0"])
def test_malformed_assignments(item):
    with pytest.raises(SceneError) as err:
        Scene().with_assignments([item])
    assert "\n" not in str(err.value)


def test_direct_construction_validates_too():
    with pytest.raises(SceneError, match="length"):
        Tower(length=-1.0)
    with pytest.raises(SceneError, match="width"):
        Tower(width=10.0, width_ratio=0.1)
    with pytest.raises(SceneError, match="initial_state"):
        Scene(initial_state=(0.0, float("nan")) + (0.0,) * 10)
    with pytest.raises(SceneError, match="sweep parameter 'period'"):
        Scene(sweep=(("period", "0.3:2:10"),))
    assert Tower() == Tower(width_ratio=0.55, ecc_x=0.0, ecc_y=0.0)
    assert a_gap_of_zero_is_allowed()


def a_gap_of_zero_is_allowed() -> bool:
    return Scene().with_params(gap=0).gap == 0.0


# ------------------------------------------------------------- reductions
def at_rest_but(**entries: float) -> list[float]:
    state = [0.0] * 12
    names = STATE_NAMES[P.TOWERS]
    for name, value in entries.items():
        state[names.index(name)] = value
    return state


@pytest.mark.parametrize(
    ("preset", "flat", "model"),
    [
        ("fig4-translational", {}, P.PAIR),
        ("fig4-translational", {"ecc_x_A": 5.0, "length_B": 60.0}, P.PAIR),
        ("fig4-translational", {"ecc_y_A": 1.0}, P.TOWERS),
        ("fig4-translational", {"ecc_y_B": -1.0}, P.TOWERS),
        ("fig4-translational", {"offset_y": 2.0}, P.TOWERS),
        ("fig4-translational", {"initial_state": at_rest_but(th_A=1e-3)}, P.TOWERS),
        ("fig4-translational", {"initial_state": at_rest_but(dY_B=0.1)}, P.TOWERS),
        ("fig4-translational", {"initial_state": at_rest_but(X_A=0.5, dX_B=1.0)}, P.PAIR),
        ("fig4-translational", {"model": "towers"}, P.TOWERS),
        ("fig3a", {}, P.TOWERS),
        ("wall", {}, P.WALL),
        ("wall", {"initial_state": at_rest_but(dth_A=1e-3)}, P.TOWER_WALL),
        ("wall", {"initial_state": at_rest_but(th_B=1.0, Y_B=2.0)}, P.WALL),
        ("wall", {"offset_y": 3.0}, P.WALL),
        ("wall", {"model": "tower-wall"}, P.TOWER_WALL),
        ("tower-wall", {}, P.TOWER_WALL),
    ],
)
def test_model_selection(preset, flat, model):
    scene = load_preset(preset).with_params(**flat)
    assert scene.model_id() == model
    assert scene.model_name == P.MODEL_NAMES[model]
    assert len(scene.initial_vector(model)) == P.MODEL_DIMS[model] == len(STATE_NAMES[model])


@pytest.mark.parametrize(
    ("preset", "model", "why"),
    [
        ("fig3a", "pair", "ecc_y_A"),
        ("fig4-translational", "wall", "opponent"),
        ("tower-wall", "wall", "ecc_y_A"),
        ("wall", "towers", "opponent"),
    ],
)
def test_forcing_an_inexact_model_says_why(preset, model, why):
    with pytest.raises(SceneError) as err:
        load_preset(preset).with_params(model=model)
    assert why in str(err.value) and "\n" not in str(err.value)


def test_pack_checks_the_model_it_is_meant_for():
    scene = load_preset("fig3a")
    with pytest.raises(SceneError, match="not exact"):
        scene.pack(P.PAIR)
    with pytest.raises(SceneError, match="model_id"):
        scene.pack(7)
    assert np.array_equal(scene.pack(P.TOWERS), scene.pack())


def test_initial_vector_restricts_the_state():
    state = [float(i + 1) for i in range(12)]
    scene = dataclasses.replace(load_preset("fig3a"), initial_state=state)
    assert scene.initial_vector(P.TOWERS).tolist() == state
    assert scene.initial_vector(P.PAIR).tolist() == [1.0, 2.0, 7.0, 8.0]
    assert scene.initial_vector(P.TOWER_WALL).tolist() == state[:6]
    assert scene.initial_vector(P.WALL).tolist() == [1.0, 2.0]
    assert load_preset("wall").initial_vector().tolist() == [0.0, 0.0]
    assert STATE_NAMES[P.PAIR] == ("X_A", "dX_A", "X_B", "dX_B")


@pytest.mark.parametrize("law", CONTACT_LAWS)
def test_the_contact_inputs_a_law_does_not_read_leave_its_parameters_unchanged(law):
    """Scene.unused_contact_inputs names exactly the inputs whose change leaves the packed
    parameter vector (all the engine reads besides the law's name) unchanged. The fixed
    layout keeps Hertz's chi slot P_CHI for every law; only the hertz law reads it (its
    block is (P_BETA, P_CHI), the others' follows N_PARAMS: engine.compose.law_base)."""
    other = {"chi": 2.0, "restitution": 0.4, "damping_variant": "ye", "no_pull": True}

    def read(scene):
        packed = scene.pack()
        return packed if law == "hertz" else np.delete(packed, P.P_CHI)

    for preset in ("fig4", "wall"):
        scene = load_preset(preset).with_params(contact_law=law)
        unused = scene.unused_contact_inputs()
        assert scene.unused_contact_inputs(changed_only=True) == ()
        for name, value in other.items():
            changed = scene.with_params(**{name: value})
            same = np.array_equal(read(changed), read(scene))
            assert same == (name in unused), (preset, law, name)
            assert changed.unused_contact_inputs(changed_only=True) == (
                (name,) if name in unused else ())
            assert (law in laws_reading(name)) == (name not in unused)
