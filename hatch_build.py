"""Wheel build hook: compile DeformX's numba kernels while ``pip install .`` builds the wheel,
and ship numba's cache in it, so that the first ``deformx demo`` or ``world.step()`` after an
install loads machine code instead of compiling for minutes.

The kernels are compiled by ``python -m deformx.precompile`` (two processes, each in its own copy
of the sources; their caches are merged) with the same interpreter that installs the wheel, on
the machine it installs on: numba's cache is tied to the CPU, the Python and numba versions and
each source file's content, and falls back to compiling when any of them differs. The wheel is
then tagged for this interpreter and platform. Nothing here can fail the build: if compiling
fails, the wheel is built without the cache (and a warning says why).

``DEFORMX_PRECOMPILE=0`` skips it (a faster install; the kernels then compile on first use).
Editable installs skip it too (numba caches next to the sources there).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

try:
    from hatchling.builders.hooks.plugin.interface import BuildHookInterface
except ImportError:  # benchmarks/bench_coldstart.py imports build_cache() without hatchling
    BuildHookInterface = object

PACKAGE = "deformx"
STAMP = "deformx-sources.sha1"  # written by deformx._kernel_cache on import


def _precompile(tree: Path, args: list[str], timeout: float, what: str) -> str:
    """Run ``python -m deformx.precompile ARGS`` on the package copy in ``tree`` (first on the
    path, numba settings of the caller dropped); its log, or RuntimeError naming ``what``."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, (str(tree), env.get("PYTHONPATH"))))
    env.setdefault("MPLBACKEND", "Agg")
    done = subprocess.run([sys.executable, "-m", f"{PACKAGE}.precompile", *args], cwd=tree,
                          env=env, capture_output=True, text=True, timeout=timeout)
    if done.returncode != 0:
        raise RuntimeError(f"{what} failed:\n{done.stderr[-3000:]}")
    return done.stderr


def _compile_part(tree: Path, part: int, n_parts: int) -> str:
    """Run one part of the precompile in ``tree`` (a copy of src/); returns its output."""
    return _precompile(tree, [f"--part={part + 1}/{n_parts}"], 3600,
                       f"part {part + 1}/{n_parts}")


def _merge_caches(into: Path, other: Path) -> None:
    """Add the kernels cached in the tree ``other`` to those in ``into`` (numba's index files
    hold numba and deformx types: unpickled by the package's own interpreter and path)."""
    _precompile(into, ["--merge", str(into / PACKAGE), str(other / PACKAGE)], 600,
                "merging the caches")


def build_cache(source: Path, work: Path, n_parts: int) -> tuple[Path, list[str]]:
    """Copy the package at ``source`` into ``n_parts`` trees under ``work``, compile one part
    of the kernels in each (at once) and merge their caches into the first; returns that
    package copy and the parts' output. Raises RuntimeError if a part fails."""
    trees = [work / f"tree{k}" for k in range(n_parts)]
    for tree in trees:
        shutil.copytree(source, tree / PACKAGE,
                        ignore=shutil.ignore_patterns("__pycache__", "*.nb[ic]"))
    with ThreadPoolExecutor(n_parts) as pool:
        logs = list(pool.map(_compile_part, trees, range(n_parts), [n_parts] * n_parts))
    for tree in trees[1:]:
        _merge_caches(trees[0], tree)
    return trees[0] / PACKAGE, logs


class PrecompileHook(BuildHookInterface):
    PLUGIN_NAME = "custom"

    def initialize(self, version: str, build_data: dict) -> None:
        if (self.target_name != "wheel" or version != "standard"
                or os.environ.get("DEFORMX_PRECOMPILE", "1").strip() in ("0", "false", "no")):
            return
        self._work = Path(tempfile.mkdtemp(prefix="deformx-precompile-"))
        n_parts = 2 if (os.cpu_count() or 1) >= 2 else 1
        start = time.perf_counter()
        self.app.display_info(f"deformx: compiling the numba kernels ({n_parts} processes; "
                              "DEFORMX_PRECOMPILE=0 skips this) ...")
        try:
            root, logs = build_cache(Path(self.root) / "src" / PACKAGE, self._work, n_parts)
        except Exception as exc:  # never fail the install: the kernels compile on first use
            self.app.display_warning(f"deformx: kernels not precompiled ({exc}); they will "
                                     "compile on first use")
            return
        for log in logs:
            self.app.display_info(log.rstrip())
        files = [*root.rglob("__pycache__/*.nbi"), *root.rglob("__pycache__/*.nbc"),
                 root / "__pycache__" / STAMP]
        for path in files:
            if path.is_file():
                build_data["force_include"][str(path)] = f"{PACKAGE}/{path.relative_to(root)}"
        build_data["pure_python"] = False
        build_data["infer_tag"] = True  # machine code inside: this interpreter and platform
        self.app.display_info(f"deformx: {len(files)} cache files, "
                              f"{time.perf_counter() - start:.0f} s")

    def finalize(self, version: str, build_data: dict, artifact_path: str) -> None:
        work = getattr(self, "_work", None)
        if work is not None:
            shutil.rmtree(work, ignore_errors=True)
