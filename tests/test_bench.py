"""The benchmark compares like with like: same equations, same span, same counts.

Speed itself is measured by ``benchmarks/bench_simulate.py`` and
``chaospound bench``, never asserted here (shared, noisy machines).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from kernels_by_name import EPS_SERIES, contact_ends, rhs

from chaospound.bench import RUNS, load_python_twin, numba_fun
from chaospound.cli import main
from chaospound.kernels.params import MODEL_DIMS, PAIR, TOWER_WALL, TOWERS, WALL
from chaospound.scene import load_preset
from chaospound.simulate import simulate

#: the pure-Python equations of the scipy baseline (benchmarks/python_twin.py)
python_rhs = load_python_twin().python_rhs
python_fun = load_python_twin().python_fun

N_STATES = 400
SHORT = ["--transient", "2", "--record", "1"]

#: scenes per model: the presets and variants that switch on every term
SCENES = {
    TOWERS: [
        ("fig3a", {}),
        ("fig5", {}),
        ("fig3a", {"ecc_x_A": 3.0, "ecc_y_B": -4.0, "offset_y": 20.0, "length_B": 80.0}),
        ("fig3a", {"torsion_damping": "as-printed", "chi": 1.0, "gyration_A": 25.0}),
        ("fig3a", {"ground": "none", "gap": 0.0, "mass_ratio": 0.7}),
    ],
    TOWER_WALL: [
        ("tower-wall", {}),
        ("tower-wall", {"ecc_x_A": -2.0, "chi": 2.5, "beta": 30.0}),
    ],
    PAIR: [("fig4-translational", {}), ("fig4-translational", {"chi": 1.0, "ground": "none"})],
    WALL: [("wall", {}), ("wall", {"chi": 3.0, "gap": 0.0})],
}
CASES = [
    (model, preset, changes, index)
    for model, scenes in SCENES.items()
    for index, (preset, changes) in enumerate(scenes)
]


def random_states(model: int, rng: np.random.Generator, n: int) -> np.ndarray:
    """States spread over no contact, one end in contact and both ends in contact."""
    dim = MODEL_DIMS[model]
    scale = np.ones(dim)
    scale[1::2] = 3.0  # velocities
    states = rng.normal(size=(n, dim)) * scale
    if model in (TOWERS, TOWER_WALL):
        # rotations from 1e-6 to 3e-2 rad: with l = 100 the faces go from
        # parallel (series regime) to strongly skewed (partial contact)
        for col in (4, 10)[: 1 if model == TOWER_WALL else 2]:
            states[:, col] = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-6, -1.5, n)
            states[:, col + 1] *= 0.01
    return states


@pytest.mark.parametrize(("model", "preset", "changes", "index"), CASES)
def test_python_rhs_equals_numba_rhs(model, preset, changes, index):
    """The scipy baseline integrates the same equations as the kernels (to 1e-12)."""
    scene = load_preset(preset).with_params(**changes) if changes else load_preset(preset)
    assert scene.model_id() == model
    p = scene.pack(model)
    params = p.tolist()
    rng = np.random.default_rng(1000 + 10 * model + index)
    out = np.empty(MODEL_DIMS[model])
    ends = np.empty(4)
    regimes = set()
    for y in random_states(model, rng, N_STATES):
        t = rng.uniform(0.0, 50.0)
        rhs(model, t, y, p, out)
        ours = np.array(python_rhs(model, t, y.tolist(), params))
        scale = np.abs(out).max()
        np.testing.assert_allclose(ours, out, rtol=1e-12, atol=1e-12 * scale)
        contact_ends(model, t, y, p, ends)
        regimes.add(_regime(ends[0], ends[1]))
    expected = {"none", "full"} if model in (PAIR, WALL) else {"none", "partial", "series",
                                                                 "skewed"}  # fmt: skip
    assert regimes >= expected, f"states covered only {sorted(regimes)}"


def test_scipy_wrappers_agree():
    """Both solve_ivp right-hand sides give the numba kernel's values."""
    scene = load_preset("fig3a")
    p = scene.pack(TOWERS)
    y = np.linspace(-0.5, 0.6, 12)
    y[0], y[6], y[4], y[10] = 1.2, -0.3, 2e-3, -1e-3  # in contact
    expected = np.empty(12)
    rhs(TOWERS, 1.3, y, p, expected)
    assert np.abs(expected[1]).max() > 1.0
    np.testing.assert_allclose(python_fun(TOWERS, p)(1.3, y), expected, rtol=1e-12)
    np.testing.assert_array_equal(numba_fun(TOWERS, p)(1.3, y), expected)


