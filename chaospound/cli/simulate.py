"""``chaospound simulate``: run a scene or a user's System to steady state and
report its impacts (text, JSON, time histories and phase diagrams)."""

from __future__ import annotations

import argparse
import math
import os
from typing import TYPE_CHECKING

from chaospound.cli.files import _save_figure, check_figure_path, check_output_path, write_json_file
from chaospound.cli.options import (
    _count0,
    _engine_of,
    _is_system,
    _system_warm,
    add_scene_options,
    target_from_args,
)
from chaospound.cli.output import EXIT_OK, CliError, _emit, _json_text, _path, _table, _with_units
from chaospound.cli.reports import _scene_rows, _solver_text, _system_document, _system_header
from chaospound.cli.status import STATUS_DELAY_S, _command_seconds, _load_kernels, _Status

if TYPE_CHECKING:
    from chaospound.scene import Scene
    from chaospound.simulate import Simulation


#: columns of the readable impact table
IMPACT_COLUMNS = ("#", "cycle", "phase", "velocity", "corner", "peak pen", "peak force", "duration")
#: the units row under the impact table's header (chaospound.units.UNITS)
IMPACT_UNITS = ("", "", "of T", "A_g omega_Ax", "", "A_g", "A_g k_Ax", "1/omega_Ax")
#: dense samples per cycle of the phase diagrams: a contact lasts about 0.2 of the
#: normalised time (5 % of a period), so 200 drew each impact's turn as 10 straight
#: segments; 2000 draws it smoothly
PHASE_PLOT_SAMPLES = 2000


def add_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "simulate",
        help="run a scene to steady state: impacts and stroboscopic section",
        description="Run a scene (transient, then record cycles) and report its impacts.",
    )
    add_scene_options(parser)
    out = parser.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print one JSON document only")
    out.add_argument(
        "--trajectory",
        type=_count0,
        default=0,
        metavar="N",
        help="dense samples per cycle over the record window (JSON 'trajectory')",
    )
    out.add_argument("--output", metavar="FILE.json", help="also write the JSON to this file")
    out.add_argument("--overwrite", action="store_true", help="replace an existing --output")
    out.add_argument("--units", choices=("model", "si"), default="model",
                     help="also report the impacts in SI (s, m/s, mm, kN) with the conversion "
                     "table; needs length_unit, tower_period, tower_mass (docs/units.md)")
    out.add_argument("--plot", metavar="FILE.png",
                     help="write the run's figure: time histories of the record window "
                     "(displacements, rotations, clearance with the impacts, contact force) "
                     "beside the phase diagrams (.png, .pdf or .svg; an existing figure is "
                     "redrawn)")
    out.add_argument("--quiet", action="store_true",
                     help="no status line on stderr (compiling, running; shown on a terminal "
                     f"when the work takes more than {STATUS_DELAY_S:g} s)")
    parser.set_defaults(func=_cmd_simulate)


def _cmd_simulate(args: argparse.Namespace) -> int:
    scene = target_from_args(args)
    units = _si_units(scene) if args.units == "si" else None
    if args.output is not None:
        check_output_path(args.output, overwrite=args.overwrite)
    if args.plot is not None:
        check_figure_path(args.plot)
        if args.output is not None and os.path.abspath(args.plot) == os.path.abspath(args.output):
            raise CliError(f"--plot {_path(args.plot)} is the --output file")
    _load_kernels(args.quiet, warm=_system_warm(scene), **_engine_of(scene))
    transient, record = ((scene.transient, scene.record) if _is_system(scene)
                         else (scene.run.transient, scene.run.record))
    cycles = f"{transient} transient + {record} recorded cycles"
    with _Status(f"running {scene.name}: {cycles}", quiet=args.quiet) as status:
        sim = _run_simulation(scene, args.trajectory)
        if args.plot is not None:
            status.set(f"drawing {scene.name}'s time histories and phase diagrams")
            _simulation_save_plot(sim, args.trajectory, args.plot,
                                  scene if _is_system(scene) else None)
    document = _simulation_document(sim)
    if _is_system(scene):
        document["system"] = _system_document(scene)
    if units is not None:
        from chaospound.units import si_impacts

        document["si"] = {"units": {"time": "s", "velocity": "m/s", "peak_penetration": "mm",
                                    "peak_force": "kN", "duration": "s"},
                          "impacts": {k: v.tolist()
                                      for k, v in si_impacts(sim.impacts, units).items()}}
    if args.output is not None:
        write_json_file(document, args.output, overwrite=args.overwrite)
    if args.json:
        _emit(_json_text(document))
    else:
        report = _simulation_report(sim, args.trajectory, args.output, args.plot,
                                    scene if _is_system(scene) else None)
        _emit(report if units is None else report + "\n" + _si_blocks(sim, units))
    return EXIT_OK


