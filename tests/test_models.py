"""Right-hand sides against the conformance vectors; Jacobians; reductions at RHS level."""

import json
from pathlib import Path

import numpy as np
import pytest
from kernels_by_name import (
    contact_ends,
    contact_forces,
    contact_potential,
    jacobian,
    jacobian_trace,
    rhs,
)

from chaospound.kernels.params import MODEL_DIMS, PAIR, TOWER_WALL, TOWERS, WALL
from chaospound.scene import load_preset

DATA = json.loads((Path(__file__).parent / "data" / "towers_vectors.json").read_text())

NAME_MAP = {
    "r": "period_ratio", "Om": "freq_ratio", "m": "mass_ratio", "a": "gap",
    "l_A": "length_A", "l_B": "length_B", "w_A": "width_A", "w_B": "width_B",
    "e_Ax": "ecc_x_A", "e_Ay": "ecc_y_A", "e_Bx": "ecc_x_B", "e_By": "ecc_y_B",
    "rho_A": "gyration_A", "rho_B": "gyration_B",
    "zx_A": "zeta_x_A", "zy_A": "zeta_y_A", "zt_A": "zeta_t_A",
    "zx_B": "zeta_x_B", "zy_B": "zeta_y_B", "zt_B": "zeta_t_B",
    "y_off": "offset_y", "beta": "beta", "chi": "chi",
    "torsion_damping": "torsion_damping", "ground": "ground",
}


def conformance_scene(case):
    values = {ours: case["scene"][theirs] for theirs, ours in NAME_MAP.items()}
    return load_preset("fig3a").with_params(**values)


@pytest.mark.parametrize("index", range(len(DATA["cases"])))
def test_conformance_vectors(index):
    """RHS, potential, forces and end penetrations of an independent implementation."""
    case = DATA["cases"][index]
    scene = conformance_scene(case)
    p = scene.pack(TOWERS)
    y = np.array(case["state"])
    t = case["t"]
    out = np.zeros(12)
    rhs(TOWERS, t, y, p, out)
    ref = np.array(case["rhs"])
    np.testing.assert_allclose(out, ref, rtol=1e-12, atol=1e-14 * np.abs(ref).max())
    assert contact_potential(TOWERS, t, y, p) == pytest.approx(case["V"], rel=1e-12, abs=1e-300)
    q = np.zeros(6)
    contact_forces(TOWERS, t, y, p, q)
    qref = np.array(case["Q"])
    np.testing.assert_allclose(q, qref, rtol=1e-12, atol=1e-13 * max(np.abs(qref).max(), 1e-300))
    ends = np.zeros(4)
    contact_ends(TOWERS, t, y, p, ends)
    assert ends[0] == pytest.approx(case["d_lo"], rel=1e-12, abs=1e-14)
    assert ends[1] == pytest.approx(case["d_hi"], rel=1e-12, abs=1e-14)


def _fd_jacobian(model, t, y, p, step=1e-7):
    n = len(y)
    jac = np.zeros((n, n))
    fp, fm = np.zeros(n), np.zeros(n)
    for j in range(n):
        h = step * max(1.0, abs(y[j]))
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        rhs(model, t, yp, p, fp)
        rhs(model, t, ym, p, fm)
        jac[:, j] = (fp - fm) / (2 * h)
    return jac


def _states(model, rng, n_states=12):
    """Random states, half of them in contact."""
    n = MODEL_DIMS[model]
    for i in range(n_states):
        y = rng.normal(scale=0.3, size=n)
        if model in (TOWERS, TOWER_WALL):
            y[4] *= 1e-2
            if model == TOWERS:
                y[10] *= 1e-2
        if i % 2 == 0:
            y[0] += 1.2  # push A towards the opponent
        yield y


