"""``chaospound lyapunov``: Lyapunov exponents with error bars, the trace
identity, the Kaplan-Yorke dimension, optionally two nearby trajectories."""

from __future__ import annotations

import argparse
import math
import time

from chaospound.cli.files import check_figure_path
from chaospound.cli.options import (
    _count0,
    _is_system,
    add_output_options,
    add_scene_options,
    target_from_args,
)
from chaospound.cli.output import EXIT_OK, CliError, _emit, _json_text, _path, _table, _with_units
from chaospound.cli.reports import _scene_rows, _solver_text, _system_document, _system_header
from chaospound.cli.status import _command_seconds, _load_kernels, _Status

LYAPUNOV_BLOCKS = 10  #: blocks of the error bars (standard error of block means)
LYAPUNOV_SEPARATION = 1e-7  #: initial separation of the two-trajectory method
LYAPUNOV_TWO_RTOL = 1e-10  #: the two trajectories' integration error must stay << separation
LYAPUNOV_TWO_ATOL = 1e-12


def add_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "lyapunov",
        help="Lyapunov exponents of a scene's steady response, with error bars",
        description="Lyapunov exponents from the variational equations (QR every excitation "
        "period), with standard errors of block means, the trace identity and the Kaplan-Yorke "
        "dimension; optionally the largest exponent from two nearby trajectories.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("lyapunov")
    group.add_argument(
        "--k", type=_count0, default=None, metavar="K", help="number of exponents (default: all)"
    )
    group.add_argument(
        "--cycles", type=_count0, default=400, metavar="N", help="excitation cycles averaged (400)"
    )
    group.add_argument(
        "--tangent-transient",
        type=_count0,
        default=20,
        metavar="N",
        help="cycles discarded while the tangent vectors align (20)",
    )
    group.add_argument(
        "--two-trajectory",
        action="store_true",
        help="also the largest exponent from two nearby trajectories "
        f"(separation {LYAPUNOV_SEPARATION:g}, rtol tightened to <= {LYAPUNOV_TWO_RTOL:g})",
    )
    group.add_argument(
        "--no-floquet",
        action="store_true",
        help="skip the orbit solve that gives a periodic response's exact (Floquet) exponents",
    )
    add_output_options(parser, plot_help="write the convergence figure (.png, .pdf or .svg; "
                       "an existing figure is redrawn)")
    parser.set_defaults(func=_cmd_lyapunov)


def _cmd_lyapunov(args: argparse.Namespace) -> int:
    from chaospound.dynamics.lyapunov import lyapunov_spectrum
    from chaospound.dynamics.system import System

    scene = target_from_args(args)
    system = scene if _is_system(scene) else System.from_scene(scene)
    if args.k is not None and not 1 <= args.k <= system.dim:
        raise CliError(
            f"--k {args.k}: must be between 1 and {system.dim} "
            f"(the {system.model_name} model's state dimension)"
        )
    if args.cycles < LYAPUNOV_BLOCKS:
        raise CliError(
            f"--cycles {args.cycles}: must be >= {LYAPUNOV_BLOCKS} "
            f"(the error bars use {LYAPUNOV_BLOCKS} blocks)"
        )
    if args.plot is not None:
        check_figure_path(args.plot)
    refusal = _qr_refusal(system)
    if refusal is not None:
        if not args.two_trajectory:
            raise CliError(f"{refusal}; run lyapunov --two-trajectory for the largest exponent")
        return _lyapunov_two_trajectory_only(args, scene, system, refusal)
    # warm the jitted kernels up, so that the reported wall time is the work's
    _load_kernels(args.quiet, lambda: lyapunov_spectrum(
        system, k=args.k, transient=0, tangent_transient=0, cycles=2, n_blocks=2),
        engine=system.engine("qr"))
    start = time.perf_counter()
    with _Status(f"Lyapunov exponents: {system.transient} transient + {args.tangent_transient} "
                 f"tangent transient + {args.cycles} averaged cycles", quiet=args.quiet):
        spectrum = lyapunov_spectrum(
            system,
            k=args.k,
            tangent_transient=args.tangent_transient,
            cycles=args.cycles,
            n_blocks=LYAPUNOV_BLOCKS,
        )
    wall = time.perf_counter() - start
    floquet = None
    if not args.no_floquet:
        from chaospound.orbits.floquet import spectrum_floquet

        with _Status("periodic? the orbit by Newton shooting for the exact exponents",
                     quiet=args.quiet):
            floquet = spectrum_floquet(system, spectrum)
    two, two_system, two_wall = None, None, 0.0
    if args.two_trajectory:
        two, two_system, two_wall = _two_trajectory_run(args, system)
    if args.plot is not None:
        title = (f"{system.name}, T = {system.period:.4g}, custom model" if system is scene
                 else f"{scene.name}, $T/T_{{Ax}}$ = {scene.excitation.period_ratio:g}, "
                 f"{system.model_name} model")
        _lyapunov_save_plot(spectrum, two, args.plot, title)
    document = _lyapunov_document(scene, system, spectrum, wall, two, two_system, two_wall)
    if not args.no_floquet:
        document["floquet"] = _floquet_document(floquet)
    if args.json:
        _emit(_json_text(document))
    else:
        _emit(_lyapunov_report(scene, system, spectrum, document, args.plot))
    return EXIT_OK


