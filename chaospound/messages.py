"""Quoting user input in error messages (no heavy imports: the CLI uses it at startup).

Every error message quotes at most about :data:`QUOTE_LIMIT` characters of a
value the user gave (a grid, a ``--set`` value, a parameter name, a TOML key or
file content), so a 100 kB argument gives a one-line message, not a screenful.
"""

from __future__ import annotations

__all__ = ["QUOTE_LIMIT", "shorten"]

QUOTE_LIMIT = 80  #: characters of a user's value quoted in an error message


def shorten(text: object, limit: int = QUOTE_LIMIT, *, quote: bool = False) -> str:
    """``text`` for an error message: whole if short, else its head and its length.

    Parameters
    ----------
    text : object
        The user's value (converted with ``str``).
    limit : int
        Most characters of ``text`` shown.
    quote : bool
        Quote the text as ``repr`` does (``'gap=1'``).

    Returns
    -------
    str
        ``text`` (or its repr) when it has at most ``limit`` characters, else
        ``'1111...' (100000 characters)``: the first ``limit - 3`` characters,
        "..." and the length.

    Examples
    --------
    >>> shorten("1" * 100_000, 10, quote=True)
    "'1111111...' (100000 characters)"
    """
    text = str(text)
    if len(text) <= limit:
        return repr(text) if quote else text
    head = text[: max(limit - 3, 1)] + "..."
    return f"{head!r} ({len(text)} characters)" if quote else f"{head} ({len(text)} characters)"