SCENES = {
    TOWERS: load_preset("fig3a").with_params(ecc_x_A=-3.0, ecc_y_B=-5.0, offset_y=7.0,
                                              length_B=90.0),
    PAIR: load_preset("fig4-translational"),
    TOWER_WALL: load_preset("tower-wall").with_params(ecc_x_A=2.0),
    WALL: load_preset("wall"),
}


@pytest.mark.parametrize("model", [TOWERS, PAIR, TOWER_WALL, WALL])
@pytest.mark.parametrize("chi", [1.5, 2.0, 3.0])
def test_jacobian_matches_finite_differences(model, chi):
    scene = SCENES[model].with_params(chi=chi)
    p = scene.pack(model)
    rng = np.random.default_rng(7)
    n = MODEL_DIMS[model]
    for y in _states(model, rng):
        jac = np.zeros((n, n))
        jacobian(model, 0.7, y, p, jac)
        fd = _fd_jacobian(model, 0.7, y, p)
        scale = np.abs(fd).max()
        np.testing.assert_allclose(jac, fd, rtol=1e-5, atol=1e-6 * scale)


@pytest.mark.parametrize("model", [TOWERS, PAIR, TOWER_WALL, WALL])
def test_trace_is_state_independent(model):
    """docs/model.md section 12: the Jacobian's trace is a constant of the damping."""
    p = SCENES[model].pack(model)
    n = MODEL_DIMS[model]
    rng = np.random.default_rng(3)
    expected = jacobian_trace(model, p)
    for y in _states(model, rng):
        jac = np.zeros((n, n))
        jacobian(model, 1.1, y, p, jac)
        assert np.trace(jac) == pytest.approx(expected, rel=1e-14)


def test_trace_formula_of_model_md():
    scene = load_preset("fig3a")
    d = scene.to_dict()
    expected = -2 * (0.03 + 0.03 + 0.03 * d["Om_tA"]) - 2 * 1.5 * (0.03 + 0.03) - 2 * 0.03 * d[
        "Om_tB"]
    assert jacobian_trace(TOWERS, scene.pack(TOWERS)) == pytest.approx(expected, rel=1e-14)
    printed = scene.with_params(torsion_damping="as-printed")
    expected = -2 * (0.03 * 3) - 2 * 1.5 * (0.03 * 3)
    assert jacobian_trace(TOWERS, printed.pack(TOWERS)) == pytest.approx(expected, rel=1e-14)


def test_pair_rhs_equals_towers_rhs_on_symmetric_states():
    scene = load_preset("fig4-translational").with_params(period_ratio=0.9)
    p4, p12 = scene.pack(PAIR), scene.pack(TOWERS)
    rng = np.random.default_rng(5)
    for _ in range(20):
        x = rng.normal(scale=0.8, size=4)
        y12 = np.zeros(12)
        y12[[0, 1, 6, 7]] = x
        f4, f12 = np.zeros(4), np.zeros(12)
        t = rng.uniform(0, 10)
        rhs(PAIR, t, x, p4, f4)
        rhs(TOWERS, t, y12, p12, f12)
        np.testing.assert_allclose(f12[[0, 1, 6, 7]], f4, rtol=1e-14, atol=1e-14)
        assert np.all(f12[[2, 3, 4, 5, 8, 9, 10, 11]] == 0.0)


def test_wall_rhs_equals_tower_wall_rhs_without_eccentricity():
    scene = load_preset("wall")
    p2, p6 = scene.pack(WALL), scene.pack(TOWER_WALL)
    rng = np.random.default_rng(6)
    for _ in range(20):
        x = rng.normal(scale=0.8, size=2) + np.array([0.8, 0.0])
        y6 = np.zeros(6)
        y6[:2] = x
        f2, f6 = np.zeros(2), np.zeros(6)
        t = rng.uniform(0, 10)
        rhs(WALL, t, x, p2, f2)
        rhs(TOWER_WALL, t, y6, p6, f6)
        np.testing.assert_allclose(f6[:2], f2, rtol=1e-14, atol=1e-14)
        assert np.all(f6[2:] == 0.0)