def _qr_refusal(system) -> str | None:
    """Why the engine refuses QR tangent dynamics for this system (its contact law on
    its model: docs/contact_laws.md section 7), or None."""
    from chaospound.engine.compose import check_tangent

    try:
        check_tangent(system.composition.with_tangent("qr"))
    except ValueError as exc:
        return str(exc)
    return None


def _two_trajectory_run(args: argparse.Namespace, system):
    """``(result, system run, wall seconds)`` of the two-trajectory estimate."""
    from chaospound.dynamics.lyapunov import largest_exponent_two_trajectory

    two_system = system
    if system.method != "rk4":
        two_system = system.with_solver(
            rtol=min(system.rtol, LYAPUNOV_TWO_RTOL), atol=min(system.atol, LYAPUNOV_TWO_ATOL)
        )
    start = time.perf_counter()
    with _Status(f"two trajectories: {args.cycles} cycles", quiet=args.quiet):
        two = largest_exponent_two_trajectory(
            two_system,
            cycles=args.cycles,
            separation=LYAPUNOV_SEPARATION,
            n_blocks=LYAPUNOV_BLOCKS,
        )
    return two, two_system, time.perf_counter() - start


def _lyapunov_two_trajectory_only(args: argparse.Namespace, scene, system, refusal: str) -> int:
    """``lyapunov --two-trajectory`` where the tangent dynamics are refused: the largest
    exponent from two trajectories alone, the refusal stated."""
    if args.plot is not None:
        raise CliError("--plot draws the QR convergence, which is not available here "
                       f"({refusal})")
    two, two_system, two_wall = _two_trajectory_run(args, system)
    document = {
        "model": system.model_name,
        "state_dim": system.dim,
        "qr": {"available": False, "reason": refusal},
        "two_trajectory": {
            "exponent": two.exponent,
            "error": two.error,
            "per_cycle": two.per_cycle,
            "error_per_cycle": two.error * two.period,
            "separation": two.separation,
            "cycles": two.cycles,
            "rtol": two_system.rtol,
            "atol": two_system.atol,
            "wall_s": two_wall,
        },
    }
    if system is scene:
        document["system"] = _system_document(system)
    else:
        document["scene"] = scene.to_dict()
    _with_units(document)
    if args.json:
        _emit(_json_text(document))
        return EXIT_OK
    if system is scene:
        header = _system_header(system)
    else:
        header = [*_scene_rows(scene, f"{system.model_name} ({system.dim} states)",
                               system.period),
                  ("solver", _solver_text(scene.solver))]
    summary = [
        ("QR spectrum", f"not available: {refusal}"),
        ("two trajectories",
         f"lambda_1 = {two.exponent:+.6f} +- {two.error:.2g} per unit t, "
         f"{two.per_cycle:+.6f} +- {two.error * two.period:.2g} per cycle "
         f"({two.cycles} cycles, separation {two.separation:g}, rtol {two_system.rtol:g}, "
         f"{two_wall:.3g} s)"),
    ]
    _emit("\n\n".join([_table(None, header, "ll"), _table(None, summary, "ll")]) + "\n")
    return EXIT_OK


