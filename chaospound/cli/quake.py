"""``chaospound quake``: a scene under an accelerogram or a stochastic motion.

Named for what it runs (an earthquake), short like the other commands; the library
is :mod:`chaospound.quake`. Reports the impacts per corner (count, peak force,
velocity, penetration), the towers' peak displacements relative to the ground, a
finite-time Lyapunov exponent over the motion and, with ``--ensemble N``, the
spread of the peak impact force over perturbed runs; ``--units si`` in m/s, kN and
mm (docs/units.md).
"""

from __future__ import annotations

import argparse
import math
import os

from chaospound.cli.files import _save_figure, check_figure_path, check_output_path, write_json_file
from chaospound.cli.options import _count, _count0, _engine_of, add_scene_options, scene_from_args
from chaospound.cli.output import EXIT_OK, CliError, _emit, _json_text, _path, _table, _with_units
from chaospound.cli.reports import _scene_rows, _solver_text
from chaospound.cli.status import STATUS_DELAY_S, _load_kernels, _Status


def _float(low: float, low_open: bool, high: float | None = None):
    """argparse type: a finite number >= low (> low when open), < high."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        ok = math.isfinite(value) and (value > low if low_open else value >= low)
        if high is not None:
            ok = ok and value < high
        if not ok:
            bound = f"{'>' if low_open else '>='} {low:g}" + (
                f" and < {high:g}" if high is not None else "")
            raise argparse.ArgumentTypeError(f"{text[:40]!r}: must be a number {bound}")
        return value
    return parse


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``quake`` to the subcommands."""
    parser = commands.add_parser(
        "quake",
        help="run a scene under an accelerogram or a stochastic motion: peak impacts, drifts",
        description="Run a scene from rest under a recorded (--record FILE) or stochastic "
        "(ground = stochastic) ground motion over its whole length; report the impacts per "
        "corner (count, peak force, velocity, penetration), the peak displacements relative "
        "to the ground, a finite-time Lyapunov exponent and, with --ensemble, the spread of "
        "the peak impact force. The scene needs length_unit [m] and tower_period [s] (or a "
        "[physical] table, docs/units.md).",
    )
    add_scene_options(parser, run=False)
    motion = parser.add_argument_group("ground motion")
    motion.add_argument("--record", dest="record_file", metavar="FILE",
                        help="accelerogram: PEER .AT2 or text (time [s], acceleration); sets "
                        "ground = record (units, dt: --set ground_units=..., ground_dt=...)")
    motion.add_argument("--scale", type=_float(0.0, True), metavar="S",
                        help="factor on the accelerations (ground_scale)")
    motion.add_argument("--tail", type=_float(0.0, False), default=0.0, metavar="SECONDS",
                        help="free vibration after the motion's end [s] (default 0)")
    analysis = parser.add_argument_group("analysis")
    analysis.add_argument("--no-lyapunov", action="store_true",
                          help="skip the finite-time Lyapunov exponent (halves the work)")
    analysis.add_argument("--separation", type=_float(0.0, True), default=1e-7, metavar="D",
                          help="initial separation of the two trajectories (A_g; default 1e-7)")
    analysis.add_argument("--ensemble", type=_count0, default=0, metavar="N",
                          help="also run N perturbed copies: percentiles of the peak force")
    analysis.add_argument("--perturb", type=_float(0.0, False), default=0.0, metavar="EPS",
                          help="ensemble: initial-state perturbation (A_g, random directions)")
    analysis.add_argument("--scale-spread", type=_float(0.0, False, 1.0), default=0.0,
                          metavar="S", help="ensemble: record scale times 1 + S u, u uniform "
                          "in [-1, 1]")
    analysis.add_argument("--realisations", action="store_true",
                          help="ensemble: each run its own stochastic realisation "
                          "(ground_seed + i): the distribution of the peak force over records")
    analysis.add_argument("--seed", type=_count0, default=0, metavar="N",
                          help="seed of the perturbation directions and scales (default 0)")
    analysis.add_argument("--samples", type=_count, default=100, metavar="N",
                          help="dense samples per section interval for the peak displacements "
                          "and the figure (default 100)")
    out = parser.add_argument_group("output")
    out.add_argument("--units", choices=("model", "si"), default="model",
                     help="report in model units or in SI (m/s, kN, mm, s; needs "
                     "tower_mass, or a [physical] table)")
    out.add_argument("--json", action="store_true", help="print one JSON document only")
    out.add_argument("--output", metavar="FILE.json", help="also write the JSON to this file")
    out.add_argument("--overwrite", action="store_true", help="replace an existing --output")
    out.add_argument("--plot", metavar="FILE.png",
                     help="time histories: ground acceleration, displacements relative to "
                     "the ground, clearance with the impacts, contact force")
    out.add_argument("--quiet", action="store_true",
                     help="no status line on stderr (shown on a terminal when the work takes "
                     f"more than {STATUS_DELAY_S:g} s)")
    parser.set_defaults(func=_cmd_quake)


