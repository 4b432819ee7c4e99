"""Numba's disk cache of the kernels, made safe to use after an edit.

Numba stamps a cached function with the hash of its *own* source file only,
so a cached ``hertz.line_force`` would keep serving the machine code of the
``moments.py`` or ``params.py`` it was compiled with.
:func:`invalidate_stale_cache` therefore hashes every module of the kernel
packages (this one and its siblings :data:`SIBLINGS`: physics, solvers,
engine; and numba's version) and, when the hash differs from the stamp kept
beside this package's cache, deletes the cached kernels of all of them. :mod:`.jit`,
which every module defining a kernel imports first, calls it once per process,
before any kernel can be loaded; importing :mod:`.params` alone (the scene
does) stays free of numba. The generated engines
(:mod:`chaospound.engine.compose`) need none of this: their file names carry
the same hash.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import uuid
from pathlib import Path

__all__ = ["STAMP_NAME", "cache_directory", "invalidate_stale_cache", "source_digest"]

STAMP_NAME = "chaospound-kernels.sha256"  #: the stamp file, in the kernels' cache directory
#: the kernels package, as numba names it (absolute, symlinks not resolved)
_HERE = Path(os.path.dirname(os.path.abspath(__file__)))


SIBLINGS = ("physics", "solvers", "engine")  #: the other kernel packages, beside this one


def source_directories(directory: Path = _HERE) -> list[Path]:
    """This package's directory and every directory of its sibling kernel packages."""
    directory = Path(directory)
    found = [directory]
    for name in SIBLINGS:
        root = directory.parent / name
        if root.is_dir():
            found += sorted({p.parent for p in root.rglob("*.py")})
    return found


def source_digest(directory: Path = _HERE) -> str:
    """sha256 of numba's version and of every ``*.py`` of the kernel packages (name and bytes).

    ``directory`` is this package's directory (of a copy of the package, in the tests).
    """
    import numba

    digest = hashlib.sha256(f"numba {numba.__version__}\n".encode())
    base = Path(directory).parent
    for folder in source_directories(directory):
        for path in sorted(folder.glob("*.py")):
            data = path.read_bytes()
            digest.update(f"{path.relative_to(base)} {len(data)}\n".encode())
            digest.update(data)
    return digest.hexdigest()


def _probe() -> None:
    """Stands in for a kernel when asking numba where it caches this package."""


def cache_directory(directory: Path = _HERE) -> Path | None:
    """Where numba caches the functions of ``directory``'s modules, as numba picks it.

    ``NUMBA_CACHE_DIR/<dir>_<sha1 of its path>`` if the variable is set, else
    the package's ``__pycache__`` if writable, else numba's user-wide cache;
    None if numba would not cache at all (or its locators changed).
    """
    try:
        from numba.core import caching

        mixin = caching._SourceFileBackedLocatorMixin
        impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # numba < 0.61
        source = str(Path(directory) / "__init__.py")
        for cls in impl._locator_classes:
            if issubclass(cls, mixin):
                locator = cls.from_function(_probe, source)
                if locator is not None:
                    return Path(locator.get_cache_path())
    except (ImportError, AttributeError, TypeError):
        return None
    return None


def invalidate_stale_cache(directory: Path = _HERE) -> bool:
    """Delete the cached kernels of the kernel packages if any of their sources changed.

    Safe for processes starting together (two sweeps, pool workers): the cache
    files are deleted first, tolerating files another process already deleted,
    and the stamp is written last, atomically (a private temporary file, then
    ``os.replace``). A process that sees the new stamp therefore never finds a
    stale file; a concurrent deletion costs at worst one more compilation
    (numba itself treats a vanished cache file as a miss).

    Returns
    -------
    bool
        True if the cache was stale and has been cleared.
    """
    cache = cache_directory(directory)
    if cache is None:
        return False
    digest = source_digest(directory)
    stamp = cache / STAMP_NAME
    with contextlib.suppress(OSError):
        if stamp.read_text().strip() == digest:
            return False
    for folder in source_directories(directory):
        where = cache_directory(folder)
        if where is None:
            continue
        for pattern in ("*.nbi", "*.nbc"):
            for path in where.glob(pattern):
                with contextlib.suppress(FileNotFoundError):
                    path.unlink()
    temporary = cache / f"{STAMP_NAME}.{os.getpid()}.{uuid.uuid4().hex[:12]}.tmp"
    try:
        temporary.write_text(digest + "\n")
        os.replace(temporary, stamp)
    except OSError:  # a read-only cache: numba will not write to it either
        with contextlib.suppress(OSError):
            temporary.unlink()
    return True
