"""The HDF5 sweep store: the documented schema, bitwise agreement with the
drivers run alone, crash recovery, and refusal of foreign files.

Every number in a sweep file must be the number :func:`chaospound.simulate`
(and :func:`chaospound.lyapunov_spectrum`) give for the same point run alone,
with the same starting state; continuation must mean "start from the
previous point's last stroboscopic state at the section"; a run killed at
any moment must leave a file whose finished points are complete and which a
resume turns into the uninterrupted file.
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import h5py
import numpy as np
import pytest
from storecheck import assert_same_store, bitwise, store_contents  # noqa: F401

import chaospound
from chaospound import store
from chaospound.dynamics.lyapunov import lyapunov_spectrum
from chaospound.scene import STATE_NAMES, Scene, load_preset
from chaospound.simulate import simulate
from chaospound.store import (
    IMPACT_FIELDS,
    REGIMES,
    SweepStoreError,
    SweepWriter,
    open_sweep,
)
from chaospound.sweep import SweepSpec, parse_axis, run_point, run_sweep

#: the towers model of the paper's Fig. 4, shortened (20 + 4 cycles)
FIG4 = load_preset("fig4").with_params(transient=20, record=4)
WALL = load_preset("wall").with_params(transient=20, record=4)

# ------------------------------------------------------------------ helpers











def sweep_of(scene: Scene, grid: str, **options) -> SweepSpec:
    return SweepSpec((parse_axis(grid, scene),), **options)


# ---------------------------------------------------------------- schema

#: every dataset of a branch: (dtype, shape) with N points, n states, k exponents,
#: I impact rows and M stroboscopic rows
BRANCH_DATASETS = {
    "order": (np.int64, ("N",)),
    "status": (np.int8, ("N",)),
    "message": ("S", ("N",)),
    "regime": (np.int8, ("N",)),
    "impacts_per_period": (np.int16, ("N",)),
    "period_cycles": (np.int16, ("N",)),
    "transient_used": (np.int32, ("N",)),
    "corner_sequence": ("S", ("N",)),
    "strobe_mismatch": (np.float64, ("N",)),
    "zero_one": (np.float64, ("N",)),
    "max_exponent": (np.float64, ("N",)),
    "max_exponent_error": (np.float64, ("N",)),
    "exponents": (np.float64, ("N", "k")),
    "final_state": (np.float64, ("N", "n")),
    "steps": (np.int64, ("N",)),
    "rejected": (np.int64, ("N",)),
    "rhs_evals": (np.int64, ("N",)),
    "wall_s": (np.float64, ("N",)),
    "impact_start": (np.int64, ("N",)),
    "impact_count": (np.int64, ("N",)),
    **{f"impacts/{name}": (np.int8 if name == "corner" else np.float64, ("I",))
       for name in IMPACT_FIELDS},
    "strobe_start": (np.int64, ("N",)),
    "strobe_count": (np.int64, ("N",)),
    "strobe/state": (np.float64, ("M", "n")),
}
ROOT_ATTRIBUTES = ("format", "format_version", "chaospound_version", "scene", "scene_resolved",
                   "sweep", "units", "model", "state_names", "created", "wall_s")
BRANCH_ATTRIBUTES = ("impacts_committed", "strobe_committed", "REGIMES")


@pytest.fixture(scope="module")
def both_file(tmp_path_factory) -> Path:
    """fig4, 8 points of T/T_Ax, forward and backward continuation, 2 exponents (the
    paper's window procedure: each point's record is its own simulate run)."""
    path = tmp_path_factory.mktemp("store") / "both.h5"
    spec = sweep_of(FIG4, "period_ratio=0.6:1.3#8", continuation="both", lyapunov=2,
                    lyapunov_cycles=10, classify="paper")
    run_sweep(FIG4, spec, path, progress=False)
    return path


@pytest.fixture(scope="module")
def fresh_file(tmp_path_factory) -> Path:
    """fig4, 6 points from the scene's initial state, no exponents (the window
    procedure, as both_file)."""
    path = tmp_path_factory.mktemp("store") / "fresh.h5"
    run_sweep(FIG4, sweep_of(FIG4, "period_ratio=0.5,0.8,1.0,1.2,1.6,1.9", classify="paper"),
              path, progress=False)
    return path


def test_schema_matches_the_documentation(both_file):
    """Every documented dataset and attribute, with its dtype and shape, and nothing else."""
    for name in [*BRANCH_DATASETS, *ROOT_ATTRIBUTES, *BRANCH_ATTRIBUTES, "grid"]:
        assert name.rsplit("/", 1)[-1] in store.__doc__, f"{name} is not documented"
    n = len(STATE_NAMES[FIG4.model_id()])
    with h5py.File(both_file, "r") as f:
        assert set(f.attrs) == set(ROOT_ATTRIBUTES)
        assert f.attrs["format"] == store.FORMAT
        assert int(f.attrs["format_version"]) == store.FORMAT_VERSION
        assert f.attrs["chaospound_version"] == chaospound.__version__
        assert Scene.from_toml(f.attrs["scene"]) == FIG4
        assert json.loads(f.attrs["scene_resolved"]) == json.loads(json.dumps(FIG4.to_dict()))
        assert json.loads(f.attrs["state_names"]) == list(STATE_NAMES[FIG4.model_id()])
        assert f.attrs["model"] == FIG4.model_name
        assert set(json.loads(f.attrs["units"])) >= {"time", "length", "velocity", "exponents"}
        sweep = json.loads(f.attrs["sweep"])
        assert sweep["parameters"] == ["period_ratio"] and sweep["branches"] == ["forward",
                                                                                 "backward"]
        assert float(f.attrs["wall_s"]) > 0.0
        assert list(f["grid"]) == ["period_ratio"]
        grid = f["grid"]["period_ratio"]
        assert grid.dtype == np.float64  # 0.6:1.3#8: step 0.1, the typed decimals
        assert grid[()].tolist() == [0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3]
        assert set(f) == {"grid", "forward", "backward"}
        sizes = {"N": 8, "n": n, "k": 2}
        for branch in ("forward", "backward"):
            g = f[branch]
            found = set()
            g.visititems(lambda name, obj, found=found: found.add(name)
                         if isinstance(obj, h5py.Dataset) else None)
            assert found == set(BRANCH_DATASETS)
            sizes["I"] = int(g["impact_count"][()].sum())
            sizes["M"] = int(g["strobe_count"][()].sum())
            for name, (dtype, shape) in BRANCH_DATASETS.items():
                ds = g[name]
                if dtype == "S":
                    assert ds.dtype.kind == "S", name
                else:
                    assert ds.dtype == dtype, name
                assert ds.shape == tuple(sizes[s] for s in shape), name
            assert set(g.attrs) == set(BRANCH_ATTRIBUTES)
            assert int(g.attrs["impacts_committed"]) == sizes["I"]
            assert int(g.attrs["strobe_committed"]) == sizes["M"]
            assert tuple(json.loads(g.attrs["REGIMES"])) == REGIMES
            # the flat arrays are appended in the branch's visiting order, without gaps
            order = g["order"][()]
            expected = np.arange(8) if branch == "forward" else np.arange(8)[::-1]
            assert bitwise(order, expected.astype(np.int64))
            for start, count in (("impact_start", "impact_count"),
                                 ("strobe_start", "strobe_count")):
                counts = g[count][()][order]
                assert bitwise(g[start][()][order],
                               np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int64))
            assert np.all(g["status"][()] == store.STATUS_DONE)
            assert np.all(g["strobe_count"][()] == FIG4.run.record + 1)


def test_fresh_points_equal_simulate_alone(fresh_file):
    """Each point of a fresh sweep is bitwise the run simulate() gives for it alone."""
    sweep = open_sweep(fresh_file)
    assert sweep.branches == ["fresh"] and sweep.parameters == ["period_ratio"]
    period_ratios = sweep.grid["period_ratio"]
    assert bitwise(sweep.points()[:, 0], period_ratios)
    impacting = 0
    for i, value in enumerate(period_ratios):
        sim = simulate(FIG4.with_params(period_ratio=float(value)))
        assert_point_equals_simulation(sweep, "fresh", i, sim)
        impacting += len(sim.impacts) > 0
    assert impacting >= 3, "the grid should contain impacting points"
    with h5py.File(fresh_file, "r") as f:
        assert "exponents" not in f["fresh"]
        assert np.all(np.isnan(f["fresh"]["max_exponent"][()]))


def test_continuation_points_equal_simulate_from_the_previous_state(both_file):
    """Forward and backward chains: each point is simulate() started at the section from the
    previous point's last stroboscopic state (the first from the scene's initial state), and
    its exponents are lyapunov_spectrum() from the point's last section."""
    sweep = open_sweep(both_file)
    values = sweep.grid["period_ratio"]
    for branch, chain in (("forward", range(8)), ("backward", range(7, -1, -1))):
        state = None
        exponents = sweep.array("exponents", branch)
        for i in chain:
            point = FIG4.with_params(period_ratio=float(values[i]))
            sim = simulate(point, initial_state=state, start_at_section=state is not None)
            assert_point_equals_simulation(sweep, branch, i, sim)
            spectrum = lyapunov_spectrum(point, k=2, transient=0,
                                         initial_state=sim.strobe.state[-1], cycles=10,
                                         tangent_transient=10)
            assert bitwise(exponents[i], spectrum.exponents)
            assert bitwise(sweep.array("max_exponent", branch)[i], spectrum.exponents[0])
            assert bitwise(sweep.array("max_exponent_error", branch)[i], spectrum.errors[0])
            state = sim.strobe.state[-1]


