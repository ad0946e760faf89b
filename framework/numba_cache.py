"""Numba's on-disk cache kept consistent with the sources.

numba keys a cached function on its own file only, so after an edit to a function that others inline
(``block_residual``, ``fk_one``, ...) the callers' cached machine code is stale: it runs the old definition
(seen here: an unknown block kind falling into another kind's branch and writing past its rows). On import, the
package's sources are hashed; when the hash differs from the one stamped beside the cache, every cached entry of
the package is removed and the new hash stamped. A fresh install has no entries; a read-only one keeps its own.

numba's index does not key on its code-generation settings either (the optimization level, bounds checks, debug
information, profiling support): a run under ``NUMBA_ENABLE_PROFILING=1`` (for ``perf``) cached machine code that
later runs then loaded — UR5 pose solves 1.86x slower, same answers, until the cache was dropped (seen here). So
those settings are hashed with the sources.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from numba.core import config as numba_config

PACKAGE = Path(__file__).resolve().parent
STAMP = PACKAGE / "__pycache__" / "numba-sources.sha256"
#: numba's settings that change the machine code it caches (``numba.core.config`` attributes, set from
#: ``NUMBA_OPT``, ``NUMBA_BOUNDSCHECK``, ``NUMBA_DEBUGINFO``, ``NUMBA_ENABLE_PROFILING``)
CODEGEN_SETTINGS = ("OPT", "BOUNDSCHECK", "DEBUGINFO_DEFAULT", "ENABLE_PROFILING")


def sources_hash(package: Path = PACKAGE) -> str:
    """SHA-256 of the package's Python sources (paths and contents, in sorted order) and of numba's
    :data:`CODEGEN_SETTINGS`."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(str(path.relative_to(package)).encode())
        digest.update(path.read_bytes())
    for name in CODEGEN_SETTINGS:
        digest.update(f"{name}={getattr(numba_config, name, None)!r}".encode())
    return digest.hexdigest()


def drop_stale_entries(package: Path = PACKAGE, stamp: Path = STAMP) -> int:
    """Remove the package's cached numba entries (``*.nbi``, ``*.nbc``) if its sources changed since they were
    stamped; returns how many files were removed (0 when the stamp matches or nothing can be written)."""
    current = sources_hash(package)
    try:
        if stamp.read_text() == current:
            return 0
    except OSError:
        pass
    removed = 0
    for pattern in ("*.nbi", "*.nbc"):
        for entry in package.rglob(pattern):
            try:
                entry.unlink()
                removed += 1
            except OSError:
                pass
    try:
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(current)
    except OSError:
        pass
    return removed


def cold(package: Path = PACKAGE) -> bool:
    """Whether none of the package's compiled code is cached yet (a fresh install, or sources changed since the
    cache was stamped): the first solves then compile it, about 3 minutes on 2 cores. ``False`` where the package's
    folder cannot be written (numba caches elsewhere then, and this cannot tell)."""
    if not os.access(package, os.W_OK):
        return False
    return next(package.rglob("*.nbi"), None) is None