def _si_units(scene):
    """The scene's physical units for --units si (a one-line error without them)."""
    from chaospound.units import require_si

    if _is_system(scene):
        raise CliError("--units si: a user's system has no physical units")
    return require_si(scene)


def _si_blocks(sim: Simulation, units) -> str:
    """The conversion table and the impact table in SI (``--units si``)."""
    from chaospound.units import conversion_rows, si_impacts

    blocks = [_table(("quantity", "SI", "model", "rule"), conversion_rows(sim.scene), "llll")]
    table = si_impacts(sim.impacts, units)
    if len(sim.impacts):
        rows = [(str(i + 1), f"{table['time'][i]:.6g}", f"{table['velocity'][i]:.5g}", label,
                 f"{table['peak_penetration'][i]:.4g}", f"{table['peak_force'][i]:.5g}",
                 f"{table['duration'][i] * 1e3:.4g}")
                for i, label in enumerate(sim.impacts.labels)]
        blocks.append(_table(("#", "time", "velocity", "corner", "peak pen", "peak force",
                              "duration"), [("", "s", "m/s", "", "mm", "kN", "ms"), *rows],
                             "rrrlrrr"))
    return "\n\n".join(blocks) + "\n"


def _simulation_save_plot(sim: Simulation, samples_per_cycle: int, path: str,
                          system=None) -> None:
    """Time histories and phase diagrams of the run (rerun with dense samples unless the
    run has at least :data:`PHASE_PLOT_SAMPLES` per cycle: the same steps, interpolated);
    the phase diagrams alone for a user's ``system``."""
    from chaospound.plot import plot_phase_diagrams, plot_run

    if samples_per_cycle < PHASE_PLOT_SAMPLES:
        sim = _run_simulation(sim.scene if sim.scene is not None else system,
                              PHASE_PLOT_SAMPLES)
    if sim.scene is None:  # a user's system: no contact model to draw, its phase diagrams
        _save_figure(plot_phase_diagrams(sim), path)
        return
    from chaospound.simulate import contact_history

    _save_figure(plot_run(sim, contact_history(sim)), path)


def _run_simulation(scene: Scene, samples_per_cycle: int) -> Simulation:
    """Run the scene (simulate loads the jitted kernels before its timer starts)."""
    from chaospound.simulate import simulate

    return simulate(scene, samples_per_cycle=samples_per_cycle)


def _simulation_document(sim: Simulation) -> dict:
    document = _with_units(sim.to_json_dict())
    if sim.trajectory is not None:
        document["trajectory"] = {
            "time": sim.trajectory.time.tolist(),
            "state": sim.trajectory.state.tolist(),
        }
    return document