def assert_point_equals_simulation(sweep, branch, i, sim) -> None:
    imp = sweep.impacts(i, branch)
    for name in ("time", "phase", "velocity", "peak_penetration", "peak_force", "duration"):
        assert bitwise(imp[name], getattr(sim.impacts, name)), (branch, i, name)
    assert list(imp["corner"]) == sim.impacts.labels
    assert bitwise(sweep.strobe(i, branch), sim.strobe.state)
    assert bitwise(sweep.array("final_state", branch)[i], sim.strobe.state[-1])
    assert sweep.array("steps", branch)[i] == sim.stats.steps
    assert sweep.array("rejected", branch)[i] == sim.stats.rejected
    assert sweep.array("rhs_evals", branch)[i] == sim.stats.rhs_evals
    assert sweep.status(branch)[i] == "done"
    # impacts lie in the record window, in time order
    period = sim.scene.period
    t0 = sim.strobe.time[0]
    assert np.all(np.diff(imp["time"]) > 0)
    assert np.all((imp["time"] >= t0 - 1e-9 * period)
                  & (imp["time"] <= t0 + sim.record * period))
    regime = sweep.regimes(branch)[i]
    if len(sim.impacts) == 0:
        assert regime == "none"
    else:
        assert regime != "none"
    if regime in ("periodic", "group-periodic"):
        n = int(sweep.array("impacts_per_period", branch)[i])
        period_cycles = int(sweep.array("period_cycles", branch)[i])
        assert n >= 1 and period_cycles >= 1
        if sim.record % period_cycles == 0:  # a whole number of periods in the window
            assert len(sim.impacts) == n * sim.record // period_cycles