def _cmd_quake(args: argparse.Namespace) -> int:
    from chaospound.quake import ensemble, finite_time_lyapunov, quake, quake_scene
    from chaospound.units import require_si, units_of

    if args.ensemble == 0 and (args.perturb or args.scale_spread or args.realisations):
        raise CliError("--perturb, --scale-spread and --realisations need --ensemble N")
    if args.record_file is not None and not os.path.isfile(args.record_file):
        raise CliError(f"record file {_path(args.record_file)} not found")
    scene = quake_scene(scene_from_args(args), args.record_file, args.scale)
    if args.realisations and scene.excitation.ground != "stochastic":
        raise CliError(f"--realisations: ground = {scene.excitation.ground}, not stochastic")
    units = require_si(scene) if args.units == "si" else units_of(scene)
    if args.output is not None:
        check_output_path(args.output, overwrite=args.overwrite)
    if args.plot is not None:
        check_figure_path(args.plot)
    tail = args.tail / units.time if units is not None else 0.0
    _load_kernels(args.quiet, **_engine_of(scene))
    with _Status(f"running {scene.name} under its ground motion", quiet=args.quiet) as status:
        run = quake(scene, tail=tail, samples_per_cycle=args.samples, lyapunov=False)
        if not args.no_lyapunov:
            status.set("finite-time Lyapunov exponent (two trajectories)")
            run = _replace(run, lyapunov=finite_time_lyapunov(
                run.scene, run.simulation.record, args.separation, args.seed))
        if args.ensemble:
            status.set(f"ensemble of {args.ensemble} runs")
            run = _replace(run, ensemble=ensemble(run.scene, args.ensemble, args.perturb,
                                                  args.scale_spread, args.seed,
                                                  args.realisations))
        if args.plot is not None:
            from chaospound.quake import plot_quake

            status.set("drawing the time histories")
            _save_figure(plot_quake(run, units if args.units == "si" else None), args.plot)
    document = _with_units(run.to_json_dict())
    if args.units == "si":
        document["si"] = _si_document(run, units)
    if args.output is not None:
        write_json_file(document, args.output, overwrite=args.overwrite)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_report(run, units if args.units == "si" else None, args))
    return EXIT_OK


def _replace(run, **changes):
    from dataclasses import replace

    return replace(run, **changes)


def _si_document(run, units) -> dict:
    """The run's peaks in SI (the ``si`` object of the JSON)."""
    from chaospound.units import si_value

    out = {
        "units": {"force": "kN", "velocity": "m/s", "penetration": "mm", "displacement": "mm",
                  "time": "s", "lyapunov": "1/s"},
        "length_unit_m": units.length, "tower_period_s": units.period, "tower_mass_kg": units.mass,
        "motion_end": si_value(units, "time", run.motion_end),
        "peak_force": si_value(units, "force", run.peak_force),
        "corners": [{"corner": c.corner, "impacts": c.impacts,
                     "peak_force": si_value(units, "force", c.peak_force),
                     "peak_velocity": si_value(units, "velocity", c.peak_velocity),
                     "peak_penetration": si_value(units, "length", c.peak_penetration)}
                    for c in run.corners],
        "towers": [{"tower": t.tower,
                    "displacement": si_value(units, "length", t.displacement),
                    "corner_displacement": si_value(units, "length", t.corner_displacement),
                    "rotation": t.rotation} for t in run.towers],
    }
    if run.lyapunov is not None:
        out["lyapunov"] = run.lyapunov.exponent / units.time
    if run.ensemble is not None:
        out["ensemble_percentiles"] = {f"{q:g}": si_value(units, "force", v)
                                       for q, v in run.ensemble.percentiles.items()}
    return out