def _lyapunov_save_plot(spectrum, two, path: str, scene: str) -> None:
    """Write the convergence figure atomically; file errors become CliError."""
    from chaospound.plot import plot_lyapunov_convergence, save

    fig = plot_lyapunov_convergence(spectrum, two, scene=scene)
    check_figure_path(path)
    try:
        save(fig, path)
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None


def _lyapunov_document(scene, system, spectrum, wall, two, two_system, two_wall) -> dict:
    total = float(spectrum.exponents.sum())
    document = {
        "model": system.model_name,
        "state_dim": system.dim,
        "qr": {"available": True},  # (where refused: False and the reason, two trajectories)
        "k": int(spectrum.exponents.size),
        "full_spectrum": bool(spectrum.exponents.size == system.dim),
        "period": spectrum.period,
        "transient_cycles": spectrum.transient,
        "tangent_transient_cycles": spectrum.tangent_transient,
        "cycles": spectrum.cycles,
        "blocks": int(spectrum.block_means.shape[0]),
        "exponents": spectrum.exponents.tolist(),
        "errors": spectrum.errors.tolist(),
        "max_exponent": spectrum.max_exponent,
        "max_error": spectrum.max_error,
        "per_cycle": spectrum.per_cycle.tolist(),
        "errors_per_cycle": spectrum.errors_per_cycle.tolist(),
        "sum": total,
        "trace": spectrum.trace,
        "kaplan_yorke": spectrum.kaplan_yorke,
        "work": {"steps": spectrum.steps, "rhs_evals": spectrum.rhs_evals, "wall_s": wall},
    }
    if system is scene:
        document["system"] = _system_document(system)
    else:
        document["scene"] = scene.to_dict()
    _with_units(document)
    if two is not None:
        document["two_trajectory"] = {
            "exponent": two.exponent,
            "error": two.error,
            "per_cycle": two.per_cycle,
            "error_per_cycle": two.error * two.period,
            "separation": two.separation,
            "cycles": two.cycles,
            "rtol": two_system.rtol,
            "atol": two_system.atol,
            "wall_s": two_wall,
        }
    return document


def _floquet_document(floquet) -> dict:
    """The orbit solve beside the QR estimates: which exponents are exact."""
    if floquet is None:
        return {"periodic": False, "exact": False,
                "note": "no period <= 16 cycles at the end of the run: the QR estimates "
                        "stand alone"}
    return {"periodic": True, **floquet.to_json_dict(),
            "per_cycle": [float(e) for e in floquet.per_cycle]}


def _floquet_summary(floquet: dict, spectrum) -> tuple[str, str]:
    """The report's row on the Floquet exponents (which numbers are exact, and why)."""
    if not floquet["periodic"]:
        return ("periodic orbit", "none found (no period <= 16 cycles at the end of the run): "
                                  "the QR estimates above stand alone")
    period = floquet["period_cycles"]
    cycles = f"period {period} cycle{'' if period == 1 else 's'}"
    if not floquet["found"]:
        return ("periodic orbit", f"{cycles}, but {floquet['note']}")
    lam = floquet["exponents"][0]
    gap = spectrum.max_exponent - lam
    err = spectrum.max_error
    off = f", {abs(gap) / err:.1f} error bars" if err > 0 else ""
    state = ("exact: the response's Lyapunov exponents; the QR values above are finite-run "
             "estimates" if floquet["exact"] else f"NOT exact ({floquet['note']})")
    return ("Floquet exponents",
            f"{cycles}, orbit solved by Newton (residual {floquet['residual']:.1e}, "
            f"{floquet['method']} monodromy): {state}; lambda_1 = {lam:+.7f} per unit t, "
            f"QR - Floquet = {gap:+.2g}{off}")


