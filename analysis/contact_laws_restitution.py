"""Measured coefficient of restitution of every contact law: results/contact_laws_restitution.*

One free impact of two bodies (no springs, no ground), ``m_eff d'' = -F(d, d')``
from ``d = 0, d' = v0`` until d returns to 0, integrated by scipy's DOP853 at
rtol 1e-12, atol 1e-14 with the law's own ``point_force`` (the integrator and the
laws' parameters are those of tests/test_contact_laws.py, imported from there,
so the table and the tests measure the same thing). For each law and target e
it reports the measured e at v0 = 1, its spread over v0 = 0.01, 0.1, 1, 10
(A_g omega_Ax: three decades), and the least force over the peak force (a
negative value is a tensile, pulling force). docs/contact_laws.md quotes it.

Usage::

    python analysis/contact_laws_restitution.py            # results/contact_laws_restitution.*
    python analysis/contact_laws_restitution.py --out DIR  # elsewhere
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import json
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGETS = (0.3, 0.4, 0.5, 0.6, 0.65, 0.7, 0.8, 0.9, 0.95, 0.99)
SPEEDS = (0.01, 0.1, 1.0, 10.0)


def _cases():
    """tests/test_contact_laws.py as a module (its DAMPED laws and free_impact)."""
    sys.path.insert(0, str(ROOT))
    spec = importlib.util.spec_from_file_location("contact_law_cases",
                                                  ROOT / "tests" / "test_contact_laws.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def measure() -> dict:
    """Run every (law, e, v0) impact; returns the rows and the settings."""
    cases = _cases()
    rows = []
    for name, (law, make) in cases.DAMPED.items():
        for e in TARGETS:
            by_speed = {}
            for v0 in SPEEDS:
                measured, duration, peak, least = cases.free_impact(law, cases.pack(make(e)),
                                                                    cases.M_EFF, v0)
                by_speed[v0] = (measured, duration, peak, least)
            es = [v[0] for v in by_speed.values()]
            at_one = by_speed[1.0]
            rows.append({"law": name, "target": e, "measured": at_one[0],
                         "deviation": at_one[0] - e, "spread": max(es) - min(es),
                         "duration": at_one[1], "least_over_peak": at_one[3] / at_one[2]})
    return {"rows": rows, "m_eff": cases.M_EFF, "k": cases.K_LIN, "beta": cases.BETA,
            "speeds": SPEEDS}


def report(data: dict) -> str:
    """The markdown table."""
    laws = list(dict.fromkeys(r["law"] for r in data["rows"]))
    lines = [
        "# Coefficient of restitution of the contact laws (free impact)",
        "",
        "Written by `python analysis/contact_laws_restitution.py` "
        f"({data['date']}, {data['seconds']:.0f} s on {data['machine']}).",
        "",
        f"Two free bodies, m_eff = {data['m_eff']:.6f} m_A (the paper's pair, m_A/m_B = 2.25), "
        f"linear k = {data['k']:g} K_Ax, Hertz beta = {data['beta']:g} K_Ax A_g^-0.5, "
        "chi = 1.5; scipy DOP853, rtol 1e-12, atol 1e-14, the law's own point force.",
        "Measured e at v0 = 1 A_g omega_Ax; *spread*: max - min of the measured e over "
        f"v0 = {', '.join(f'{v:g}' for v in data['speeds'])} (every law is self-similar "
        "in v0, so this is integration error only); *pull*: least force / peak force "
        "(negative: the law pulls).",
        "",
        "## Measured e against the target",
        "",
        "| target e | " + " | ".join(laws) + " |",
        "|---|" + "---|" * len(laws),
    ]
    for e in TARGETS:
        cells = []
        for law in laws:
            row = next(r for r in data["rows"] if r["law"] == law and r["target"] == e)
            cells.append(f"{row['measured']:.4f} ({row['deviation']:+.4f})")
        lines.append(f"| {e:g} | " + " | ".join(cells) + " |")
    lines += ["", "## Largest spread over the speeds, and the pull", "",
              "| law | max spread | least force / peak (e = 0.3, 0.65, 0.95) |", "|---|---|---|"]
    for law in laws:
        rows = [r for r in data["rows"] if r["law"] == law]
        pulls = [next(r for r in rows if r["target"] == e)["least_over_peak"]
                 for e in (0.3, 0.65, 0.95)]
        lines.append(f"| {law} | {max(r['spread'] for r in rows):.1e} | "
                     + ", ".join(f"{v:+.3f}" for v in pulls) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "results")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    data = measure()
    data["seconds"] = time.perf_counter() - start
    data["date"] = datetime.date.today().isoformat()
    data["machine"] = f"{platform.machine()}, Python {platform.python_version()}"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "contact_laws_restitution.json").write_text(json.dumps(data, indent=1) + "\n")
    text = report(data)
    (args.out / "contact_laws_restitution.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
