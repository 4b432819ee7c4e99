"""Output files of the commands: atomic JSON, checks of output and figure paths
before any work, atomic figures."""

from __future__ import annotations

import os
import tempfile

from chaospound.cli.output import CliError, _json_text, _path
from chaospound.messages import shorten


def write_json_file(document: object, path: str, *, overwrite: bool = False) -> None:
    """Write JSON atomically: a temporary file in the same folder, then a rename.

    Parameters
    ----------
    document : object
        JSON-serialisable; non-finite floats become ``null``.
    path : str
        Target file.
    overwrite : bool
        Replace an existing file (else :class:`CliError`).
    """
    text = _json_text(document)
    check_output_path(path, overwrite=overwrite)
    folder = os.path.dirname(os.path.abspath(path))
    try:
        handle = tempfile.NamedTemporaryFile(
            "w", encoding="utf-8", dir=folder, prefix=".chaospound-", suffix=".tmp", delete=False
        )
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None
    try:
        with handle:
            handle.write(text)
        check_output_path(path, overwrite=overwrite)
        os.replace(handle.name, path)
    except BaseException as exc:
        os.unlink(handle.name)
        if isinstance(exc, OSError):
            raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None
        raise


def check_output_path(path: str, *, overwrite: bool) -> None:
    """Raise :class:`CliError` unless ``path`` can be written (before any work)."""
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise CliError(f"output {_path(path)} is a directory")
    if os.path.exists(path) and not overwrite:
        raise CliError(f"output {_path(path)} exists (use --overwrite to replace it)")
    if not os.path.isdir(folder):
        raise CliError(f"output {_path(path)}: folder {_path(folder)} does not exist")


def check_figure_path(path: str) -> None:
    """Raise :class:`CliError` unless a figure can be drawn to ``path`` (before any work).

    A figure is a derived product: an existing figure is redrawn (no --overwrite
    needed). Refused: a directory, a missing folder, and an extension that is not a
    figure format (so a data file such as .h5 or .json is never replaced by a figure).
    """
    from matplotlib.figure import Figure

    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise CliError(f"output {_path(path)} is a directory")
    if not os.path.isdir(folder):
        raise CliError(f"output {_path(path)}: folder {_path(folder)} does not exist")
    extension = os.path.splitext(path)[1].lstrip(".").lower()
    formats = Figure().canvas.get_supported_filetypes()
    if extension and extension not in formats:
        raise CliError(f"output {_path(path)}: .{shorten(extension)} is not a figure format "
                       f"(use {', '.join('.' + f for f in FIGURE_FORMATS)})")


#: figure formats named in help texts and messages (matplotlib writes more)
FIGURE_FORMATS = ("png", "pdf", "svg")


def _save_figure(fig, path: str) -> None:
    """Write a figure atomically (redrawn if it exists); file errors become CliError."""
    from chaospound.plot import save

    check_figure_path(path)
    try:
        save(fig, path)
    except OSError as exc:
        raise CliError(f"cannot write {_path(path)}: {exc.strerror or exc}") from None