def _lyapunov_report(scene, system, spectrum, document: dict, plot: str | None) -> str:
    """Header, exponent table and summary of one Lyapunov run, as text."""
    cycles = (f"{spectrum.transient} transient + {spectrum.tangent_transient} tangent "
              f"transient + {spectrum.cycles} averaged ({document['blocks']} blocks)")
    if system is scene:
        header = [*_system_header(system), ("cycles", cycles)]
    else:
        header = [
            *_scene_rows(scene, f"{system.model_name} ({system.dim} states: "
                                f"{' '.join(system.state_names)})", spectrum.period),
            ("cycles", cycles),
            ("solver", _solver_text(scene.solver)),
        ]  # fmt: skip
    rows = [
        (
            str(i + 1),
            f"{lam:+.6f}",
            f"{err:.2g}",
            f"{lam_c:+.6f}",
            f"{err_c:.2g}",
        )
        for i, (lam, err, lam_c, err_c) in enumerate(
            zip(spectrum.exponents, spectrum.errors, spectrum.per_cycle,
                spectrum.errors_per_cycle, strict=True)
        )
    ]  # fmt: skip
    columns = ("#", "lambda (per unit t)", "+-", "lambda T (per cycle)", "+-")
    floquet = document.get("floquet")
    if floquet is not None and floquet.get("found"):
        mark = "exact" if floquet["exact"] else "not exact"
        columns = (*columns, f"Floquet (per unit t, {mark})")
        rows = [(*row, f"{floquet['exponents'][i]:+.7f}") for i, row in enumerate(rows)]
    total, trace = document["sum"], document["trace"]
    if trace is None or (isinstance(trace, float) and math.isnan(trace)):
        identity = (f"{total:.6g} (no trace identity: the Jacobian's trace is not constant "
                    "along the orbit)")
    elif document["full_spectrum"]:
        identity = f"{total:.6g} (trace identity {trace:.6g}, difference {total - trace:.2g})"
    else:
        identity = (
            f"{total:.6g} (of {document['k']} exponents; the trace identity "
            f"{trace:.6g} holds for all {system.dim})"
        )
    summary = [
        ("sum", identity),
        ("Kaplan-Yorke dimension", f"{document['kaplan_yorke']:.4g}"
         + ("" if document["full_spectrum"] else f" (from {document['k']} exponents)")),
    ]  # fmt: skip
    if floquet is not None:
        summary.append(_floquet_summary(floquet, spectrum))
    two = document.get("two_trajectory")
    if two is not None:
        summary.append((
            "two trajectories",
            f"lambda_1 = {two['exponent']:+.6f} +- {two['error']:.2g} per unit t, "
            f"{two['per_cycle']:+.6f} +- {two['error_per_cycle']:.2g} per cycle "
            f"(separation {two['separation']:g}, rtol {two['rtol']:g}, {two['wall_s']:.3g} s)",
        ))  # fmt: skip
    work = document["work"]
    summary.append(("work", f"{work['steps']} steps, {work['rhs_evals']} rhs evaluations, "
                            f"{work['wall_s']:.3g} s; {_command_seconds():.3g} s the whole "
                            "command"))  # fmt: skip
    if plot is not None:
        summary.append(("wrote", plot))
    blocks = [
        _table(None, header, "ll"),
        _table(columns, rows, "r" * len(columns)),
        _table(None, summary, "ll"),
    ]
    return "\n\n".join(blocks) + "\n"
