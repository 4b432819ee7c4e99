"""The ``chaospound`` command line.

Commands::

    chaospound presets [NAME]            table of presets, or one preset's TOML
    chaospound params [NAME ...]         flat parameter names, meaning and range
    chaospound simulate (--preset NAME | SCENE.toml) [--set k=v ...] [--json] ...
    chaospound section (--preset NAME | SCENE.toml) [--phase P] [--cycles N] [--plot FILE] ...
    chaospound impact-map (--preset NAME | SCENE.toml) [--plot FILE] [--json] ...
    chaospound sweep (--preset NAME | SCENE.toml) [--param NAME=GRID ...] -o FILE.h5 ...
    chaospound basins (--preset NAME | SCENE.toml) --grid NAME=GRID [--grid ...] -o FILE.h5
    chaospound plot FILE.h5 [-o FILE.png|.pdf|.svg] [--branch NAME] [--dpi N] [--size W,H] ...
    chaospound orbit (--preset NAME | SCENE.toml) [--period K] [--json]
    chaospound continue (--preset NAME | SCENE.toml) --param NAME=START:STOP [--period K] -o B.h5
    chaospound plot BRANCH.h5 [--over SWEEP.h5] [-o FILE.png]
    chaospound quake (--preset NAME | SCENE.toml) [--record FILE] [--units si] [--ensemble N] ...

Every command that runs a scene takes the same scene options, added by
:func:`add_scene_options` and turned into a validated
:class:`~chaospound.scene.Scene` by :func:`scene_from_args`; later commands
(lyapunov, classify, sweep, plot, bench) reuse both. ``simulate``, ``section``,
``impact-map``, ``classify``, ``lyapunov`` and ``sweep`` also take a user's system,
``FILE.py:ATTR`` in place of the scene file (:func:`target_from_args`, :mod:`chaospound.userfile`).

Exit codes: 0 success; 1 a numerical failure
(:class:`~chaospound.simulate.SimulationError`); 2 bad input (usage, scene
parameters, scene files, output files), reported as one line
``chaospound: error: ...`` on stderr with nothing written; 130 interrupted.

Heavy modules (numpy through the scene layer, numba through the kernels) are
imported inside the command functions, so ``chaospound --help`` and usage
errors stay fast.

Layout: one module per command (:mod:`~chaospound.cli.presets` with params,
:mod:`~chaospound.cli.simulate`, :mod:`~chaospound.cli.section`,
:mod:`~chaospound.cli.impact_map`, :mod:`~chaospound.cli.lyapunov`,
:mod:`~chaospound.cli.classify`, :mod:`~chaospound.cli.sweep`,
:mod:`~chaospound.cli.basins`,
:mod:`~chaospound.cli.plot`, :mod:`~chaospound.cli.bench`,
:mod:`~chaospound.cli.orbit` with continue, :mod:`~chaospound.cli.quake`), each with
``add_parser(commands)``
and its ``_cmd_*`` function, registered by :data:`COMMANDS`; the shared helpers
in :mod:`~chaospound.cli.options` (scene options, argparse types),
:mod:`~chaospound.cli.output` (exit codes, stderr lines, stdout, tables, JSON),
:mod:`~chaospound.cli.files` (output paths, atomic writes),
:mod:`~chaospound.cli.reports` (report headers) and
:mod:`~chaospound.cli.status` (the status line, kernel loading). A new command
is a new module plus one entry of :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import NoReturn

from chaospound.cli import (
    basins,
    bench,
    classify,
    impact_map,
    lyapunov,
    orbit,
    plot,
    presets,
    quake,
    section,
    simulate,
    sweep,
)
from chaospound.cli.files import check_figure_path as check_figure_path
from chaospound.cli.files import check_output_path as check_output_path
from chaospound.cli.files import write_json_file as write_json_file
from chaospound.cli.options import add_output_options as add_output_options
from chaospound.cli.options import add_scene_options as add_scene_options
from chaospound.cli.options import scene_from_args as scene_from_args
from chaospound.cli.options import target_from_args as target_from_args
from chaospound.cli.output import (
    EXIT_BROKEN_PIPE,
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    PROG,
    CliError,
    _fail,
    _is_simulation_error,
    _silence_stdout,
)
from chaospound.cli.plot import _sweep_figure as _sweep_figure
from chaospound.cli.presets import parameter_defaults as parameter_defaults
from chaospound.cli.section import distinct_points as distinct_points
from chaospound.cli.status import STATUS_DELAY_S as STATUS_DELAY_S
from chaospound.cli.status import _load_kernels as _load_kernels
from chaospound.cli.status import _start_command
from chaospound.cli.status import _Status as _Status
from chaospound.cli.sweep import SWEEP_CLASSIFY as SWEEP_CLASSIFY
from chaospound.cli.sweep import SWEEP_CONTINUATIONS as SWEEP_CONTINUATIONS
from chaospound.cli.sweep import note_sweep_overrides as note_sweep_overrides
from chaospound.messages import QUOTE_LIMIT, shorten

__all__ = [
    "CliError",
    "EXIT_FAILURE",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_USAGE",
    "add_scene_options",
    "build_parser",
    "main",
    "note_sweep_overrides",
    "scene_from_args",
    "target_from_args",
    "write_json_file",
]
# the ``NAME as NAME`` imports above re-export what tests, benchmarks and scripts
# import from chaospound.cli, so that the split into modules changed no importer

#: the command modules, in the order of ``chaospound --help``: each adds its
#: subcommands with ``add_parser(commands)``
COMMANDS = (presets, simulate, section, impact_map, lyapunov, classify, sweep, basins, plot,
            bench, orbit, quake)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit code: 0 success, 1 numerical failure, 2 bad input, 130
        interrupted. Only ``python -m chaospound`` and the console script turn
        it into ``SystemExit``.
    """
    _start_command()
    try:
        try:
            args = build_parser().parse_args(argv)
            return args.func(args)
        except _ParserExit as done:  # --help, --version
            return done.status
        except ValueError as exc:  # SceneError, CliError, usage errors
            return _fail(str(exc), EXIT_USAGE)
        except RuntimeError as exc:
            if not _is_simulation_error(exc):
                raise
            return _fail(str(exc), EXIT_FAILURE)
    except KeyboardInterrupt:
        return _fail("interrupted", EXIT_INTERRUPTED)
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_BROKEN_PIPE


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand.

    Returns
    -------
    argparse.ArgumentParser
        Usage errors raise :class:`CliError`; ``--help`` and ``--version``
        raise a private exception that :func:`main` turns into exit code 0.
    """
    from chaospound import __version__

    parser = _Parser(
        prog=PROG,
        description="Chaotic seismic pounding between two towers: scenes, runs, analyses.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        command.add_parser(commands)
    return parser


class _ParserExit(Exception):
    """argparse finished early (--help, --version) with this exit status."""

    def __init__(self, status: int) -> None:
        super().__init__(status)
        self.status = status


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are exceptions, so :func:`main` returns codes."""

    def error(self, message: str) -> NoReturn:
        raise CliError(_shorten_words(message))

    def exit(self, status: int = 0, message: str | None = None) -> NoReturn:
        if message:
            sys.stderr.write(message)
        raise _ParserExit(status)


def _shorten_words(message: str) -> str:
    """argparse's message with every long word (an argument it quotes whole) cut short."""
    words = []
    for word in message.split(" "):
        if len(word) > QUOTE_LIMIT and word[0] == word[-1] and word[0] in "'\"":
            word = shorten(word[1:-1], quote=True)
        elif len(word) > QUOTE_LIMIT:
            word = shorten(word)
        words.append(word)
    return " ".join(words)
