"""``chaospound bench``: speed against scipy's solve_ivp on this machine."""

from __future__ import annotations

import argparse

from chaospound.cli.options import _count0, add_scene_options, scene_from_args
from chaospound.cli.output import EXIT_OK, CliError, _emit, _json_text, _with_units


def add_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "bench",
        help="speed against scipy's solve_ivp on this machine",
        description="Time one steady run (default: preset fig3a) against "
        "scipy.integrate.solve_ivp(RK45) with a pure-Python and a numba right-hand side, "
        "same span and tolerances, in one run; also 'chaospound simulate' end to end.",
    )
    add_scene_options(parser)
    group = parser.add_argument_group("benchmark")
    group.add_argument(
        "--repeats", type=_count0, default=5, metavar="N",
        help="timing rounds (5): chaospound 6x around one run of each solve_ivp variant;"
        " the best of each counts",
    )
    group.add_argument(
        "--no-cli", action="store_true", help="skip timing 'chaospound simulate' in a subprocess"
    )
    group.add_argument("--json", action="store_true", help="print one JSON document only")
    parser.set_defaults(func=_cmd_bench)


def _cmd_bench(args: argparse.Namespace) -> int:
    from chaospound.bench import format_benchmark, run_benchmark

    if args.repeats < 1:
        raise CliError(f"--repeats {args.repeats}: must be an integer >= 1")
    if args.preset is None and args.scene_file is None:
        args.preset = "fig3a"
    scene = scene_from_args(args)
    result = run_benchmark(scene, repeats=args.repeats, cli=not args.no_cli)
    _emit(_json_text(_with_units(result)) if args.json else format_benchmark(result))
    return EXIT_OK
