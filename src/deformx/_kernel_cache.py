"""Drop numba's on-disk kernel caches when the sources of DeformX's kernels changed.

numba's ``cache=True`` checks only the source file of the cached function itself, so a kernel
that calls an updated kernel in another module would keep running stale machine code (after an
upgrade or while developing). One stamp over the kernels' sources fixes that: when it changes,
the cached kernels next to the sources are deleted and recompiled on first use.

The stamp covers only what can change compiled code, so that editing the CLI, an app or a
renderer keeps the caches. Its modules are found from the source text, not from a list, so a
new kernel module anywhere in the package takes part without anyone updating this file:

- every module that imports numba's top level (``import numba``, ``from numba import ...``)
  or uses a jit decorator (``@njit``, ``@jit``, ``@numba.njit``, ``@overload``, ...), and
- every package module those import, transitively (``from .so3 import ...``,
  ``from deformx.engine... import ...``): numba freezes the globals a kernel reads (constants,
  compile options such as ``kernels/refcount.py``'s) into its machine code.

A module that only listens to numba (``from numba.core import event``) and is imported by no
kernel module stays out. When in doubt a module is included: that only costs a recompile.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

_STAMP = "deformx-sources.sha1"

_KERNEL = re.compile(
    rb"^[ \t]*(?:import[ \t]+numba\b|from[ \t]+numba[ \t]+import\b"
    rb"|@[ \t]*(?:numba\.)?(?:njit|jit|generated_jit|vectorize|guvectorize|cfunc|stencil"
    rb"|overload\w*|intrinsic|register_jitable|jitclass)\b)",
    re.M,
)
_FROM = re.compile(rb"^[ \t]*from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)", re.M)
_IMPORT = re.compile(rb"^[ \t]*import[ \t]+([\w.]+)", re.M)


def _module_file(root: Path, parts: list[str]) -> Path | None:
    """``root/a/b.py`` or ``root/a/b/__init__.py`` for ``parts == ['a', 'b']``; None if neither."""
    base = root.joinpath(*parts)
    for candidate in (base.with_suffix(".py") if parts else None, base / "__init__.py"):
        if candidate is not None and candidate.is_file():
            return candidate
    return None


def _imported_files(root: Path, path: Path, source: bytes) -> set[Path]:
    """Files of the package under ``root`` that the module at ``path`` imports."""
    package = list(path.relative_to(root).parent.parts)
    found: set[Path] = set()
    for dots, name, names in _FROM.findall(source):
        parts = name.decode().split(".") if name else []
        if dots:
            up = len(dots) - 1
            if up > len(package):
                continue
            parts = package[: len(package) - up] + parts
        elif parts and parts[0] == root.name:
            parts = parts[1:]
        else:
            continue  # another package
        module = _module_file(root, parts)
        if module is None:
            continue
        if module.name != "__init__.py":
            found.add(module)
            continue
        for item in names.decode().strip("()").split(","):
            item = item.split("#")[0].split(" as ")[0].strip()
            sub = _module_file(root, parts + [item]) if item.isidentifier() else None
            found.add(sub if sub is not None else module)
    for name in _IMPORT.findall(source):
        parts = name.decode().split(".")
        if parts[0] == root.name and (module := _module_file(root, parts[1:])) is not None:
            found.add(module)
    return found


def _kernel_texts(root: Path) -> dict[Path, bytes]:
    """Source text of every module under ``root`` that takes part in the stamp."""
    sources = {path: path.read_bytes() for path in root.rglob("*.py")}
    todo = [path for path, text in sources.items() if _KERNEL.search(text)]
    chosen = set(todo)
    while todo:
        path = todo.pop()
        for dep in _imported_files(root, path, sources[path]):
            if dep not in chosen and dep in sources:
                chosen.add(dep)
                todo.append(dep)
    return {path: sources[path] for path in sorted(chosen)}


def _major(package: str, parts: int = 1) -> str:
    """The first ``parts`` numbers of an installed package's version ("" if not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return ".".join(version(package).split(".")[:parts])
    except PackageNotFoundError:
        return ""


def kernel_sources(root: Path | None = None) -> list[Path]:
    """The modules under ``root`` (default: this package) whose edits can change compiled kernels."""
    return list(_kernel_texts(Path(__file__).parent if root is None else root))


def invalidate_stale_kernel_caches(root: Path | None = None) -> bool:
    """Delete cached kernels under ``root`` (the package) if the kernels' sources changed;
    True if so (also on the first call, when there is no stamp yet)."""
    root = Path(__file__).parent if root is None else root
    digest = hashlib.sha1()
    # Compiled code may also depend on numpy's major version (its type rules) and numba's; a
    # cache shipped in a wheel (hatch_build.py) built against other versions is dropped.
    digest.update(f"numpy {_major('numpy')}, numba {_major('numba', 2)}".encode())
    for path, text in _kernel_texts(root).items():
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(text)
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