def test_reader_api(both_file):
    sweep = open_sweep(both_file)
    assert sweep.shape == (8,)
    assert sweep.state_names == list(STATE_NAMES[FIG4.model_id()])
    assert len(sweep.impact_velocities("backward")) == 8
    assert all(r in REGIMES for r in sweep.regimes("forward"))
    assert sweep.messages("forward") == [""] * 8
    with pytest.raises(SweepStoreError, match="branch 'fresh'"):
        sweep.array("status", "fresh")
    assert chaospound.open_sweep is open_sweep
    assert chaospound.run_sweep is run_sweep


# ------------------------------------------------------------ crash recovery


@pytest.mark.parametrize("killed_after", ["data", "statuses"])
def test_resume_after_a_kill_inside_a_commit(tmp_path, killed_after):
    """A run killed inside a commit: after flushing a batch's data but before its statuses
    ("data"), or after its statuses but before the committed lengths ("statuses"). The
    file shows the first points done; resuming gives the uninterrupted file."""
    spec = sweep_of(WALL, "period_ratio=0.6:1.2#6")
    reference = tmp_path / "reference.h5"
    run_sweep(WALL, spec, reference, progress=False)
    path = tmp_path / "killed.h5"
    path.write_bytes(reference.read_bytes())
    with h5py.File(path, "r+") as f:  # roll the file back to "3 points committed"
        group = f["fresh"]
        assert group["impact_count"][3:].sum() > 0
        if killed_after == "data":
            group["status"][3:] = store.STATUS_PENDING
        group.attrs["impacts_committed"] = group["impact_count"][:3].sum()
        group.attrs["strobe_committed"] = group["strobe_count"][:3].sum()
    done = [s == "done" for s in open_sweep(path).status()]
    assert done == [True] * 3 + [killed_after == "statuses"] * 3
    run_sweep(WALL, spec, path, resume=True, progress=False)
    assert_same_store(path, reference)


