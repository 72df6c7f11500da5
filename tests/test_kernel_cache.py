"""Stale numba caches are dropped when a kernel's sources change (numba only watches the
kernel's own file), and kept when anything else (CLI, apps, plots) changes."""

from __future__ import annotations

import shutil
from pathlib import Path

import deformx
from deformx._kernel_cache import invalidate_stale_kernel_caches, kernel_sources

PACKAGE = Path(deformx.__file__).parent

KERNEL = """from numba import njit

from ..consts import K


@njit(cache=True)
def f(x):
    return K * x
"""


def _edit(path: Path, line: str = "# edited\n") -> None:
    path.write_text(path.read_text() + line)


def test_cached_kernels_are_dropped_when_a_kernel_or_what_it_imports_changes(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub" / "__pycache__").mkdir(parents=True)
    (pkg / "consts.py").write_text("K = 1\n")
    (pkg / "app.py").write_text("import numpy\n\nprint('numba: njit(cache=True)')\n")
    (pkg / "sub" / "b.py").write_text(KERNEL)
    cached = pkg / "sub" / "__pycache__" / "b.f-6.py311.nbi"
    cached.write_bytes(b"old")
    assert invalidate_stale_kernel_caches(pkg)  # no stamp yet: clean start
    assert not cached.exists()
    cached.write_bytes(b"fresh")
    assert not invalidate_stale_kernel_caches(pkg)  # unchanged sources: cache kept
    (pkg / "app.py").write_text("x = 3\n")  # not a kernel, not imported by one
    (pkg / "notes.py").write_text("y = 4\n")
    assert not invalidate_stale_kernel_caches(pkg)
    assert cached.exists()
    (pkg / "consts.py").write_text("K = 2\n")  # a constant numba froze into b.f's machine code
    assert invalidate_stale_kernel_caches(pkg)
    assert not cached.exists()


def _package_copy(tmp_path: Path) -> tuple[Path, Path]:
    """A copy of the installed package tree, stamped, with one fake cached kernel in it."""
    root = tmp_path / "deformx"
    shutil.copytree(PACKAGE, root, ignore=shutil.ignore_patterns("__pycache__"))
    assert invalidate_stale_kernel_caches(root)
    cached = root / "engine" / "kernels" / "__pycache__" / "verlet.advance_rod-40.py311.nbi"
    cached.parent.mkdir(exist_ok=True)
    cached.write_bytes(b"compiled")
    return root, cached


def test_the_stamp_covers_the_kernel_modules_of_the_package_and_nothing_else():
    names = {p.relative_to(PACKAGE).as_posix() for p in kernel_sources()}
    assert {"engine/kernels/verlet.py", "engine/kernels/so3.py", "engine/geometry/bvh.py",
            "engine/contact/segments.py"} <= names
    assert "engine/kernels/refcount.py" in names  # no kernel, but compile options kernels import
    for other in ("cli.py", "apps/scenes.py", "apps/bench.py", "visual/plots.py",
                  "engine/world.py", "engine/compile_notice.py", "_kernel_cache.py"):
        assert other not in names


def test_editing_non_kernel_modules_of_the_package_keeps_the_caches(tmp_path):
    root, cached = _package_copy(tmp_path)
    for name in ("cli.py", "apps/scenes.py", "visual/plots.py", "engine/world.py"):
        _edit(root / name)
    (root / "visual" / "renderer.py").write_text('"""A new renderer."""\n\nimport numpy as np\n')
    assert not invalidate_stale_kernel_caches(root)
    assert cached.exists()


def test_editing_a_kernel_module_drops_the_caches(tmp_path):
    root, cached = _package_copy(tmp_path)
    _edit(root / "engine" / "kernels" / "so3.py")
    assert invalidate_stale_kernel_caches(root)
    assert not cached.exists()


def test_a_module_kernels_import_takes_part_without_a_decorator(tmp_path):
    root, cached = _package_copy(tmp_path)
    _edit(root / "engine" / "kernels" / "refcount.py")
    assert invalidate_stale_kernel_caches(root)
    assert not cached.exists()


def test_a_new_kernel_module_takes_part_without_registering_it(tmp_path):
    root, cached = _package_copy(tmp_path)
    new = root / "engine" / "kernels" / "twist.py"
    new.write_text("import numba\n\n\n@numba.njit(cache=True)\ndef twist(x):\n    return 2.0 * x\n")
    assert invalidate_stale_kernel_caches(root)  # a kernel module appeared
    cached.write_bytes(b"compiled")
    assert not invalidate_stale_kernel_caches(root)
    _edit(new)
    assert invalidate_stale_kernel_caches(root)
    assert not cached.exists()


def test_a_cache_built_against_another_numpy_major_is_dropped(tmp_path, monkeypatch):
    """A wheel's shipped cache (hatch_build.py) compiled under numpy 2 is not used under 1."""
    import deformx._kernel_cache as kc

    root, cached = _package_copy(tmp_path)
    assert not invalidate_stale_kernel_caches(root)
    real = kc._major
    monkeypatch.setattr(kc, "_major", lambda p, n=1: "1" if p == "numpy" and real(p) != "1"
                        else "2" if p == "numpy" else real(p, n))
    assert invalidate_stale_kernel_caches(root)
    assert not cached.exists()
