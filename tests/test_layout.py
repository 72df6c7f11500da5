"""The package's layers: the engine and the visual layer's package load no app libraries."""

from __future__ import annotations

import subprocess
import sys


def _loaded_after(statement: str, modules: tuple[str, ...]) -> list[str]:
    code = f"import sys\n{statement}\nprint(' '.join(m for m in {modules!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def test_engine_imports_no_app_or_plotting_library():
    # (not yaml: numba itself loads it for its config file)
    assert _loaded_after("import deformx", ("pydantic", "matplotlib", "rich", "typer")) == []


def test_visual_package_does_not_load_matplotlib_until_a_plot_module_is_used():
    assert _loaded_after("import deformx.visual", ("matplotlib",)) == []


def test_moved_modules_live_in_their_layers():
    assert _loaded_after("import deformx.apps.scenes, deformx.apps.bench, deformx.visual.plots",
                         ("deformx.scenes", "deformx.plotting", "deformx.bench")) == []


def test_cosim_is_loaded_only_on_request_and_knows_no_higher_layer():
    assert _loaded_after("import deformx", ("mujoco", "deformx.cosim")) == []
    assert _loaded_after("import deformx.cosim, deformx.robots",
                         ("deformx.visual", "deformx.apps", "matplotlib")) == []


def test_visual_names_of_the_public_api_load_on_first_use():
    assert _loaded_after("import deformx.visual", ("mujoco", "bpy")) == []
    assert _loaded_after("from deformx import visual; visual.Camera, visual.FastRenderer",
                         ("mujoco",)) == ["mujoco"]