# ------------------------------------------------------------ foreign files


def test_foreign_files_are_refused_and_left_alone(tmp_path):
    spec = sweep_of(WALL, "period_ratio=0.6:1.2#3")
    text = tmp_path / "notes.h5"
    text.write_text("not hdf5\n")
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = np.arange(3)
    different = tmp_path / "different.h5"
    run_sweep(WALL, sweep_of(WALL, "period_ratio=0.6:1.2#4"), different, progress=False)
    for path, match in ((text, "not a readable HDF5 file"),
                        (other, "not a chaospound sweep store"),
                        (tmp_path / "missing.h5", "no such file"),
                        (tmp_path, "is a directory, not a sweep store")):
        with pytest.raises(SweepStoreError, match=match):
            open_sweep(path)
    for path, options, match in (
        (text, {"resume": True}, "not a readable HDF5 file"),
        (other, {"resume": True}, "not a chaospound sweep store"),
        (different, {"resume": True}, "different sweep"),
        (different, {}, "file exists"),
        (text, {"overwrite": True}, "not a readable HDF5 file.*left as it is"),
        (other, {"overwrite": True}, "not a chaospound sweep store.*left as it is"),
    ):
        before = (path.read_bytes(), os.stat(path).st_mtime_ns)
        with pytest.raises(SweepStoreError, match=match):
            run_sweep(WALL, spec, path, progress=False, **options)
        assert (path.read_bytes(), os.stat(path).st_mtime_ns) == before
    # a different scene is a different sweep too, and the message names what differs
    changed = dataclasses.replace(WALL, name="renamed")
    with pytest.raises(SweepStoreError, match=r'different sweep or scene \(name: "wall" in '
                                              r'the file, "renamed" now\)'):
        run_sweep(changed, sweep_of(changed, "period_ratio=0.6:1.2#4"), different, resume=True,
                  progress=False)


def test_messages_survive_truncation(tmp_path):
    """A failure message cut inside a multi-byte character still reads back."""
    spec = sweep_of(WALL, "period_ratio=0.6,0.7")
    path = tmp_path / "messages.h5"
    failed = run_point(WALL.with_params(max_steps=5), spec, 0)
    assert failed.status == 2
    failed.message = "é" * store.MESSAGE_LENGTH
    meta = {"scene": WALL.to_toml(), "sweep": spec.to_json()}
    with SweepWriter(path, meta, {"period_ratio": spec.axes[0].values},
                     {"fresh": spec.order("fresh")}, 2, 0) as writer:
        writer.write("fresh", [failed])
    message = open_sweep(path).messages()[0]
    assert message.startswith("é" * 10) and len(message.encode()) <= store.MESSAGE_LENGTH + 3


# ------------------------------------------------------------ analysis API


