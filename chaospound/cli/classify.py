"""``chaospound classify``: the steady response's regime (none, periodic,
group-periodic, quasi-periodic, chaotic) and its evidence."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from chaospound.cli.files import check_figure_path
from chaospound.cli.options import (
    _count0,
    _engine_of,
    _is_system,
    _system_warm,
    add_output_options,
    add_scene_options,
    target_from_args,
)
from chaospound.cli.output import EXIT_OK, CliError, _emit, _json_text, _path, _table, _with_units
from chaospound.cli.reports import _scene_rows, _system_document, _system_header
from chaospound.cli.simulate import PHASE_PLOT_SAMPLES
from chaospound.cli.status import _command_seconds, _load_kernels, _Status

if TYPE_CHECKING:
    from chaospound.scene import Scene


def add_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "classify",
        help="classify a scene's steady response: none, periodic n-P, group-periodic n-P, "
        "quasi-periodic, chaotic",
        description="Classify the steady response (docs/classification.md): adaptive transient "
        "(from --transient cycles, the minimum, to --max-transient), period and impacts per "
        "period from the stroboscopic section and the impacts, else the largest Lyapunov "
        "exponent and the 0-1 test. Runs with rtol <= 1e-8.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("classification")
    group.add_argument(
        "--max-transient",
        type=_count0,
        default=2000,
        metavar="N",
        help="longest transient in cycles (2000); --transient is the shortest (40)",
    )
    group.add_argument(
        "--max-period", type=_count0, default=16, metavar="P", help="longest period searched (16)"
    )
    group.add_argument(
        "--window",
        type=_count0,
        default=None,
        metavar="N",
        help="record window in cycles (default max(4 max-period, 32))",
    )
    group.add_argument(
        "--lyapunov-cycles",
        type=_count0,
        default=200,
        metavar="N",
        help="cycles averaged for the largest exponent when there is no period (200)",
    )
    group.add_argument("--no-01", action="store_true", help="skip the 0-1 test for chaos")
    add_output_options(parser, plot_help="write phase diagrams of the steady state (.png, "
                       ".pdf or .svg; an existing figure is redrawn)", quiet_help="progress")
    parser.set_defaults(func=_cmd_classify)


def _cmd_classify(args: argparse.Namespace) -> int:
    from chaospound.dynamics.classify import classify

    if args.record is not None:
        raise CliError(f"--record {args.record}: not used by classify (use --window N)")
    scene = target_from_args(args)
    system = scene if _is_system(scene) else None
    shortest = system.transient if system is not None else scene.run.transient
    if shortest < 1:
        raise CliError(f"--transient {shortest}: the shortest transient must be >= 1 cycle")
    if args.max_transient < shortest:
        raise CliError(
            f"--max-transient {args.max_transient}: must be >= the shortest transient "
            f"{shortest} (--transient)"
        )
    if args.max_period < 1:
        raise CliError(f"--max-period {args.max_period}: must be an integer >= 1")
    if args.window is not None and args.window < 2 * args.max_period:
        raise CliError(f"--window {args.window}: must be at least twice --max-period "
                       f"({args.max_period}), >= {2 * args.max_period}")
    if args.plot is not None:
        check_figure_path(args.plot)
    _load_kernels(args.quiet, warm=_system_warm(scene), **_engine_of(scene))
    with _Status(f"classifying {scene.name}", quiet=args.quiet) as status:
        regime = classify(
            scene,
            min_transient=shortest,
            max_transient=args.max_transient,
            window=args.window,
            max_period=args.max_period,
            lyapunov_cycles=args.lyapunov_cycles,
            test01=not args.no_01,
            progress=lambda text: status.set(f"classifying {scene.name}: {text}"),
        )
        if args.plot is not None:
            status.set(f"classified {regime.label}: drawing the phase diagrams")
            _classify_save_plot(scene, regime, args.plot)
    document = regime.to_json_dict()
    document["model"] = regime.evidence.get("model")
    if system is not None:
        document["system"] = _system_document(system)
    else:
        document["scene"] = scene.to_dict()
    _with_units(document)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_classify_report(scene, regime, args.plot))
    return EXIT_OK


def _classify_save_plot(scene: Scene, regime, path: str) -> None:
    """Phase diagrams of the classified steady state (rerun at the classification's tolerances)."""
    from chaospound.plot import plot_phase_diagrams, save
    from chaospound.simulate import simulate

    rtol, atol = regime.evidence.get("rtol"), regime.evidence.get("atol")
    method = scene.method if _is_system(scene) else scene.solver.method
    if method != "rk4" and rtol is not None and math.isfinite(atol):
        scene = (scene.with_solver(rtol=rtol, atol=atol) if _is_system(scene)
                 else scene.with_params(rtol=rtol, atol=atol))
    record = max(2 * regime.period_cycles, 4) if regime.period_cycles else 8
    run = simulate(scene, transient=regime.transient_used, record=record,
                   samples_per_cycle=PHASE_PLOT_SAMPLES)
    fig = plot_phase_diagrams(run)
    fig.suptitle(f"{fig.get_suptitle()}: {regime.label}")
    check_figure_path(path)
    try:
        save(fig, path)
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None


def _floquet_text(regime, floquet: dict, period_t: float) -> str:
    """The largest exponent of a periodic response from its solved orbit (rule 8)."""
    if regime.floquet_exponents is None:
        return f"- (periodic; {floquet.get('note', 'no orbit')})"
    lam = regime.floquet_exponents[0]
    how = (f"orbit solved by Newton, {floquet['method']} monodromy, max |mu| = "
           f"{abs(regime.floquet_multipliers[0]):.6f}")
    state = "exact Floquet exponent" if regime.floquet_exact else \
        f"Floquet exponent, NOT exact: {floquet['note']}"
    return f"{lam:+.7f} per unit t, {lam * period_t:+.7f} per cycle ({state}; {how})"


def _classify_report(scene: Scene, regime, plot: str | None) -> str:
    """The classification as an aligned text report."""
    evidence = regime.evidence
    cycles = regime.period_cycles
    period = "-" if cycles is None else f"{cycles} cycle{'' if cycles == 1 else 's'}"
    impacts = "-" if regime.impacts_per_period is None else str(regime.impacts_per_period)
    floquet = evidence.get("floquet")
    if regime.max_exponent is None and floquet is not None:
        exponent = _floquet_text(regime, floquet, scene.period)
    elif regime.max_exponent is None:
        exponent = "- (not needed: a period was found)" if regime.period_cycles else "-"
    else:
        period_t = scene.period
        exponent = (
            f"{regime.max_exponent:+.5f} +- {regime.max_exponent_error:.2g} per unit t, "
            f"{regime.max_exponent * period_t:+.5f} +- {regime.max_exponent_error * period_t:.2g}"
            " per cycle"
        )
    zero_one = "-" if regime.zero_one is None else f"{regime.zero_one:.3f}"
    if evidence.get("zero_one_banded") is not None:  # rule 6: banded chaos
        zero_one += (f"; {evidence['zero_one_banded']:.3f} less the means of "
                     f"{evidence['zero_one_bands']} bands")
    if evidence.get("zero_one_vetoed") is not None:  # rule 6: the veto needs more sections
        zero_one += (f" (over {evidence.get('sections')} sections; "
                     f"{evidence['zero_one_vetoed']:.3f} over the first 1001, which vetoed "
                     "the exponent)")
    digits = evidence.get("birkhoff_digits")  # rule 6's other test of regularity
    birkhoff = [] if digits is None else [
        ("Birkhoff average", f"{digits:.1f} digits (regular at >= 5)")]
    solver = scene if _is_system(scene) else scene.solver
    accuracy = (
        f"{solver.steps_per_cycle} steps per cycle"
        if solver.method == "rk4"
        else f"rtol {evidence.get('rtol'):g}, atol {evidence.get('atol'):g}"
    )
    if _is_system(scene):
        head = [row for row in _system_header(scene) if row[0] != "solver"]
    else:
        head = _scene_rows(scene, str(evidence.get("model")), scene.period)
    rows = [
        *head,
        ("regime", regime.label),
        ("period", period),
        ("impacts per period", impacts),
        ("corner sequence", " ".join(regime.corner_sequence) or "-"),
        ("strobe mismatch", f"{regime.strobe_mismatch:.3g} (tol {evidence.get('tol'):g}, "
                            f"at P = {evidence.get('best_period')})"),
        ("largest exponent", exponent),
        ("0-1 test K", zero_one),
        *birkhoff,
        ("confidence", f"{regime.confidence:.2f}"),
        ("transient used", f"{regime.transient_used} cycles, then a {evidence.get('window_cycles')}"
                           "-cycle window"),
        ("solver", f"{solver.method}, {accuracy}"),
        ("wall time", f"{_command_seconds():.3g} s the whole command"),
    ]  # fmt: skip
    if evidence.get("reached_by") == "newton":
        approach = evidence["approach"]
        if "orbit_period" in approach:  # rule 8b
            how = (f"Newton at P = {approach['period']} found an orbit of period "
                   f"{approach['orbit_period']}, {approach['distance']:.2g} of the scale from "
                   f"the record, which still approached it; the window alone said "
                   f"{approach['label']}")
        else:  # rule 6b
            how = (f"Newton at P = {approach['period']}: the record closed in on the orbit "
                   f"({approach['distance_first_quarter']:.2g} -> "
                   f"{approach['distance_last_quarter']:.2g} of the scale over "
                   f"{approach['sections']} sections; Newton and the window at 1e-3 times "
                   f"the rtol); rule 6 alone said {approach['label']}")
        rows.insert(rows.index(("confidence", f"{regime.confidence:.2f}")), ("reached by", how))
    if plot is not None:
        rows.append(("wrote", plot))
    return _table(None, rows, "ll") + "\n"