def _simulation_report(sim: Simulation, samples_per_cycle: int, output: str | None,
                       plot: str | None = None, system=None) -> str:
    """Header, impact table and summary of one run (of a scene, or of ``system``), as text."""
    scene, imp = sim.scene, sim.impacts
    if system is not None:
        header = [*_system_header(system),
                  ("cycles", f"{sim.transient} transient + {sim.record} recorded")]
    else:
        header = [
            *_scene_rows(scene, f"{sim.model} ({len(sim.state_names)} states: "
                                f"{' '.join(sim.state_names)})", sim.period),
            ("cycles", f"{sim.transient} transient + {sim.record} recorded, "
                       f"section phase {scene.run.phase:g}"),
            *_motion_span(sim),
            ("solver", _solver_text(scene.solver)),
        ]  # fmt: skip
    blocks = [_table(None, header, "ll")]
    if len(imp):
        rows = [
            (
                str(i + 1),
                str(int(imp.cycle[i])),
                f"{imp.phase[i]:.5f}",
                f"{imp.velocity[i]:.6g}",
                label,
                f"{imp.peak_penetration[i]:.4g}",
                f"{imp.peak_force[i]:.4g}" if system is None else "-",  # no contact law
                f"{imp.duration[i]:.4g}",
            )
            for i, label in enumerate(imp.labels)
        ]
        units = IMPACT_UNITS if system is None else ("", "", "of T", "", "", "", "", "")
        blocks.append(_table(IMPACT_COLUMNS, [units, *rows], "rrrrlrrr"))
    else:
        blocks.append("no impacts in the record window")
    summary = _summary(sim, samples_per_cycle, output)
    if plot is not None:
        drawn = "phase diagrams" if system is not None else "time histories and phase diagrams"
        summary.append(("wrote", f"{plot} ({drawn})"))
    blocks.append(_table(None, summary, "ll"))
    return "\n\n".join(blocks) + "\n"


def _motion_span(sim: Simulation) -> list[tuple[str, str]]:
    """For a record or a stochastic motion: where the motion ends and what the run spans
    (a run shorter than the motion leaves its end out; one longer, free vibration)."""
    from chaospound.quake import motion_end
    from chaospound.units import units_of

    scene = sim.scene
    if scene.excitation.ground not in ("record", "stochastic"):
        return []
    end = motion_end(scene.excitation.ground_block())
    span = (sim.transient + sim.record) * sim.period
    base = units_of(scene)

    def when(t: float) -> str:
        return f"t = {t:.6g}" + (f" ({base.time * t:.4g} s)" if base is not None else "")

    text = f"motion ends at {when(end)}; the run spans t = 0 to {when(span)[4:]}"
    if span < end:
        more = math.ceil(end / sim.period - 1e-9) - sim.transient
        text += f": its last part is not run (--set record={more} covers it)"
    return [("duration", text)]


def _summary(sim: Simulation, samples_per_cycle: int, output: str | None) -> list[tuple[str, str]]:
    imp, stats = sim.impacts, sim.stats
    last_cycle = sim.transient + sim.record - 1
    last = [label for label, k in zip(imp.labels, imp.cycle, strict=True) if k == last_cycle]
    per_step = 1e6 * stats.wall_s / stats.steps if stats.steps else math.nan
    rows = [
        ("impacts per cycle", f"{len(imp) / sim.record:.4g} ({len(imp)} in {sim.record} cycles)"),
        (
            "velocity",
            f"min {imp.velocity.min():.6g}, max {imp.velocity.max():.6g}"
            + (" (A_g omega_Ax)" if sim.scene is not None else "")  # a system's own units
            if len(imp) else "-",
        ),
        (f"corners, cycle {last_cycle}", " ".join(last) if last else "none"),
        (
            "steps",
            f"{stats.steps} accepted, {stats.rejected} rejected, "
            f"{stats.rhs_evals} rhs evaluations, {stats.events} events",
        ),
        ("wall time", f"{stats.wall_s:.4g} s in the kernels ({per_step:.3g} us per accepted "
                      f"step); {_command_seconds():.3g} s the whole command (start-up, kernels "
                      "loaded or compiled, reports)"),
    ]
    if samples_per_cycle:
        rows.append(("trajectory", f"{samples_per_cycle} samples per cycle (JSON 'trajectory')"))
    if output is not None:
        rows.append(("wrote", output))
    return rows

