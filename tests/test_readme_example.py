"""The README's Python example runs as written."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_runs(tmp_path, monkeypatch):
    text = README.read_text()
    section = text[text.index("## Using it from Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    assert (tmp_path / "cantilever.npz").exists()


def test_readme_drivers_example_runs():
    text = README.read_text()
    section = text[text.index("Clamps and colliders are kinematic drivers"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    exec(compile("import deformx as dx\n" + code, "README.md", "exec"), {})


def test_readme_cosim_example_runs():
    text = README.read_text()
    section = text[text.index("## Co-simulation with robots (MuJoCo)"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    scope: dict = {}
    exec(compile("import deformx as dx\n" + code, "README.md", "exec"), scope)
    sim, rope = scope["sim"], scope["rope"]
    assert abs(sim.time - 1.0) < 1e-9
    # the tool carries the hanging rope's weight (its wrench points down)
    assert sim.wrench("tool_tip")[2] < -0.5 * rope.mass * 9.81


def test_readme_render_example_runs(tmp_path, monkeypatch):
    text = README.read_text()
    section = text[text.index("## Rendering: RGB, depth, instance masks"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    world_code = ("import deformx as dx\nworld = dx.World()\n"
                  "world.add_rod(dx.Rod.straight(n_elements=10, start=(-0.3, 0, 0.05), "
                  "length=0.6))\nworld.add_plane()\n")
    exec(compile(world_code + code, "README.md", "exec"), {})
    assert (tmp_path / "frames" / "t0_instances.png").is_file()


def test_readme_learning_example_runs():
    import pytest

    pytest.importorskip("gymnasium")
    text = README.read_text()
    section = text[text.index("## Robot learning: the hit-target task"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    code = code.replace("num_envs=32", "num_envs=2")  # the same call, a smaller batch
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
    env, envs = scope["env"], scope["envs"]
    obs, _ = env.reset(seed=0)
    assert obs.shape == (18,) and envs.reset(seed=0)[0].shape == (2, 18)
    env.close()
    envs.close()
