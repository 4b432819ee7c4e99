"""``chaospound section``: the stroboscopic Poincare section and its distinct
points."""

from __future__ import annotations

import argparse

from chaospound.cli.files import _save_figure, check_figure_path
from chaospound.cli.options import (
    _count,
    _engine_of,
    _is_system,
    _positive_float,
    _system_warm,
    add_output_options,
    add_scene_options,
    target_from_args,
)
from chaospound.cli.output import EXIT_OK, _emit, _json_text, _table, _with_units
from chaospound.cli.reports import (
    _emit_report,
    _scene_rows,
    _solver_text,
    _state_unit,
    _system_document,
    _system_header,
)
from chaospound.cli.status import _load_kernels, _Status

#: relative distance (to the section's size) within which two section points are one
SECTION_TOL = 1e-6
#: most section points listed by the text report (all are in the JSON)
SECTION_ROWS = 12


def add_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "section",
        help="stroboscopic Poincare section: the state once per excitation period",
        description="The states at t = (phase + k) T for k = transient .. transient + cycles "
        "(T the excitation period): a response of period P cycles gives P distinct points, "
        "a quasi-periodic one a closed curve, a chaotic one a cloud. The report counts the "
        "distinct points. --transient sets the cycles discarded first (the scene's, 40 "
        "for the presets). A system FILE.py:ATTR (docs/custom_systems.md) is sectioned at "
        "t = k T.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("section")
    group.add_argument("--cycles", type=_count, default=200, metavar="N",
                       help="cycles recorded (200): N + 1 points")
    group.add_argument("--tol", type=_positive_float, default=SECTION_TOL, metavar="TOL",
                       help="two points closer than TOL times the section's size count as "
                       f"one distinct point ({SECTION_TOL:g})")
    add_output_options(parser, plot_help="draw the points in the panels of the phase "
                       "diagrams (.png, .pdf or .svg; an existing figure is redrawn)")
    parser.set_defaults(func=_cmd_section)


def _cmd_section(args: argparse.Namespace) -> int:
    from chaospound.dynamics.poincare import stroboscopic_section

    scene = target_from_args(args)
    system = scene if _is_system(scene) else None
    if args.plot is not None:
        check_figure_path(args.plot)
    _load_kernels(args.quiet, warm=_system_warm(scene), **_engine_of(scene))
    transient = system.transient if system is not None else scene.run.transient
    phase = 0.0 if system is not None else scene.run.phase  # a system's: t = k T
    with _Status(f"section of {scene.name}: {transient} transient + {args.cycles} "
                 "cycles", quiet=args.quiet):
        section = stroboscopic_section(scene, phase=phase, cycles=args.cycles)
    distinct, counts, size = distinct_points(section.states, args.tol)
    if args.plot is not None:
        from chaospound.plot import plot_strobe

        fig = plot_strobe(section)
        what = (f"{scene.name}, {section.model} model" if system is not None else
                f"{scene.name}, $T/T_{{Ax}}$ = {scene.excitation.period_ratio:g}, "
                f"{section.model} model")
        fig.suptitle(f"{what}: section at phase {section.phase:g}, cycles "
                     f"{int(section.cycles[0])}-{int(section.cycles[-1])}, {len(section)} "
                     f"points, {len(distinct)} distinct")
        _save_figure(fig, args.plot)
    document = _with_units(section.to_json_dict())
    document["transient_cycles"] = int(section.cycles[0])
    document["distinct_points"] = len(distinct)
    document["distinct_tol"] = args.tol
    if system is not None:
        document["system"] = _system_document(system)
    else:
        document["scene"] = scene.to_dict()
    if args.json:
        _emit(_json_text(document))
        return EXIT_OK
    rows_of_section = [
        ("section", f"t = ({section.phase:g} + k) T, k = {int(section.cycles[0])} .. "
                    f"{int(section.cycles[-1])}: {len(section)} points"),
        ("distinct points", f"{len(distinct)} (within {args.tol:g} of the section's size "
                            f"{size:.4g})"),
    ]  # fmt: skip
    if system is not None:
        header = [*_system_header(system), *rows_of_section]
    else:
        header = [
            *_scene_rows(scene, f"{section.model} ({len(section.state_names)} states: "
                                f"{' '.join(section.state_names)})", section.period),
            rows_of_section[0],
            ("solver", _solver_text(scene.solver)),
            rows_of_section[1],
        ]  # fmt: skip
    names = section.state_names
    units = [("" if system is not None else _state_unit(n)) for n in names]
    rows = [(str(i + 1), str(n), *(f"{v:.6g}" for v in section.states[j]))
            for i, (j, n) in enumerate(zip(distinct[:SECTION_ROWS], counts, strict=False))]
    blocks = [_table(None, header, "ll"),
              _table(("#", "points", *names), [("", "", *units), *rows],
                     "rr" + "r" * len(names))]
    if len(distinct) > SECTION_ROWS:
        blocks.append(f"(first {SECTION_ROWS} of {len(distinct)} distinct points; all "
                      "points in --json)")
    return _emit_report(blocks, [], args.plot)


def distinct_points(states, tol: float) -> tuple[list[int], list[int], float]:
    """The distinct points of a section, in order of first appearance.

    Two points are one when their distance is at most ``tol`` times the section's
    size (the largest absolute state component over the points, at least 1e-300).

    Returns
    -------
    (indices, counts, size)
        The index of each distinct point's first occurrence, how many points
        fall on it, and the size used.
    """
    import numpy as np

    states = np.asarray(states, dtype=float)
    size = float(max(np.max(np.abs(states), initial=0.0), 1e-300))
    firsts: list[int] = []
    counts: list[int] = []
    for i, point in enumerate(states):
        for k, j in enumerate(firsts):
            if float(np.max(np.abs(point - states[j]))) <= tol * size:
                counts[k] += 1
                break
        else:
            firsts.append(i)
            counts.append(1)
    return firsts, counts, size
