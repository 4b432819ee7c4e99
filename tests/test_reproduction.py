"""The paper reproduction (analysis/reproduce_paper.py) in its quick mode.

Runs ``python analysis/reproduce_paper.py --quick`` once (about 20-40 s) into
a temporary folder and checks physics facts in what it wrote, not only that
it ran:

* Fig. 3: e_Ay/l = +0.1 at T/T_Ax = 0.70 is group-periodic 3-1 with corners
  A+ B- A+ (the paper's C, F, C); e_Ay/l = -0.1 is its mirror image, A- B+ A-,
  with the same impact velocities, translations equal and rotations opposite.
* Fig. 4: the translational spectrum has only "face" impacts (no torsion, no
  corners); the torsional one has corner impacts; the max-velocity ratio
  torsional / translational is computed and > 1.
* e_Ay/l = 0.1 at T/T_Ax = 0.9 is chaotic by the adaptive classifier, 1.5 has
  no impact once steady (classification.md's measured table).
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "analysis" / "reproduce_paper.py"
FIGURES = ("fig3a.png", "fig3b.png", "fig4.png", "fig4_regimes.png", "fig5.png",
           "sensitivity_length.png", "sensitivity_transient.png")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def quick(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("paper")
    scratch = tmp_path_factory.mktemp("scratch")
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--out", str(out), "--scratch", str(scratch)],
        capture_output=True, text=True, timeout=600, cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out


def read_csv(path: Path) -> list[dict]:
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


def test_figures_are_png_files(quick):
    for name in FIGURES:
        data = (quick / name).read_bytes()
        assert data[:8] == PNG_MAGIC, name
        assert len(data) > 20_000, f"{name} looks empty ({len(data)} bytes)"


def test_fig3a_group_periodic_3_1_at_corners_c_f_c(quick):
    fig3 = json.loads((quick / "fig3.json").read_text())
    a = fig3["fig3a"]
    assert a["regime"] == "group-periodic 3-1"
    assert a["corner_sequence"] == ["A+", "B-", "A+"]
    # the numbered impacts of the last cycle: three, at those corners, with distinct velocities
    last = a["last_cycle_impacts"]
    assert [i["corner"] for i in last] == ["A+", "B-", "A+"]
    velocities = [i["velocity"] for i in last]
    assert min(abs(x - y) for k, x in enumerate(velocities) for y in velocities[k + 1:]) > 0.1


def test_fig3b_is_the_mirror_image(quick):
    fig3 = json.loads((quick / "fig3.json").read_text())
    b = fig3["fig3b"]
    assert b["regime"] == "group-periodic 3-1"
    assert b["corner_sequence"] == ["A-", "B+", "A-"]
    assert fig3["velocities_equal"]
    mirror = fig3["mirror"]
    assert mirror["X_A"]["relation"] == "equal" and mirror["th_A"]["relation"] == "opposite"
    # y -> -y maps the two scenes onto each other exactly: the equations are symmetric
    assert fig3["mirror_max_relative_deviation"] < 1e-9
    assert mirror["th_A"]["amplitude"] > 0.01  # and the rotation is not trivially zero


def test_translational_spectrum_has_only_face_impacts(quick):
    rows = read_csv(quick / "spectrum_translational.csv")
    corners = {c for r in rows for c in r["corners"].split()}
    assert corners == {"face"}
    torsional = read_csv(quick / "spectrum_torsional.csv")
    corners = {c for r in torsional for c in r["corners"].split()}
    assert corners and "face" not in corners  # eccentric towers hit at corners


def test_max_velocity_ratio_is_computed(quick):
    claims = json.loads((quick / "claims.json").read_text())
    ratio = claims["max_ratio_torsional_translational"]["window_1000"]
    assert ratio["max"] > 1.0 and ratio["p99"] > 1.0
    vel = claims["velocities"]
    tor = vel["torsional"]["window_1000"]
    tra = vel["translational"]["window_1000"]
    assert ratio["max"] == pytest.approx(tor["max"] / tra["max"], rel=1e-4)
    assert tra["p99"] <= tra["max"] and tor["p99"] <= tor["max"]
    assert "ecc_doubling_change_percent" in claims


def test_adaptive_classification_at_known_points(quick):
    rows = {round(float(r["period_ratio"]), 3): r for r in
            read_csv(quick / "adaptive_torsional.csv")}
    assert rows[0.7]["label"] == "group-periodic 3-1"
    assert rows[0.7]["corner_sequence"] == "A+ B- A+"
    assert rows[0.9]["regime"] == "chaotic"
    assert float(rows[0.9]["lambda"]) > 3 * float(rows[0.9]["lambda_err"])
    assert rows[1.5]["regime"] == "none"
    translational = {round(float(r["period_ratio"]), 3): r for r in
                     read_csv(quick / "adaptive_translational.csv")}
    # two face impacts per cycle with different velocities: n > P under docs/model.md's rule
    assert translational[0.9]["label"] == "group-periodic 2-1"
    assert translational[0.9]["corner_sequence"] == "face face"


def test_claims_table_lists_every_claim(quick):
    text = (quick / "claims.md").read_text()
    for claim in ("group-periodic windows", "most torsional impacts are chaotic",
                  "~3x translational", "~20 %", "mirror"):
        assert claim in text
