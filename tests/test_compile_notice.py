"""The word on the "deformx" logger while numba compiles a deformx kernel, and only then."""

from __future__ import annotations

import importlib
import logging
import subprocess
import sys
import uuid

import pytest
from numba import njit

import deformx
from deformx.engine import compile_notice

KERNELS = """from numba import njit


@njit(cache={cache})
def inner(x):
    return 2.0 * x


@njit(cache={cache})
def outer(x):
    return inner(x) + 1.0
"""


@pytest.fixture
def probe(tmp_path, monkeypatch):
    """A fresh module ``deformx._probe_<random>`` (a file in tmp_path) with two kernels."""

    made = []

    def make(cache: bool = False):
        name = f"_probe_{uuid.uuid4().hex[:12]}"
        (tmp_path / f"{name}.py").write_text(KERNELS.format(cache=cache))
        monkeypatch.setattr(deformx, "__path__", [*deformx.__path__, str(tmp_path)])
        made.append(f"deformx.{name}")
        return importlib.import_module(made[-1])

    yield make
    for name in made:
        sys.modules.pop(name, None)


def _notices(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "deformx" and r.levelno == logging.INFO]


def test_a_first_compile_logs_once_and_its_duration_and_a_compiled_call_logs_nothing(probe, caplog):
    kernels = probe()
    caplog.set_level(logging.INFO, logger="deformx")
    assert kernels.outer(1.0) == 3.0  # compiles outer, and inner inside it
    messages = _notices(caplog)
    assert len(messages) == 2, messages
    assert messages[0] == compile_notice.START_MESSAGE
    assert messages[1].startswith("compiled numba kernels in ") and messages[1].endswith(" s")
    caplog.clear()
    assert kernels.outer(2.0) == 5.0  # already compiled for float64
    assert kernels.inner(2.0) == 4.0  # compiled inside outer, so nothing to do either
    assert _notices(caplog) == []


def test_compiling_other_packages_functions_logs_nothing(caplog):
    @njit
    def not_ours(x):
        return x + 1

    caplog.set_level(logging.INFO, logger="deformx")
    assert not_ours(1) == 2
    assert _notices(caplog) == []


def test_hooks_see_the_outermost_compile_and_a_failing_hook_breaks_nothing(probe):
    kernels = probe()
    calls = []

    def broken_start() -> None:
        raise RuntimeError("a front end that fails")

    with compile_notice.on_compile(lambda: calls.append("start"), lambda s: calls.append(s)), \
            compile_notice.on_compile(broken_start, lambda s: None):
        assert kernels.outer(1.0) == 3.0
        kernels.outer(2.0)
    assert calls[0] == "start" and len(calls) == 2 and calls[1] > 0.0
    kernels.outer(3)  # a new signature compiles again, but the hooks were removed
    assert len(calls) == 2


def test_loading_kernels_from_numbas_cache_logs_nothing(tmp_path):
    (tmp_path / "_probe_cached.py").write_text(KERNELS.format(cache=True))
    script = (
        "import logging, deformx\n"
        "logging.basicConfig(level=logging.INFO, format='%(name)s: %(message)s')\n"
        f"deformx.__path__.append({str(tmp_path)!r})\n"
        "from deformx._probe_cached import outer\n"
        "print(outer(1.0))\n"
    )

    def run() -> str:
        proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                              check=True, timeout=300)
        assert proc.stdout.strip() == "3.0"
        return proc.stderr

    assert compile_notice.START_MESSAGE in run()  # cold: compiles and writes the cache
    assert "numba kernels" not in run()  # warm: loads it, no compile event


def test_the_cli_spinner_shows_while_compiling_and_is_gone_afterwards(probe, monkeypatch):
    import io
    import time

    from rich.console import Console

    from deformx import cli

    out = io.StringIO()
    monkeypatch.setattr(cli, "console", Console(file=out, force_terminal=True, width=100))
    kernels = probe()
    with cli._compile_spinner():
        kernels.outer(1.0)
        shown = out.getvalue().count(cli.COMPILE_MESSAGE)
        time.sleep(0.3)  # a spinner left running would redraw meanwhile
        kernels.outer(2.0)  # compiled: no second spinner
        assert out.getvalue().count(cli.COMPILE_MESSAGE) == shown
    assert shown >= 1
    with cli._compile_spinner():
        kernels.outer(3)  # a new signature (int64): compiles, spins again
    assert out.getvalue().count(cli.COMPILE_MESSAGE) > shown
