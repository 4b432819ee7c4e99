"""The store's promise under hostile conditions: a point the store reports as done is
complete and correct whatever happens to any process at any moment, nothing committed is
lost, and a resumed sweep equals an uninterrupted one bit for bit.

Every test drives the real command line in real processes and kills them with SIGKILL
(the main process alone, or its whole process group) at random moments, including
during a resume and during the final consolidation; fills a small tmpfs; and starts
writers that compete for one output. After every kill the output must open, every point
it shows as done must equal the uninterrupted run's, and ``--resume`` must finish it.
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from storecheck import assert_same_store, bitwise

from chaospound.journal import journal_path
from chaospound.store import open_sweep, sweep_progress

ROOT = Path(__file__).resolve().parents[1]
#: a cheap, impacting scan: the wall preset, 20 + 4 cycles a point (the paper's window:
#: what is tested here is the store, and the converged default spends up to 2000 cycles
#: on a point; tests/test_sweep.py kills and resumes the default), 2 workers, small chunks
GRID = ["--preset", "wall", "--set", "transient=20", "--set", "record=4", "--classify", "paper",
        "--workers", "2", "--chunk", "2", "--quiet"]


def env() -> dict:
    return dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT),
                                                        os.environ.get("PYTHONPATH", "")]))


def sweep_command(path: Path, points: int, *extra: str) -> list[str]:
    return [sys.executable, "-m", "chaospound", "sweep", *GRID, "--param",
            f"period_ratio=0.3:2.0#{points}", "-o", str(path), *extra]


def start(path: Path, points: int, *extra: str, **kwargs) -> subprocess.Popen:
    return subprocess.Popen(sweep_command(path, points, *extra), env=env(),
                            stdout=kwargs.pop("stdout", subprocess.DEVNULL),
                            stderr=kwargs.pop("stderr", subprocess.PIPE), text=True,
                            start_new_session=True, **kwargs)


def kill(proc: subprocess.Popen, group: bool) -> None:
    with _suppress():
        if group:
            os.killpg(proc.pid, signal.SIGKILL)
        else:
            proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)


class _suppress:
    def __enter__(self):
        return self

    def __exit__(self, kind, value, tb):
        return kind is not None and issubclass(kind, ProcessLookupError)


def reap_group(proc: subprocess.Popen) -> None:
    """After a kill of the main process alone: the workers must follow it on their own;
    the group is cleared here only so that a failing test leaves nothing running."""
    with _suppress():
        os.killpg(proc.pid, signal.SIGKILL)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """Uninterrupted runs, one per grid size."""
    folder = tmp_path_factory.mktemp("reference")
    made: dict[int, Path] = {}

    def get(points: int) -> Path:
        if points not in made:
            path = folder / f"wall-{points}.h5"
            proc = subprocess.run(sweep_command(path, points), env=env(), capture_output=True,
                                  text=True, timeout=600)
            assert proc.returncode == 0, proc.stderr
            made[points] = path
        return made[points]

    return get


def assert_committed_points_correct(path: Path, reference: Path) -> int:
    """The output opens (journal or file); its done points equal the reference's."""
    partial, full = open_sweep(path), open_sweep(reference)
    done = np.flatnonzero(partial.array("status") != 0)
    for name in ("status", "regime", "steps", "rhs_evals", "final_state", "strobe_mismatch",
                 "impact_count", "strobe_count"):
        assert bitwise(partial.array(name)[done], full.array(name)[done]), name
    for i in done[:: max(1, done.size // 50)]:  # the flat arrays, on a sample of points
        assert bitwise(partial.strobe(i), full.strobe(i))
        for name in ("time", "velocity", "peak_force"):
            assert bitwise(partial.impacts(i)[name], full.impacts(i)[name])
    return int(done.size)


def wait_for(predicate, timeout: float, pause: float = 0.002) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(pause)
    return False


def consolidating(path: Path) -> bool:
    return any(path.parent.glob(path.name + ".tmp-*"))


def storm(tmp_path: Path, reference: Path, points: int, kills: int, seed: int) -> dict:
    """``kills`` sweeps of one output, each SIGKILLed at a random moment (some right as
    the consolidation starts), each followed by a resume that is itself the next victim
    (or, once a run got to finish the file, by an --overwrite run); a last resume finishes
    the file. After every kill the journal's done points and any file at the output's
    name are checked against the reference. Returns what happened."""
    rng = random.Random(seed)
    path = tmp_path / "storm.h5"
    seen = {"killed": 0, "during_consolidation": 0, "finished_early": 0, "group": 0}
    full_run = None
    for k in range(kills):
        began = time.monotonic()
        finished = path.exists() and not journal_path(path).exists()
        # a finished file is swept again with --overwrite: it must survive until replaced
        option = ["--overwrite"] if finished else ["--resume"] if k else []
        proc = start(path, points, *option)
        group = rng.random() < 0.5
        if rng.random() < 0.25:  # aim at the consolidation: kill as its temporary appears
            hit = wait_for(lambda p=proc: consolidating(path) or p.poll() is not None, 120,
                           0.0005)
            if hit and proc.poll() is None:
                time.sleep(rng.uniform(0.0, 0.03))
                seen["during_consolidation"] += 1
        else:
            horizon = full_run if full_run is not None else 4.0
            time.sleep(rng.uniform(0.2, 1.2 * horizon))
        if proc.poll() is None:
            kill(proc, group)
            seen["killed"] += 1
            seen["group"] += group
        else:
            proc.wait()
            assert proc.returncode == 0, proc.stderr.read()
            seen["finished_early"] += 1
            full_run = time.monotonic() - began
        reap_group(proc)
        proc.stderr.close()
        if journal_path(path).exists():
            assert_committed_points_correct(path, reference)
        if path.exists():  # a file at the output's name is always a finished, correct one
            assert_same_store(path, reference)
    proc = subprocess.run(sweep_command(path, points, "--resume"), env=env(),
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    assert not journal_path(path).exists()
    assert not consolidating(path) and not Path(f"{path}.lock").exists()
    assert_same_store(path, reference)
    return seen


def test_kill_storm(tmp_path, reference):
    """20 kills (main process or whole group, in resumes and in consolidations)."""
    seen = storm(tmp_path, reference(600), 600, kills=20, seed=13)
    assert seen["killed"] >= 10, seen


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(10))
def test_kill_storm_long(tmp_path, reference, seed):
    """10 x 20 = 200 kills over sweeps of different lengths."""
    points = (400, 900, 1500)[seed % 3]
    seen = storm(tmp_path, reference(points), points, kills=20, seed=seed)
    assert seen["killed"] >= 10, seen


def test_resume_of_a_finished_file_says_so(tmp_path, reference):
    path = tmp_path / "done.h5"
    shutil.copy(reference(600), path)
    before = path.read_bytes()
    proc = subprocess.run(sweep_command(path, 600, "--resume"), env=env(), capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "finished already" in proc.stdout and "600 points" in proc.stdout
    assert path.read_bytes() == before


def test_summary_of_a_resumed_sweep_counts_every_point(tmp_path, reference):
    for points in (600, 2400, 9600):  # finished before the kill (a fast host): a longer one
        path = tmp_path / f"resumed-{points}.h5"
        proc = start(path, points)
        assert wait_for(lambda p=path: journal_path(p).exists() and sweep_progress(p)[0] > 100,
                        120, 0.02)
        kill(proc, group=True)
        proc.stderr.close()
        done, total = sweep_progress(path)
        assert total == points
        if done < total:
            break
    assert 0 < done < total
    proc = subprocess.run(sweep_command(path, points, "--resume"), env=env(),
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    first, regimes = proc.stdout.splitlines()[:2]
    assert f"{points - done} points computed ({points} in the grid)" in first
    assert f"{points} stored in all" in first
    counts = [int(word) for word in regimes.replace(",", " ").replace(";", " ").split()
              if word.isdigit()]
    assert sum(counts) == points  # regimes and failures of all the grid's points
    assert_same_store(path, reference(points))


# ------------------------------------------------------------------ orphans


def children_of(pid: int) -> list[int]:
    psutil = pytest.importorskip("psutil")
    return [c.pid for c in psutil.Process(pid).children(recursive=True)]


def alive(pid: int) -> bool:
    psutil = pytest.importorskip("psutil")
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def test_workers_die_with_their_parent_and_release_its_pipes(tmp_path):
    """SIGKILL of the main process alone: no worker is alive 2 s later, the pipe the
    sweep wrote to reaches end-of-file (``| tee log`` ends), and --resume is accepted."""
    path = tmp_path / "orphans.h5"
    proc = start(path, 4000, stdout=subprocess.PIPE)
    assert wait_for(lambda: journal_path(path).exists() and sweep_progress(path)[0] > 0, 120,
                    0.02)
    workers = children_of(proc.pid)
    assert len(workers) >= 2, workers
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    killed_at = time.monotonic()
    assert wait_for(lambda: not any(alive(w) for w in workers), 2.0, 0.02), \
        [w for w in workers if alive(w)]
    assert proc.stdout.read() == ""  # end of file: no process holds the pipe any more
    assert time.monotonic() - killed_at < 5
    reap_group(proc)
    proc.stdout.close()
    proc.stderr.close()
    resumed = start(path, 4000, "--resume")
    time.sleep(1.0)
    assert resumed.poll() is None, resumed.stderr.read()  # not refused: it is computing
    kill(resumed, group=True)
    resumed.stderr.close()


# -------------------------------------------------------------- two writers


def test_one_writer_per_output(tmp_path, reference):
    """Four simultaneous starts on one path: exactly one writes, the others exit 2 with one
    line; --overwrite and --resume against the running sweep are refused likewise, naming
    it; the file ends equal to the uninterrupted run."""
    path = tmp_path / "contested.h5"
    procs = [start(path, 600) for _ in range(4)]
    codes = [p.wait(timeout=600) for p in procs]
    errors = [p.stderr.read() for p in procs]
    for p in procs:
        p.stderr.close()
    assert sorted(codes) == [0, 2, 2, 2], (codes, errors)
    for code, err in zip(codes, errors, strict=True):
        if code == 2:
            lines = err.splitlines()
            assert len(lines) == 1 and lines[0].startswith("chaospound: error: "), err
            assert "running sweep" in lines[0] or "exists" in lines[0], err
    assert_same_store(path, reference(600))

    path = tmp_path / "running.h5"
    proc = start(path, 4000)
    assert wait_for(lambda: journal_path(path).exists() and sweep_progress(path)[0] > 0, 120,
                    0.02)
    # paused, not finished: with warm caches the 4000 points can end before the contenders
    # start; a stopped sweep still holds its output, and SIGKILL ends it below all the same
    os.killpg(proc.pid, signal.SIGSTOP)
    for option in ("--overwrite", "--resume"):
        other = subprocess.run(sweep_command(path, 4000, option), env=env(),
                               capture_output=True, text=True, timeout=120)
        assert other.returncode == 2, other.stderr
        lines = other.stderr.splitlines()
        assert len(lines) == 1 and f"pid {proc.pid}" in lines[0], other.stderr
    assert proc.poll() is None  # the running sweep goes on
    kill(proc, group=True)
    proc.stderr.close()
    done = assert_committed_points_correct(path, reference_4000(tmp_path, path))
    assert done > 0


def reference_4000(tmp_path: Path, killed: Path) -> Path:
    """The uninterrupted 4000-point file, made by resuming a copy of the killed one."""
    copy = tmp_path / "finished-4000.h5"
    for src in killed.parent.glob(killed.name + ".journal*"):
        shutil.copy(src, copy.parent / src.name.replace(killed.name, copy.name))
    proc = subprocess.run(sweep_command(copy, 4000, "--resume"), env=env(), capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return copy


def test_a_stale_lock_is_taken_over(tmp_path, reference):
    """A lock file left by a killed sweep (no process holds it) does not block the resume."""
    path = tmp_path / "stale.h5"
    Path(f"{path}.lock").write_text("pid 999999 on nowhere, since long ago\n")
    proc = subprocess.run(sweep_command(path, 600), env=env(), capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert not Path(f"{path}.lock").exists()
    assert_same_store(path, reference(600))


# ------------------------------------------------------------------ full disk


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MB tmpfs (skipped where mounting is not allowed)."""
    mount = tmp_path / "disk"
    mount.mkdir()
    if shutil.which("mount") is None or os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root and mount(8)")
    proc = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(mount)],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {proc.stderr.strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], capture_output=True)


def test_full_disk_exits_1_and_the_committed_points_resume(small_disk, reference):
    """The disk fills mid-sweep: exit 1 with one line, the journal stays readable with its
    committed points intact; with space again, --resume gives the uninterrupted file."""
    path = small_disk / "full.h5"
    proc = subprocess.run(sweep_command(path, 4000), env=env(), capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 1, (proc.returncode, proc.stderr)
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("chaospound: error: "), proc.stderr
    assert "--resume" in lines[0]
    reference_file = reference(4000)
    done = assert_committed_points_correct(path, reference_file)
    assert done > 0
    subprocess.run(["mount", "-o", "remount,size=256m", str(small_disk)], check=True)
    proc = subprocess.run(sweep_command(path, 4000, "--resume"), env=env(),
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert_same_store(path, reference_file)


# ------------------------------------------------------------------------ Dask


def dask_storm(tmp_path: Path, reference: Path, points: int, kills: int, seed: int) -> dict:
    """The storm on the Dask backend (``--scheduler local``): the client process killed
    (alone or with its cluster's process group), or one of its worker processes killed
    while the sweep goes on (the nanny restarts it and its tasks are rerun)."""
    pytest.importorskip("distributed")
    psutil = pytest.importorskip("psutil")
    rng = random.Random(seed)
    path = tmp_path / "dask-storm.h5"
    seen = {"client_killed": 0, "worker_killed": 0, "finished": 0}
    for k in range(kills):
        finished = path.exists() and not journal_path(path).exists()
        option = ["--overwrite"] if finished else ["--resume"] if k else []
        journal = journal_path(path)
        before = sweep_progress_or_zero(path) if journal.exists() else 0
        proc = start(path, points, "--scheduler", "local", *option)
        def committed(p=proc, journal=journal, before=before) -> bool:  # this run's first
            return (journal.exists() and sweep_progress_or_zero(path) > before) \
                or p.poll() is not None

        if not wait_for(committed, 120, 0.02):
            pytest.fail("the Dask sweep never committed a point")
        if rng.random() < 0.3 and proc.poll() is None:  # a worker dies, the sweep goes on
            workers = [c for c in psutil.Process(proc.pid).children(recursive=True)
                       if "spawn_main" in " ".join(c.cmdline())]
            if workers:
                rng.choice(workers).kill()
                seen["worker_killed"] += 1
        time.sleep(rng.uniform(0.0, 2.0))
        if proc.poll() is None:
            kill(proc, group=rng.random() < 0.5)
            seen["client_killed"] += 1
        else:
            assert proc.wait() == 0, proc.stderr.read()
            seen["finished"] += 1
        reap_group(proc)
        proc.stderr.close()
        if journal_path(path).exists():
            assert_committed_points_correct(path, reference)
        if path.exists():
            assert_same_store(path, reference)
    proc = subprocess.run(sweep_command(path, points, "--resume"), env=env(),
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert_same_store(path, reference)
    return seen


def sweep_progress_or_zero(path: Path) -> int:
    """Points done so far; 0 before the sweep has written anything."""
    if not (path.exists() or journal_path(path).exists()):
        return 0
    try:
        return sweep_progress(path)[0]
    except Exception:  # noqa: BLE001 - not there yet
        return 0


def test_dask_client_killed_then_resumed(tmp_path, reference):
    """One kill of a Dask sweep's client (and its local cluster), then --resume."""
    seen = dask_storm(tmp_path, reference(600), 600, kills=1, seed=3)
    assert seen["client_killed"] + seen["finished"] == 1


@pytest.mark.slow
def test_dask_kill_storm(tmp_path, reference):
    """20 kills of Dask clients and workers, each followed by a resume."""
    seen = dask_storm(tmp_path, reference(1500), 1500, kills=20, seed=7)
    assert seen["client_killed"] >= 10 and seen["worker_killed"] >= 2, seen


def test_read_only_folder_is_one_line(tmp_path):
    """An output in a read-only file system: exit 2, one line naming the folder, nothing
    written (skipped where mounting is not allowed)."""
    mount = tmp_path / "ro"
    mount.mkdir()
    if shutil.which("mount") is None or os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root and mount(8)")
    proc = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(mount)],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {proc.stderr.strip()}")
    try:
        proc = subprocess.run(sweep_command(mount / "x.h5", 10), env=env(),
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 2, proc.stderr
        lines = proc.stderr.splitlines()
        assert len(lines) == 1 and "cannot create files in" in lines[0], proc.stderr
        assert list(mount.iterdir()) == []
    finally:
        subprocess.run(["umount", "-l", str(mount)], capture_output=True)