def test_bench_cli_json(capsys):
    """One run of 'chaospound bench --json': keys, positive numbers, consistent counts."""
    code = main(["bench", *SHORT, "--repeats", "1", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    result = json.loads(out)
    assert {"scene", "model", "n_states", "span", "method", "rtol", "atol", "machine",
            "speedup", "cli", "targets", *RUNS} <= set(result)  # fmt: skip
    assert (result["scene"], result["model"], result["n_states"]) == ("fig3a", "towers", 12)
    assert (result["span"]["transient"], result["span"]["record"]) == (2, 1)
    assert result["span"]["t_end"] == pytest.approx(3 * 2 * np.pi * 0.7)
    for name in RUNS:
        entry = result[name]
        for key in ("wall_s", "steps", "rhs_evals", "us_per_step", "ns_per_rhs_eval", "repeats"):
            assert entry[key] > 0, (name, key)
        # Dormand-Prince: 6 new evaluations per attempted step (FSAL)
        assert entry["rhs_evals"] >= 6 * entry["steps"]
        assert entry["us_per_step"] == pytest.approx(1e6 * entry["wall_s"] / entry["steps"])
    for name in ("scipy-python", "scipy-numba"):
        assert set(result["speedup"][name]) == {"wall", "per_step"}
        assert all(v > 0 for v in result["speedup"][name].values())
        # same trajectory as chaospound at the end of the span
        assert result[name]["final_state_diff"] < 1e-3
    # the same equations give solve_ivp the same step sequence with either rhs
    assert result["scipy-python"]["steps"] == result["scipy-numba"]["steps"]
    assert result["scipy-python"]["rhs_evals"] == result["scipy-numba"]["rhs_evals"]
    # the benchmarked run is the real run
    scene = load_preset("fig3a").with_params(transient=2, record=1)
    assert result["chaospound"]["steps"] == simulate(scene).stats.steps
    assert result["cli"]["wall_s"] > 0 and result["cli"]["argv"][-2] == "simulate"
    assert all(isinstance(goal["met"], bool) for goal in result["targets"].values())


def test_bench_cli_text_without_subprocess(capsys):
    code = main(["bench", "--preset", "wall", *SHORT, "--repeats", "1", "--no-cli"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "scene wall (wall, 2 states)" in out
    assert "solve_ivp RK45, Python rhs" in out and "CLI end to end" not in out
    # the goals are explained to a user, not referred to an issue tracker
    assert "issue" not in out and "speed goals of chaospound" in out and "(goal <=" in out


def test_bench_cli_without_the_python_twin(capsys, monkeypatch):
    """An installed package has no benchmarks/: the Python-rhs run is reported missing."""
    import chaospound.bench

    monkeypatch.setattr(chaospound.bench, "load_python_twin", lambda: None)
    code = main(["bench", "--preset", "wall", *SHORT, "--repeats", "1", "--no-cli"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "solve_ivp RK45, Python rhs: not run, " in out and "python_twin.py" in out
    assert "solve_ivp RK45, numba rhs" in out and "x wall vs Python rhs" not in out


def test_bench_cli_rejects_zero_repeats(capsys):
    code = main(["bench", "--repeats", "0"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith("chaospound: error: --repeats 0") and err.count("\n") == 1


# ----------------------------------------------------------------- helpers
def _regime(d_lo: float, d_hi: float) -> str:
    if d_lo <= 0.0 and d_hi <= 0.0:
        return "none"
    if d_lo == d_hi:
        return "full"  # translational models: one penetration
    if d_lo <= 0.0 or d_hi <= 0.0:
        return "partial"
    mean = 0.5 * (d_lo + d_hi)
    return "series" if abs(0.5 * (d_hi - d_lo)) < EPS_SERIES * mean else "skewed"
