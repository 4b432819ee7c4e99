"""Codes of the corner that strikes at an impact onset (docs/model.md section 8)."""

CORNER_FACE = 0
CORNER_A_PLUS = 1
CORNER_A_MINUS = 2
CORNER_B_PLUS = 3
CORNER_B_MINUS = 4
CORNER_LABELS = ("face", "A+", "A-", "B+", "B-")
FACE_TOL = 1e-9  #: |d_lo - d_hi| < FACE_TOL max(1, |d_max|): a "face" impact
