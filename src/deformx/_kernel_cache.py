"""Drop numba's on-disk kernel caches when any of DeformX's sources changed.

numba's ``cache=True`` checks only the source file of the cached function itself, so a kernel
that calls an updated kernel in another module would keep running stale machine code (after an
upgrade or while developing). One stamp over all sources fixes that: when it changes, the cached
kernels next to the sources are deleted and recompiled on first use.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

_STAMP = "deformx-sources.sha1"


def invalidate_stale_kernel_caches(root: Path | None = None) -> bool:
    """Delete cached kernels under ``root`` (the package) if the sources changed; True if so."""
    root = Path(__file__).parent if root is None else root
    digest = hashlib.sha1()
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    stamp = root / "__pycache__" / _STAMP
    try:
        if stamp.exists() and stamp.read_text() == digest.hexdigest():
            return False
        for cached in (*root.rglob("__pycache__/*.nbi"), *root.rglob("__pycache__/*.nbc")):
            cached.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError:  # a read-only install: numba then caches elsewhere, nothing to clean here
        return False
    return True
