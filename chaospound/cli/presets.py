"""``chaospound presets`` (the bundled scenes) and ``chaospound params`` (the flat
parameter names, their meaning, range and default)."""

from __future__ import annotations

import argparse

from chaospound.cli.output import EXIT_OK, CliError, _emit, _table
from chaospound.messages import shorten


def _add_presets(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "presets",
        help="list the bundled scenes, or print one as TOML",
        description="List the bundled scenes; with NAME print its TOML "
        "(e.g. 'chaospound presets fig3a > my.toml', then edit and run my.toml).",
    )
    parser.add_argument("name", nargs="?", metavar="NAME", help="print this preset's TOML")
    parser.set_defaults(func=_cmd_presets)


def _cmd_presets(args: argparse.Namespace) -> int:
    from importlib import resources

    from chaospound.scene import list_presets, load_preset

    if args.name is None:
        rows = [(name, load_preset(name).description) for name in list_presets()]
        _emit(_table(("preset", "description"), rows, "ll"))
        return EXIT_OK
    name = args.name.removesuffix(".toml")
    load_preset(name)  # checks the name and the file
    _emit(resources.files("chaospound").joinpath("presets", name + ".toml").read_text("utf-8"))
    return EXIT_OK


def _add_params(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "params",
        help="list the scene parameters (for --set and scene files)",
        description="Flat parameter names, their meaning and allowed range.",
    )
    parser.add_argument("names", nargs="*", metavar="NAME", help="only these parameters")
    parser.set_defaults(func=_cmd_params)


def _cmd_params(args: argparse.Namespace) -> int:
    from chaospound.scene import parameter_help

    described = parameter_help()
    for name in args.names:
        if name not in described:
            raise CliError(f"unknown parameter {shorten(name, quote=True)} "
                           "(see 'chaospound params')")
    names = args.names or list(described)
    defaults = parameter_defaults()
    rows = [(n, defaults[n], described[n]) for n in names]
    _emit(_table(("parameter", "default", "meaning; range"), rows, "lll"))
    return EXIT_OK


#: parameters whose default is derived from others: what it follows
_DERIVED_DEFAULTS = {
    "mass_ratio": "auto: freq_ratio**2",
    "gyration": "auto: sqrt((l^2+w^2)/12)",
    "width": "width_ratio l",
    "atol": "1e-3 rtol",
}


def parameter_defaults() -> dict[str, str]:
    """Default of every flat parameter and shorthand, as shown by ``chaospound params``.

    Values of the default scene (:class:`~chaospound.scene.Scene` ``()``); a default
    that follows other parameters says what it follows and its default value, e.g.
    ``"auto: freq_ratio**2 = 2.25"``. A shorthand shows the default of the names it sets.
    """
    from chaospound.scene import PARAMETERS, SHORTHANDS, Scene

    values = Scene().to_dict()
    out = {}
    for name in PARAMETERS:
        value = values[name]
        if isinstance(value, bool):
            shown = str(value).lower()
        elif isinstance(value, float):
            shown = f"{value:g}"
        else:
            shown = str(value)
        rule = _DERIVED_DEFAULTS.get(name.removesuffix("_A").removesuffix("_B"))
        out[name] = f"{rule} = {shown}" if rule else shown
    out["model"] = "auto"  # to_dict gives the reduction used; the setting is auto
    for short, names in SHORTHANDS.items():
        out[short] = out[names[0]]
    return out


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``presets`` and ``params`` to the subcommands."""
    _add_presets(commands)
    _add_params(commands)
