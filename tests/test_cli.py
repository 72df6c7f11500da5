"""The deformx command (demo, run, bench) and YAML scene files, end to end but tiny."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from deformx.apps.scenes import load_scene, parse_scene
from deformx.cli import app, demo_scene

runner = CliRunner()
REPO = Path(__file__).resolve().parents[1]

TINY_SCENE = {
    "dt": 1.0e-4,
    "duration": 0.02,
    "rods": [
        {
            "name": "cantilever",
            "kind": "straight",
            "n_elements": 10,
            "start": [0.0, 0.0, 0.2],
            "direction": [1.0, 0.0, 0.0],
            "normal": [0.0, 0.0, 1.0],
            "length": 0.3,
            "fix_start": True,
            "material": {"radius": 0.005, "density": 1000.0, "youngs_modulus": 1.0e6, "damping": 1.0},
        },
        {
            "kind": "points",
            "points": [[0.0, 0.2, 0.05], [0.1, 0.2, 0.05], [0.2, 0.2, 0.06], [0.3, 0.2, 0.05]],
            "pinned": [0],
            "material": {"youngs_modulus": 5.0e5, "poisson_ratio": 0.4},
        },
    ],
    "planes": [{"point": [0, 0, 0], "normal": [0, 0, 1], "static_friction": 0.5}],
    "output": {"name": "tiny", "record_every": 0.005, "video": False},
}


def write_scene(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data))
    return path


def invoke(args):
    return runner.invoke(app, [str(a) for a in args], env={"COLUMNS": "200"})


def test_run_tiny_scene_writes_npz_and_png(tmp_path):
    scene = write_scene(tmp_path / "tiny.yaml", TINY_SCENE)
    out = tmp_path / "out"
    res = invoke(["run", scene, "--out", out, "--no-progress"])
    assert res.exit_code == 0, res.output
    npz, png = out / "tiny.npz", out / "tiny.png"
    assert npz.is_file() and png.is_file()
    assert png.stat().st_size > 1000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with np.load(npz) as data:
        keys = set(data.files)
        assert {"time", "rod0_positions", "rod0_directors", "rod1_positions", "rod1_directors"} <= keys
        t = data["time"]
        T = len(t)
        assert T >= 4  # 0.02 s sampled every 0.005 s, plus the initial state
        assert t[0] == pytest.approx(0.0)
        assert t[-1] == pytest.approx(0.02, abs=1e-9)
        assert np.all(np.diff(t) > 0)
        assert data["rod0_positions"].shape == (T, 11, 3)
        assert data["rod0_directors"].shape == (T, 10, 3, 3)
        assert data["rod1_positions"].shape == (T, 4, 3)
        assert data["rod1_directors"].shape == (T, 3, 3, 3)
        p0 = data["rod0_positions"]
        assert np.all(np.isfinite(p0))
        # the clamped end stays put, the free end falls under gravity
        assert np.abs(p0[:, 0] - p0[0, 0]).max() < 1e-12
        assert p0[-1, -1, 2] < p0[0, -1, 2]
        # the pinned node of the second rod stays put
        p1 = data["rod1_positions"]
        assert np.abs(p1[:, 0] - p1[0, 0]).max() < 1e-12
    assert "tiny.npz" in res.output and "tiny.png" in res.output


def test_run_uses_output_directory_from_scene(tmp_path, monkeypatch):
    data = dict(TINY_SCENE, duration=0.005, output={"directory": "from-scene", "name": "s", "plot": False})
    scene = write_scene(tmp_path / "s.yaml", data)
    monkeypatch.chdir(tmp_path)
    res = invoke(["run", scene, "--no-progress"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "from-scene" / "s.npz").is_file()
    assert not (tmp_path / "from-scene" / "s.png").exists()


@pytest.mark.parametrize(
    "change, field",
    [
        ({"rods": [{"material": {"youngs_modulus": -1.0}}]}, "rods[0].material.youngs_modulus"),
        ({"rods": [{"n_elements": 1}]}, "rods[0].n_elements"),
        ({"rods": [{"kind": "helix"}]}, "rods[0].kind"),
        ({"rods": [{"n_elements": 5, "pinned": [9]}]}, "rods[0].pinned"),
        ({"planes": [{"normal": [0, 0, 0]}]}, "planes[0].normal"),
        ({"dt": 0.0}, "dt"),
        ({"duration": "long"}, "duration"),
        ({"gravity": [0, 0]}, "gravity"),
        ({"output": {"record_every": -1}}, "output.record_every"),
        ({"rods": [{"material": {"colour": "red"}}]}, "rods[0].material.colour"),
    ],
)
def test_bad_field_is_named(tmp_path, change, field):
    scene = write_scene(tmp_path / "bad.yaml", change)
    res = invoke(["run", scene, "--out", tmp_path / "o"])
    assert res.exit_code == 2
    assert field in res.output, res.output
    assert "Traceback" not in res.output
    with pytest.raises(ValueError, match=field.replace("[", r"\[").replace("]", r"\]")):
        load_scene(scene)


def test_unknown_integrator_and_unavailable_stable_name_the_field(tmp_path):
    with pytest.raises(ValueError, match="integrator"):
        parse_scene({"integrator": "rk4"})
    # "stable" passes validation; the engine decides whether it is available yet.
    scene = write_scene(tmp_path / "stable.yaml", dict(TINY_SCENE, integrator="stable", duration=0.001))
    res = invoke(["run", scene, "--out", tmp_path / "o", "--no-progress"])
    if res.exit_code != 0:
        assert res.exit_code == 2, res.output
        assert "integrator" in res.output
        assert "Traceback" not in res.output


def test_missing_scene_file(tmp_path):
    res = invoke(["run", tmp_path / "nope.yaml"])
    assert res.exit_code == 2
    assert "not found" in res.output


def test_empty_scene_uses_defaults():
    scene = parse_scene(None)
    assert scene.dt > 0 and scene.duration > 0
    assert len(scene.rods) == 1 and scene.rods[0].kind == "straight"
    assert scene.integrator == "verlet"


def test_example_scene_validates():
    scene = load_scene(REPO / "examples" / "scenes" / "drape.yaml")
    assert len(scene.rods) == 2 and len(scene.planes) == 1


def test_demo_short_writes_files(tmp_path):
    out = tmp_path / "demo"
    res = invoke(["demo", "--duration", "0.05", "--out", out, "--no-progress"])
    assert res.exit_code == 0, res.output
    for name in ("demo.npz", "demo.png", "demo.mp4", "frames/last_rgb.png",
                 "frames/last_depth.npy", "frames/last_instances.png", "frames/last_camera.json"):
        f = out / name
        assert f.is_file() and f.stat().st_size > 0, name
    import imageio.v3 as iio

    ids = iio.imread(out / "frames" / "last_instances.png")
    assert set(range(1, len(demo_scene().rods) + 1)) <= set(np.unique(ids).tolist())
    with np.load(out / "demo.npz") as data:
        assert data["time"][-1] == pytest.approx(0.05, rel=1e-3)
        n_rods = sum(1 for k in data.files if k.endswith("_positions"))
        assert n_rods == len(demo_scene().rods)
        for i in range(n_rods):
            assert np.all(np.isfinite(data[f"rod{i}_positions"]))


def test_demo_no_video(tmp_path):
    out = tmp_path / "demo"
    res = invoke(["demo", "--duration", "0.01", "--out", out, "--no-video", "--no-progress"])
    assert res.exit_code == 0, res.output
    assert (out / "demo.npz").is_file() and (out / "demo.png").is_file()
    assert not (out / "demo.mp4").exists()


def test_demo_timestep_is_stable_for_its_stiffest_cable():
    import deformx as dx

    scene = demo_scene()
    assert scene.output.render
    for spec in scene.rods:
        m = spec.material
        rod = dx.Rod.straight(n_elements=spec.n_elements, length=spec.length, radius=m.radius,
                              density=m.density, youngs_modulus=m.youngs_modulus)
        assert scene.dt <= rod.stable_dt() * 1.0001


def test_bench_runs_without_elastica():
    res = invoke(["bench", "--steps", "3", "--no-elastica"])
    assert res.exit_code == 0, res.output
    assert "1 rod x 100 el" in res.output and "64 rods x 50 el" in res.output


def test_version_and_python_dash_m():
    res = invoke(["--version"])
    assert res.exit_code == 0 and "deformx" in res.output
    proc = subprocess.run([sys.executable, "-m", "deformx", "--help"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "demo" in proc.stdout and "bench" in proc.stdout


def test_scene_with_colliders_runs_and_names_bad_fields(tmp_path):
    """examples/scenes/rope_on_shapes.yaml: a mesh file (relative path), a cylinder, rods."""
    from deformx.apps.scenes import build_world

    scene = load_scene(REPO / "examples" / "scenes" / "rope_on_shapes.yaml")
    world, rods = build_world(scene)
    assert [c.kind for c in world.colliders] == ["mesh", "cylinder"]
    world.run(0.4)
    weight = sum(r.mass for r in rods) * 9.81
    load = sum(-c.force[2] for c in world.colliders)
    assert 0.1 * weight < load < 2.0 * weight  # the ropes landed on the plate and the bar
    data = yaml.safe_load((REPO / "examples" / "scenes" / "rope_on_shapes.yaml").read_text())
    data["colliders"][1].pop("radius")
    with pytest.raises(ValueError, match="colliders.1"):
        parse_scene(data)
    data = yaml.safe_load((REPO / "examples" / "scenes" / "rope_on_shapes.yaml").read_text())
    data["colliders"][0]["path"] = "missing.stl"
    with pytest.raises(ValueError, match=r"colliders\[0\].*not found"):
        build_world(parse_scene(data), base_dir=REPO / "examples" / "scenes")


def test_render_command_writes_rendered_outputs(tmp_path):
    out = tmp_path / "r"
    res = invoke(["render", REPO / "examples" / "scenes" / "drape.yaml", "--duration", "0.02",
                  "--out", out, "--no-progress", "--no-video"])
    assert res.exit_code == 0, res.output
    assert (out / "drape.png").is_file() and (out / "frames" / "last_instances.png").is_file()
    assert "contact sheet" in res.output


def test_rod_looks_in_a_scene_file_choose_materials_textures_and_cable_assets(tmp_path):
    from deformx.apps.scenes import _frame_recorder, build_world, load_scene
    from deformx.visual.skin import Skin

    scene = load_scene(REPO / "examples" / "scenes" / "stiff_cables.yaml")
    world, _ = build_world(scene)
    recorder = _frame_recorder(scene, world)
    mats = recorder.renderer.materials
    assert mats[0].metallic == 1.0 and mats[1].texture == "stripe"
    assert isinstance(recorder.renderer.tubes[2], Skin)  # the USB-C model on the PVC cable
    frame = recorder.renderer.render(recorder.camera)
    assert {1, 2, 3} <= set(np.unique(frame.instances))
    # errors name the field
    raw = yaml.safe_load((REPO / "examples" / "scenes" / "stiff_cables.yaml").read_text())
    raw["rods"][1]["look"]["texture"] = "missing.png"
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(raw))
    bad = load_scene(path)
    with pytest.raises(ValueError, match=r"rods\[1\]\.look\.texture"):
        _frame_recorder(bad, build_world(bad)[0])
    raw["rods"][1]["look"] = {"asset": "garden_hose"}
    path.write_text(yaml.safe_dump(raw))
    res = invoke(["run", path, "--out", tmp_path, "--no-progress"])
    assert res.exit_code != 0 and "asset" in res.output


def test_demo_photoreal_without_the_extra_says_how_to_install_it(tmp_path):
    try:
        import bpy  # noqa: F401
        pytest.skip("bpy is installed here: tests/test_visual_photoreal.py runs the option")
    except ImportError:
        pass
    res = invoke(["demo", "--duration", "0.01", "--out", tmp_path, "--photoreal", "--no-progress"])
    assert res.exit_code != 0 and "[photoreal]" in res.output
