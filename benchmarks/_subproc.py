"""Helpers for the benchmarks that compare two source trees: check a reference commit out into a
temporary folder, and run a snippet in a fresh interpreter that imports ``deformx`` from a given
tree with a given numba cache folder.

The snippet runs as ``python -P -c PRELUDE + code`` with ``PYTHONPATH=<tree>/src``: that puts the
tree ahead of site-packages (and of an editable install's path entry), while numpy, numba and the
rest come from the same environment for both trees. ``PRELUDE`` defines ``_check_tree(module)``,
which exits with an error unless ``deformx`` was imported from ``<tree>/src/deformx``,
``_report(**values)``, which hands numbers back to :func:`run_in_tree`, and
``_numba_cache_stats()``.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
import argparse
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DEFAULT_REFERENCE = "f69ee60"
_MARK = "@@deformx-bench "

PRELUDE = r'''
import json, os, sys, time

def _check_tree(module):
    got = os.path.dirname(os.path.realpath(module.__file__))
    want = os.environ["DEFORMX_BENCH_SRC"]
    if got != want:
        sys.exit(f"deformx was imported from {got}, expected {want}; sys.path[:3] = {sys.path[:3]}")

def _numba_cache_stats():
    """numba disk-cache hits and misses (compilations) of all of deformx's kernels so far."""
    from numba.core.dispatcher import Dispatcher
    kernels = {id(obj): obj for name, mod in list(sys.modules.items())
               if name == "deformx" or name.startswith("deformx.")
               for obj in list(vars(mod).values()) if isinstance(obj, Dispatcher)}
    return {"cache_hits": sum(sum(k._cache_hits.values()) for k in kernels.values()),
            "cache_misses": sum(sum(k._cache_misses.values()) for k in kernels.values())}

def _report(**values):
    print(__MARK__ + json.dumps(values), flush=True)
'''.replace("__MARK__", repr(_MARK))


def tree_parser(doc: str) -> argparse.ArgumentParser:
    """The options both benchmarks share: the tree to measure, the reference commit, rounds."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=doc.split("\n\n", 1)[1])
    parser.add_argument("--tree", type=Path, default=REPO,
                        help="source tree to measure (default: this repository, %(default)s)")
    parser.add_argument("--reference", default=DEFAULT_REFERENCE,
                        help="commit to compare against (default: %(default)s)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (default: 3)")
    return parser


def git(repo: Path, *args: str) -> str:
    """Output of ``git -C repo ARGS`` (stripped); raises on failure."""
    return subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True,
                          text=True).stdout.strip()


def describe_tree(tree: Path) -> str:
    """``<short hash>`` of the tree's HEAD, and whether its ``src`` differs from it."""
    try:
        head = git(tree, "rev-parse", "--short", "HEAD")
        dirty = git(tree, "--no-optional-locks", "status", "--porcelain", "--", "src")
    except (subprocess.CalledProcessError, FileNotFoundError):
        return "not a git checkout"
    return head + (" + uncommitted changes in src" if dirty else "")


@contextlib.contextmanager
def reference_tree(commit: str, repo: Path = REPO) -> Iterator[Path]:
    """A temporary folder holding ``commit``'s files (``git archive``); removed afterwards."""
    git(repo, "rev-parse", "--verify", f"{commit}^{{commit}}")
    tmp = Path(tempfile.mkdtemp(prefix=f"deformx-ref-{commit[:12]}-"))
    try:
        archive = subprocess.Popen(["git", "-C", str(repo), "archive", "--format=tar", commit],
                                   stdout=subprocess.PIPE)
        subprocess.run(["tar", "-x", "-C", str(tmp)], stdin=archive.stdout, check=True)
        archive.stdout.close()
        if archive.wait() != 0:
            raise RuntimeError(f"git archive {commit} failed")
        yield tmp
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def check_tree(tree: Path) -> Path:
    """``tree`` resolved; raises unless it has ``src/deformx/__init__.py``."""
    tree = tree.resolve()
    if not (tree / "src" / "deformx" / "__init__.py").is_file():
        raise SystemExit(f"{tree} has no src/deformx/__init__.py")
    return tree


def numba_cache_files(folder: Path) -> list[Path]:
    """numba cache files (index ``*.nbi`` and data ``*.nbc``) anywhere under ``folder``."""
    return [p for p in folder.rglob("*") if p.suffix in (".nbi", ".nbc")]


def clear_in_tree_caches(tree: Path) -> int:
    """Delete numba's cache files next to the tree's sources; returns how many there were."""
    files = [p for p in numba_cache_files(tree / "src" / "deformx")
             if p.parent.name == "__pycache__"]
    for p in files:
        p.unlink(missing_ok=True)
    return len(files)


def run_in_tree(tree: Path, code: str, cache_dir: Path | None) -> tuple[dict, float]:
    """Run ``PRELUDE + code`` in a fresh interpreter importing deformx from ``tree`` with
    ``NUMBA_CACHE_DIR=cache_dir`` (None: numba's cache next to the sources, as in an installed
    package). Returns the last ``_report(...)`` and the wall seconds of the whole subprocess
    (interpreter start to exit)."""
    env = dict(os.environ, PYTHONPATH=str(tree / "src"),
               DEFORMX_BENCH_SRC=str((tree / "src" / "deformx").resolve()))
    env.pop("NUMBA_CACHE_DIR", None)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = str(cache_dir)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-P", "-c", PRELUDE + code], env=env,
                          cwd=tree if cache_dir is None else cache_dir,
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    reports = [line[len(_MARK):] for line in proc.stdout.splitlines() if line.startswith(_MARK)]
    if proc.returncode != 0 or not reports:
        raise RuntimeError(f"benchmark subprocess for {tree} failed (exit {proc.returncode}):\n"
                           f"{proc.stdout[-2000:]}{proc.stderr[-4000:]}")
    return json.loads(reports[-1]), wall


def prime(tree: Path) -> None:
    """One untimed ``import deformx, trimesh`` from ``tree`` (throwaway numba cache): fills the
    OS file cache and writes the tree's ``.pyc`` files, so that the first timed run is not slower
    for that alone."""
    with tempfile.TemporaryDirectory(prefix="deformx-numba-") as tmp:
        run_in_tree(tree, "import deformx, trimesh\n_check_tree(deformx)\n_report()\n", Path(tmp))


def span(values: Sequence[float], fmt: str = "{:.1f}") -> str:
    """``min–max`` of ``values`` (an en dash, as values may be negative; one number when they
    print alike)."""
    lo, hi = fmt.format(min(values)), fmt.format(max(values))
    return lo if lo == hi else f"{lo}–{hi}"


def now_and_load() -> str:
    """The date and time, and the machine's load average."""
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return f"{time.strftime('%Y-%m-%d %H:%M:%S %Z')}, {os.cpu_count()} CPUs, load average {load}"


def header(tree: Path, reference: str, repo: Path = REPO) -> str:
    """What the numbers depend on: versions, the two trees, the date and the machine's load."""
    from importlib.metadata import version

    ref = git(repo, "rev-parse", "--short", f"{reference}^{{commit}}")
    return (f"{now_and_load()}\nnumba {version('numba')}, numpy {version('numpy')}, "
            f"Python {sys.version.split()[0]} ({sys.executable})\n"
            f"tree: {tree} ({describe_tree(tree)})\nreference: {reference} = {ref}")
