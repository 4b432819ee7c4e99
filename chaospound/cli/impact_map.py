"""``chaospound impact-map``: phase and velocity of consecutive impacts,
n -> n+1."""

from __future__ import annotations

import argparse

from chaospound.cli.files import _save_figure, check_figure_path
from chaospound.cli.options import (
    _engine_of,
    _is_system,
    _system_warm,
    add_output_options,
    add_scene_options,
    target_from_args,
)
from chaospound.cli.output import EXIT_OK, CliError, _emit, _json_text, _table, _with_units
from chaospound.cli.reports import (
    _emit_report,
    _scene_rows,
    _solver_text,
    _system_document,
    _system_header,
)
from chaospound.cli.simulate import _run_simulation
from chaospound.cli.status import _load_kernels, _Status


def add_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "impact-map",
        help="impact map n -> n+1: phase and velocity of consecutive impacts",
        description="Run a scene (transient, then record cycles) and list its impacts as "
        "the map n -> n+1 of consecutive impacts: (phase_n, V_n) -> (phase_n+1, V_n+1), "
        "with the corners. A response with n impacts per period repeats every n impacts "
        "(n fixed points of the n-th iterate); a chaotic one spreads over a curve or a "
        "cloud. --record sets the cycles recorded. A system FILE.py:ATTR with a gap function "
        "(docs/custom_systems.md) runs likewise.",
    )
    add_scene_options(parser)
    add_output_options(parser, plot_help="draw the impact sequence and the return maps of "
                       "phase and velocity (.png, .pdf or .svg; an existing figure is redrawn)")
    parser.set_defaults(func=_cmd_impact_map)


def _cmd_impact_map(args: argparse.Namespace) -> int:
    from chaospound.dynamics.impact_map import impact_map

    scene = target_from_args(args)
    system = scene if _is_system(scene) else None
    if system is not None and not system.has_gap:
        raise CliError(f"system {system.name!r} has no gap function: it has no impacts "
                       "(custom_system(rhs, jacobian, gap, ...))")
    if args.plot is not None:
        check_figure_path(args.plot)
    _load_kernels(args.quiet, warm=_system_warm(scene), **_engine_of(scene))
    transient, record = ((system.transient, system.record) if system is not None
                         else (scene.run.transient, scene.run.record))
    cycles = f"{transient} transient + {record} recorded cycles"
    with _Status(f"running {scene.name}: {cycles}", quiet=args.quiet):
        sim = _run_simulation(scene, 0)
    imap = impact_map(sim)
    if args.plot is not None:
        from chaospound.plot import plot_impact_map

        fig = plot_impact_map(imap)
        what = (scene.name if system is not None else
                f"{scene.name}, $T/T_{{Ax}}$ = {scene.excitation.period_ratio:g}")
        fig.suptitle(f"{what}: {fig.get_suptitle()}, cycles {sim.transient}-"
                     f"{sim.transient + sim.record - 1}")
        _save_figure(fig, args.plot)
    document = _with_units(imap.to_json_dict())
    document["transient_cycles"] = sim.transient
    document["record_cycles"] = sim.record
    if system is not None:
        document["system"] = _system_document(system)
    else:
        document["scene"] = scene.to_dict()
    if args.json:
        _emit(_json_text(document))
        return EXIT_OK
    cycles_row = ("cycles", f"{sim.transient} transient + {sim.record} recorded")
    if system is not None:
        header = [*_system_header(system), cycles_row]
    else:
        header = [
            *_scene_rows(scene, sim.model, sim.period),
            cycles_row,
            ("solver", _solver_text(scene.solver)),
        ]  # fmt: skip
    blocks = [_table(None, header, "ll")]
    labels = imap.labels
    if len(imap) >= 2:
        rows = [(str(i + 1), str(int(imap.cycle[i])), labels[i], f"{imap.phase[i]:.5f}",
                 f"{imap.velocity[i]:.6g}", labels[i + 1], f"{imap.phase[i + 1]:.5f}",
                 f"{imap.velocity[i + 1]:.6g}") for i in range(len(imap) - 1)]
        columns = ("n", "cycle", "corner n", "phase n", "V n", "corner n+1", "phase n+1",
                   "V n+1")
        speed = "" if system is not None else "A_g omega_Ax"
        units = ("", "", "", "of T", speed, "", "of T", speed)
        blocks.append(_table(columns, [units, *rows], "rrlrrlrr"))
    else:
        blocks.append(f"{len(imap)} impact{'' if len(imap) == 1 else 's'} in the record "
                      "window: no pair n -> n+1")
    tail = [("impacts", f"{len(imap)} ({len(imap) / sim.record:.4g} per cycle), "
                        f"{max(len(imap) - 1, 0)} pairs")]
    return _emit_report(blocks, tail, args.plot)
