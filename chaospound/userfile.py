"""A user's system from a Python file: the ``FILE.py:ATTR`` spec of the command line.

``chaospound sweep my_oscillator.py:system --param zeta=0.01:0.1#10 -o x.h5``
runs the :class:`~chaospound.dynamics.system.System` that ``my_oscillator.py``
defines as ``system`` (or that ``system()`` returns). The composed engine
imports the user's functions **by module name** (:mod:`chaospound.engine.compose`),
in this process, in the sweep's worker processes and in every later process,
and numba caches its machine code by that module. So the file is not run as
``__main__``: its bytes are copied to ``<cache_root()>/user/chaospound_user_<sha12>.py``
(``sha12``: the first 12 hex digits of the file's sha256), that folder is put
on ``sys.path`` and the module imported from there. The same file gives the
same module name on every run (a numba disk-cache hit: the second process gets
its first result in about a second); an edited file gives a new name, hence a
new engine, and nothing is invalidated by hand. The file's own folder is
appended to ``sys.path`` too, so that it may import its neighbours.

Errors (missing file, import failure, no such attribute, not a System) raise
:class:`SystemSpecError`, a ``ValueError`` with a one-line message: the command
line exits with code 2.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import sys
import uuid
from dataclasses import replace
from pathlib import Path

from .dynamics.system import System
from .engine.compose import cache_root
from .messages import shorten

__all__ = ["SystemSpecError", "is_system_spec", "load_system", "user_folder"]

PREFIX = "chaospound_user_"  #: module names of loaded user files: PREFIX + 12 hex digits


class SystemSpecError(ValueError):
    """A ``FILE.py:ATTR`` spec that does not give a System (one line; exit code 2)."""


def is_system_spec(text: str | None) -> bool:
    """Whether a scene argument names a Python file (``FILE.py:ATTR`` or ``FILE.py``)."""
    if not text:
        return False
    head = text.rpartition(":")[0] if ":" in text else text
    return head.endswith(".py") or text.endswith(".py")


def user_folder() -> Path:
    """Where loaded user files live: ``<cache_root()>/user``."""
    return cache_root() / "user"


def load_system(spec: str) -> System:
    """The System a ``FILE.py:ATTR`` spec names.

    Parameters
    ----------
    spec : str
        ``path/to/file.py:name``; ``name`` is a module-level System of the file or
        a function of no arguments returning one.

    Returns
    -------
    System
        Its ``origin`` set to ``file.py:name`` (part of a sweep store's
        identity of the system, with the file's sha256).

    Raises
    ------
    SystemSpecError
        No ``:ATTR``, a missing file, an exception while importing the file or
        calling ``ATTR``, no such attribute, or something that is not a System.
    """
    text = str(spec)
    file, colon, attr = text.rpartition(":")
    if not colon or not file.endswith(".py"):
        raise SystemSpecError(f"system {shorten(text, quote=True)}: give FILE.py:ATTR, e.g. "
                              "my_oscillator.py:system")
    if not attr.isidentifier():
        raise SystemSpecError(f"system {shorten(text, quote=True)}: {shorten(attr, quote=True)} "
                              "is not a Python name")
    path = Path(file)
    if not path.is_file():
        raise SystemSpecError(f"system file {shorten(file)} not found")
    module = _import_file(path)
    if not hasattr(module, attr):
        found = sorted(k for k, v in vars(module).items()
                       if isinstance(v, System) and not k.startswith("_"))
        hint = f" (it defines the systems: {', '.join(found)})" if found else ""
        raise SystemSpecError(f"{shorten(file)} has no attribute {attr!r}{hint}")
    obj = getattr(module, attr)
    if callable(obj) and not isinstance(obj, System):
        try:
            obj = obj()
        except Exception as exc:  # the user's code: one line
            raise SystemSpecError(f"{shorten(file)}: {attr}() failed: {_first_line(exc)}") \
                from None
    if not isinstance(obj, System):
        raise SystemSpecError(f"{shorten(file)}:{attr} is a {type(obj).__name__}, not a System "
                              "(make one with chaospound.custom_system)")
    return replace(obj, origin=f"{path.name}:{attr}")


def _import_file(path: Path):
    """Import the file under its content-hashed name from the user folder (see the module
    docstring); from its own place when the cache cannot be written."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise SystemSpecError(f"system file {shorten(str(path))}: cannot read it "
                              f"({exc.strerror or exc})") from None
    name = PREFIX + hashlib.sha256(data).hexdigest()[:12]
    home = str(path.resolve().parent)
    if home not in sys.path:
        sys.path.append(home)  # after everything else: the file's neighbours, never shadowing
    if name in sys.modules:
        return sys.modules[name]
    folder = user_folder()
    try:
        target = folder / f"{name}.py"
        if not target.is_file() or target.read_bytes() != data:
            _write_atomically(target, data)
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))
        importlib.invalidate_caches()
        loader = lambda: importlib.import_module(name)  # noqa: E731
    except OSError:  # a read-only cache: import the file where it is, under the same name
        def loader():
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
            return module
    try:
        return loader()
    except BaseException as exc:
        sys.modules.pop(name, None)
        if isinstance(exc, KeyboardInterrupt):
            raise
        raise SystemSpecError(f"{shorten(str(path))}: importing it failed: "
                              f"{_first_line(exc)}") from None


def _write_atomically(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}.tmp")
    with open(temporary, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(temporary, path)


def _first_line(exc: BaseException) -> str:
    lines = str(exc).strip().splitlines()
    text = f"{type(exc).__name__}: {lines[0]}" if lines else type(exc).__name__
    return shorten(text, 200)
