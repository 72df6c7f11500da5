"""Kernels compiled ahead of first use: the wheel's build compiles them in two processes and
merges their numba caches (deformx.precompile), and an installed wheel's first steps load them.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from importlib.metadata import files
from pathlib import Path

import pytest

import deformx
from deformx.precompile import KINDS, merge_caches, parts

MODULE = """
from numba import njit


@njit(cache=True)
def twice(x):
    return 2 * x
"""


def _python(code: str, path: Path) -> str:
    """Run ``code`` in a fresh interpreter with ``path`` first on sys.path; its stdout."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, (str(path), env.get("PYTHONPATH"))))
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, cwd=path,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_merged_caches_of_two_processes_serve_every_signature_without_compiling(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    for tree in (a, b):
        (tree / "pkg").mkdir(parents=True)
        (tree / "pkg" / "__init__.py").write_text("")
        (tree / "pkg" / "mod.py").write_text(MODULE)
    # process A compiles the int version, process B the int and the float versions: both
    # write data file 1 for their first signature, so the merge must renumber B's second one
    _python("from pkg.mod import twice; twice(3)", a)
    _python("from pkg.mod import twice; twice(4); twice(1.5)", b)
    assert merge_caches(a / "pkg", b / "pkg") == 1  # the int version A already had
    assert len(list((a / "pkg" / "__pycache__").glob("*.nbc"))) == 2
    out = _python("""
        from pkg.mod import twice
        print(twice(3), twice(1.25), sum(twice.stats.cache_hits.values()),
              sum(twice.stats.cache_misses.values()))
    """, a)
    assert out.split() == ["6", "2.5", "2", "0"]  # both loaded, none compiled


def test_the_two_build_processes_share_out_every_kind_once():
    two = parts(2)
    assert sorted(k for part in two for k in part) == list(range(len(KINDS)))
    names = [[KINDS[k][0] for k in part] for part in two]
    assert all(n.startswith("stable") or n == "co-simulation" for n in names[0])
    assert all(n.startswith("verlet") or n == "renderers" for n in names[1])
    three = parts(3)
    assert sorted(k for part in three for k in part) == list(range(len(KINDS)))
    with pytest.raises(ValueError, match="part must be in"):
        deformx.precompile.precompile(echo=None, part=2, n_parts=2)


def _shipped_kernels() -> list:
    return [f for f in files("deformx") or [] if f.suffix == ".nbi"]


@pytest.mark.skipif(not _shipped_kernels(),
                    reason="deformx is not installed from a wheel with its kernels compiled "
                           "(an editable install, or DEFORMX_PRECOMPILE=0)")
def test_an_installed_wheel_steps_every_kind_of_world_without_compiling():
    """The kernels the wheel's build compiled (hatch_build.py) load in a fresh interpreter:
    every world kind, the co-simulation and the renderers step without a numba compile."""
    code = """
        from numba.core import event
        compiled = []

        class Listener(event.Listener):
            def on_start(self, ev):
                name = getattr(ev.data.get("dispatcher"), "py_func", None)
                module = getattr(name, "__module__", "") or ""
                if module.startswith("deformx"):
                    compiled.append(f"{module}.{name.__name__}")

            def on_end(self, ev):
                pass

        event.register("numba:compile", Listener())
        import deformx.precompile as p
        p.precompile(echo=None)
        print(len(compiled), sorted(set(compiled))[:20])
    """
    out = _python(code, Path(deformx.__file__).parent.parent)
    assert out.startswith("0 "), out


def test_precompile_command_runs_every_kind():
    """``deformx precompile`` (editable installs) steps every kind; after an install from the
    wheel it only loads the cache."""
    from typer.testing import CliRunner

    from deformx.cli import app

    result = CliRunner().invoke(app, ["precompile"])
    assert result.exit_code == 0, result.output
    for name, _ in KINDS:
        assert f"{name}:" in result.output
    assert "kernels compiled in" in result.output