def _report(run, units, args: argparse.Namespace) -> str:
    """The text report: header, conversion table (SI), corners, towers, exponent, ensemble."""
    from chaospound.units import conversion_rows, si_value, units_of

    scene, sim = run.scene, run.simulation
    base = units_of(scene)
    end = (f"{base.time * run.motion_end:.6g} s" if base is not None
           else f"t = {run.motion_end:.6g}")
    header = [*_scene_rows(scene, f"{sim.model} ({len(sim.state_names)} states)", sim.period),
              ("duration", f"motion ends at {end}; run covers {sim.record} section intervals "
                           f"(t = {run.time:.6g})"),
              ("solver", _solver_text(scene.solver))]
    blocks = [_table(None, header, "ll")]
    if units is not None:
        blocks.append(_table(("quantity", "SI", "model", "rule"), conversion_rows(scene), "llll"))

    def value(kind: str, number: float) -> str:
        return f"{si_value(units, kind, number) if units is not None else number:.5g}"

    unit = ({"force": "kN", "velocity": "m/s", "length": "mm"} if units is not None else
            {"force": "A_g K_Ax", "velocity": "A_g omega_Ax", "length": "A_g"})
    if run.corners:
        rows = [(c.corner, str(c.impacts), value("force", c.peak_force),
                 value("velocity", c.peak_velocity), value("length", c.peak_penetration))
                for c in run.corners]
        blocks.append(_table(("corner", "impacts", "peak force", "peak velocity",
                              "peak penetration"),
                             [("", "", unit["force"], unit["velocity"], unit["length"]), *rows],
                             "lrrrr"))
    else:
        blocks.append("no impacts")
    rows = [(f"tower {t.tower}", value("length", t.displacement),
             value("length", t.corner_displacement), f"{t.rotation:.4g}") for t in run.towers]
    blocks.append(_table(("peak relative to the ground", "centre of mass", "facing corners",
                          "rotation"), [("", unit["length"], unit["length"], "rad"), *rows],
                         "lrrr"))
    summary = [("impacts", f"{run.impacts}, peak force {value('force', run.peak_force)} "
                           f"{unit['force']}")]
    if run.lyapunov is not None:
        ftle = run.lyapunov
        rate = (f"{ftle.exponent / units.time:.4g} 1/s" if units is not None
                else f"{ftle.exponent:.4g} omega_Ax")
        change = "grows" if ftle.amplification >= 1.0 else "shrinks"
        summary.append(("finite-time Lyapunov", f"{rate} over the run (separation "
                        f"{ftle.separation:g} A_g {change} to "
                        f"{ftle.separation * ftle.amplification:.3g} A_g, "
                        f"x {ftle.amplification:.3g})"))
    if run.ensemble is not None:
        e = run.ensemble
        shown = ", ".join(f"p{q:g} {value('force', v)}" for q, v in e.percentiles.items())
        summary.append((f"ensemble ({e.peak_force.size} runs)",
                        f"peak force {shown} {unit['force']}; spread (max - min) "
                        f"{value('force', e.spread)} (perturb {e.perturb:g} A_g, scale spread "
                        f"{e.scale_spread:g}"
                        + (", one realisation each" if e.realisations else "") + ")"))
    if args.plot is not None:
        summary.append(("wrote", args.plot))
    if args.output is not None:
        summary.append(("wrote", args.output))
    blocks.append(_table(None, summary, "ll"))
    return "\n\n".join(blocks) + "\n"