def test_to_xarray_round_trips_every_dataset(both_file):
    """Every dataset of both branches comes back through to_xarray, bit for bit, with the
    swept parameters as named dimensions, regimes as strings and units as attributes."""
    xr = pytest.importorskip("xarray")
    sweep = open_sweep(both_file)
    with h5py.File(both_file, "r") as f:
        for branch in sweep.branches:
            ds = sweep.to_xarray(branch)
            assert isinstance(ds, xr.Dataset) and ds.attrs["branch"] == branch
            g = f[branch]
            names = []
            g.visititems(lambda n, obj, names=names: names.append(n)
                         if isinstance(obj, h5py.Dataset) else None)
            for name in names:
                stored = g[name][()]
                if name.startswith("impacts/"):
                    var = ds[f"impact_{name.split('/')[1]}"].values
                    if name.endswith("corner"):
                        from chaospound.physics.corners import CORNER_LABELS
                        stored = np.array([CORNER_LABELS[int(c)] for c in stored])
                        assert list(var) == list(stored)
                        continue
                    assert bitwise(var, stored), name
                elif name == "strobe/state":
                    assert bitwise(ds["strobe_state"].values, stored)
                elif name == "order":
                    assert bitwise(ds["order"].values, stored)
                elif name == "regime":
                    assert list(ds["regime"].values) == [REGIMES[int(c)] for c in stored]
                elif name == "status":
                    assert set(ds["status"].values) == {"done"}
                elif stored.dtype.kind == "S":
                    assert list(ds[name].values) == [v.decode() for v in stored]
                else:
                    assert ds[name].dims[0] == "period_ratio"
                    assert bitwise(ds[name].values, stored), name
            assert ds["impact_velocity"].attrs["units"] == store.UNITS["velocity"]
            assert ds["max_exponent"].attrs["units"] == store.UNITS["exponents"]
            assert list(ds["state"].values) == sweep.state_names
            value = float(sweep.grid["period_ratio"][3])
            assert ds.sel(period_ratio=value)["steps"].item() == sweep.array("steps", branch)[3]


def test_grid_coordinates_are_the_typed_decimals(tmp_path):
    """start:stop:step grids hold the doubles of the decimals typed (0.8, not
    0.7999999999999999), so that coordinates compare equal to typed values."""
    axis = parse_axis("period_ratio=0.6:1.2:0.1", WALL)
    assert axis.values.tolist() == [0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2]
    assert parse_axis("gap=0.5:1.5:0.25", WALL).values.tolist() == [0.5, 0.75, 1.0, 1.25, 1.5]
    path = tmp_path / "exact.h5"
    run_sweep(WALL, SweepSpec((axis,)), path, progress=False)
    with open_sweep(path) as sweep:
        ds = sweep.to_xarray()
        assert ds.sel(period_ratio=0.8)["regime"].item() == sweep.regimes()[2]
        assert ds.sel(period_ratio=0.9)["steps"].item() == sweep.array("steps")[3]


def test_count_grids_with_a_decimal_step_hold_the_typed_decimals(tmp_path):
    """start:stop#count grids whose step is a decimal hold its decimals too (0.85:0.95#5:
    0.9, where numpy.linspace gives 0.8999999999999999); other count grids stay
    numpy.linspace bitwise (the fig4 scan's 0.3:2.0#1000, step 1.7 / 999)."""
    from fractions import Fraction

    axis = parse_axis("period_ratio=0.85:0.95#5", WALL)
    assert axis.values.tolist() == [0.85, 0.875, 0.9, 0.925, 0.95]
    for grid in ("0:1#11", "-8:4#121", "-2:2#201", "1.5:0.5#201", "0.5:3.0#26", "1e-3:2e-3#5"):
        (start, stop), count = grid.split("#")[0].split(":"), int(grid.split("#")[1])
        exact = [float(Fraction(start) + k * (Fraction(stop) - Fraction(start)) / (count - 1))
                 for k in range(count)]  # the exact rational, correctly rounded
        assert parse_axis(f"gap={grid}").values.tolist() == exact, grid
    for grid in ("0.3:2.0#1000", "0.5:2.0#200", "0:1#3", "0.1:0.2#7"):
        (start, stop), count = grid.split("#")[0].split(":"), int(grid.split("#")[1])
        assert bitwise(parse_axis(f"gap={grid}").values,
                       np.linspace(float(start), float(stop), count)), grid
    path = tmp_path / "count.h5"
    run_sweep(WALL, SweepSpec((axis,)), path, progress=False)
    with open_sweep(path) as sweep:
        assert sweep.to_xarray().sel(period_ratio=0.9)["regime"].item() == sweep.regimes()[2]


def test_reader_repr_and_errors_name_the_valid_choices(both_file):
    sweep = open_sweep(both_file)
    text = repr(sweep)
    assert text.count("\n") < 10 and "period_ratio 0.6..1.3 (8)" in text
    assert "forward: 8 of 8 done" in text and "backward: 8 of 8 done" in text
    with pytest.raises(SweepStoreError, match="no per-point array 'velocityy'.*max_exponent"):
        sweep.array("velocityy")
    with pytest.raises(SweepStoreError, match="branch 'fresh': the file has forward, backward"):
        sweep.to_xarray("fresh")
