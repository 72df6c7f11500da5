"""Stale numba caches are dropped when any source changes (numba only watches the own file)."""

from __future__ import annotations

from deformx._kernel_cache import invalidate_stale_kernel_caches


def test_cached_kernels_are_dropped_when_any_source_changes(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub" / "__pycache__").mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "sub" / "b.py").write_text("y = 2\n")
    cached = pkg / "sub" / "__pycache__" / "b.kernel-1.py311.nbi"
    cached.write_bytes(b"old")
    assert invalidate_stale_kernel_caches(pkg)  # no stamp yet: clean start
    assert not cached.exists()
    cached.write_bytes(b"fresh")
    assert not invalidate_stale_kernel_caches(pkg)  # unchanged sources: cache kept
    assert cached.exists()
    (pkg / "a.py").write_text("x = 3\n")  # a change in another module than b.py
    assert invalidate_stale_kernel_caches(pkg)
    assert not cached.exists()
