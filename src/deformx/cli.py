"""The ``deformx`` command: ``demo``, ``run SCENE.yaml``, ``render``, ``bench`` and
``train hit-target``."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Optional

import typer
from rich import box
from rich.console import Console
from rich.markup import escape
from rich.table import Table

app = typer.Typer(
    name="deformx",
    help="DeformX: fast Cosserat-rod simulation of wires, cables and ropes.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console()
err_console = Console(stderr=True)

# Demo ropes: (label, Young's modulus in Pa). Same geometry, stiffness over two decades.
DEMO_ROPES = (  # label, Young's modulus (Pa), radius (m)
    ("soft rope, E=1e5 Pa", 1.0e5, 0.006),
    ("rope, E=3e5 Pa", 3.0e5, 0.005),
    ("cord, E=1e6 Pa", 1.0e6, 0.005),
    ("cable, E=2e6 Pa", 2.0e6, 0.004),
    ("stiff cable, E=2e6 Pa", 2.0e6, 0.004),
)


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("deformx")
    except Exception:  # pragma: no cover - running from a source tree
        return "unknown"


def _version_callback(value: bool) -> None:
    if value:
        console.print(f"deformx {_version()}")
        raise typer.Exit()


@app.callback()
def main(
    version: bool = typer.Option(False, "--version", callback=_version_callback, is_eager=True,
                                 help="Print the version and exit."),
) -> None:
    """DeformX: fast Cosserat-rod simulation of wires, cables and ropes."""


def _round_down(x: float) -> float:
    """Largest number of the form m * 10**e with m in {1, 1.5, 2, 2.5, ..., 9.5} that is <= x."""
    e = math.floor(math.log10(x))
    m = math.floor(x / 10.0**e * 2.0) / 2.0
    return float(f"{m}e{e}")


def demo_scene(duration: float = 2.0, out: Path | str = "deformx-demo", video: bool = True):
    """The demo: five cables of different colour and stiffness fall onto a table holding a
    bunny-like blob and a box, drape over them and the table's edges and settle; rendered
    by the fast renderer (shadows), with depth and instance masks of the last frame."""
    from .apps.scenes import (CameraSpec, Collider, Material, Output, Plane, Scene,
                              StraightRod, estimate_stable_dt)

    # Explicit steps at the stiffest cable's limit (~4e-5 s): the stable integrator would take
    # 2 ms steps, but its kernels take ~3 minutes to compile on 2 cores (the explicit ones
    # ~1.5), and the whole demo must stay under 3 minutes from an empty cache.
    length, n_elements, density, damping = 0.8, 24, 1200.0, 1.5
    dt = _round_down(min(estimate_stable_dt(length, n_elements, r, density, E)
                         for _, E, r in DEMO_ROPES))
    starts = ((-0.40, -0.16, 0.62), (-0.38, -0.04, 0.66), (-0.42, 0.06, 0.70),
              (-0.36, 0.16, 0.74), (-0.12, -0.38, 0.78))
    directions = ((1.0, 0.15, 0.0), (1.0, -0.1, 0.0), (1.0, 0.05, 0.0), (1.0, -0.2, 0.0),
                  (0.15, 1.0, 0.0))
    rods = [
        StraightRod(name=label, n_elements=n_elements, start=start, direction=d,
                    normal=(0.0, 0.0, 1.0), length=length,
                    material=Material(radius=r, density=density, youngs_modulus=E,
                                      damping=damping))
        for (label, E, r), start, d in zip(DEMO_ROPES, starts, directions)
    ]
    table_top = 0.40
    colliders = [
        Collider(kind="box", half_extents=(0.32, 0.24, table_top / 2),
                 position=(0.0, 0.0, table_top / 2), static_friction=0.6, kinetic_friction=0.5),
        Collider(kind="blob", radius=0.08, seed=0, position=(-0.08, 0.02, table_top),
                 static_friction=0.5),
        Collider(kind="box", half_extents=(0.05, 0.05, 0.05), position=(0.16, -0.08,
                 table_top + 0.05), static_friction=0.5),
    ]
    return Scene(
        gravity=(0.0, 0.0, -9.81), dt=dt, integrator="verlet", duration=duration, rods=rods,
        planes=[Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), static_friction=0.6,
                      kinetic_friction=0.5)],
        colliders=colliders, rod_contact=True,
        output=Output(directory=str(out), name="demo", record_every=1.0 / 30.0, plot=True,
                      video=video, render=True,
                      camera=CameraSpec(position=(0.95, -1.05, 1.0), look_at=(0.0, 0.0, 0.38),
                                        fov_y=36.0)),
    )


def _human_size(n: int) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n} B"  # pragma: no cover


def _report(result, scene, title: str, compile_hint: bool = True) -> None:
    files = Table(title=title, show_header=True, header_style="bold")
    files.add_column("output")
    files.add_column("path")
    files.add_column("size", justify="right")
    rendered = scene.output.render
    descriptions = {"npz": "trajectory (npz)",
                    "png": "contact sheet (png)" if rendered else "side/top plot (png)",
                    "mp4": "rendered video (mp4)" if rendered else "video (mp4)",
                    "frames": "last frame: rgb, depth, masks, camera"}
    for key, path in result.items():
        p = Path(path)
        size = p.stat().st_size if p.exists() else 0
        files.add_row(descriptions.get(key, key), str(p), _human_size(size))
    console.print(files)

    n_el = sum(r.n_elements if r.kind == "straight" else len(r.points) - (0 if r.closed else 1)
               for r in scene.rods)
    stats = Table(show_header=False, box=None)
    stats.add_column("quantity", style="bold")
    stats.add_column("value")
    stats.add_row("rods / elements", f"{len(scene.rods)} / {n_el}")
    stats.add_row("simulated", f"{result.sim_time:.3f} s in {result.n_steps} steps of dt = {scene.dt:.3g} s")
    per_step = result.wall_time / max(result.n_steps, 1)
    stats.add_row("simulation wall time",
                  f"{result.wall_time:.2f} s  ({per_step * 1e6:.1f} µs/step, "
                  f"{result.sim_time / max(result.wall_time, 1e-12):.2f}x real time)")
    stats.add_row("numba compile / cache load", f"{result.compile_time:.2f} s"
                  + ("  (first run compiles; later runs load the cache)" if compile_hint else ""))
    stats.add_row("plot/video time", f"{result.render_time:.2f} s")
    console.print(stats)


def _fail(message: str, code: int = 2) -> None:
    err_console.print(f"[bold red]error:[/bold red] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


COMPILE_MESSAGE = "Compiling numba kernels (first run, cached afterwards)..."


@contextmanager
def _compile_spinner(enabled: bool = True) -> Iterator[None]:
    """Within the block, one spinner line while numba compiles DeformX's kernels, removed
    when the compile ends (nothing on warm runs, which load the kernels from the cache)."""
    if not enabled:
        yield
        return
    from .engine import compile_notice

    shown = []

    def start() -> None:
        status = console.status(COMPILE_MESSAGE, spinner="dots")
        shown.append(status)
        status.start()

    def end(seconds: float = 0.0) -> None:
        while shown:
            shown.pop().stop()

    with compile_notice.on_compile(start, end):
        try:
            yield
        finally:
            end()


def _run_and_report(scene, out: Optional[Path], title: str, progress: bool) -> None:
    from .apps.scenes import run_scene
    from .errors import SimulationDiverged

    try:
        with _compile_spinner(progress):
            result = run_scene(scene, progress=progress, out_dir=out, title=title)
    except SimulationDiverged as err:
        _fail(str(err), code=1)
    except ValueError as err:
        _fail(str(err))
    _report(result, scene, title)


@app.command()
def demo(
    out: Path = typer.Option(Path("deformx-demo"), "--out", "-o", help="Output directory."),
    duration: float = typer.Option(2.0, "--duration", "-d", min=1e-6, help="Simulated seconds."),
    video: bool = typer.Option(True, "--video/--no-video", help="Also write demo.mp4."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar (and a spinner while kernels compile)."),
    photoreal: bool = typer.Option(False, "--photoreal", help="Also render key frames with Blender Cycles (extra [photoreal])."),
    samples: int = typer.Option(16, "--samples", min=1, help="Cycles samples per pixel for --photoreal."),
) -> None:
    """Five cables of different colour and stiffness fall onto a table with a blob and a box.

    Writes demo.npz (trajectories), demo.mp4 (rendered video), demo.png (contact sheet) and
    frames/ (the last frame's RGB, depth, instance masks, camera.json) to --out; with
    --photoreal also photoreal/ (three key frames path-traced by Cycles).
    """
    scene = demo_scene(duration=duration, out=out, video=video)
    if photoreal:
        try:
            import bpy  # noqa: F401
            import OpenEXR  # noqa: F401
        except ImportError:
            _fail("--photoreal needs the [photoreal] extra: python -m pip install "
                  "\".[photoreal]\" \"numpy<2\" (Python 3.11; on 3.13 numpy>=2.2)")
    console.print(f"[bold]DeformX demo[/bold]: {len(scene.rods)} cables, {duration:g} s simulated, "
                  f"dt = {scene.dt:.3g} s -> {out}")
    _run_and_report(scene, out, "DeformX demo: cables draping over a table", progress)
    if photoreal:
        paths = photoreal_key_frames(scene, Path(out) / "demo.npz", Path(out) / "photoreal",
                                     samples=samples)
        console.print(f"photoreal key frames ({samples} samples, Cycles): "
                      + ", ".join(str(p) for p in paths))


def photoreal_key_frames(scene, record: Path, out: Path, samples: int = 16,
                         count: int = 3) -> list[Path]:
    """Re-pose the scene's world at ``count`` recorded times (first, middle, last) and render
    each with the photoreal renderer; returns the RGB paths."""
    import numpy as np

    from .apps.scenes import build_world
    from .visual.camera import Camera
    from .visual.photoreal import PhotorealRenderer

    world, rods = build_world(scene)
    c = scene.output.camera
    cam = Camera(position=c.position, look_at=c.look_at, up=c.up, fov_y=c.fov_y,
                 width=c.width, height=c.height)
    renderer = PhotorealRenderer(world, samples=samples)
    paths = []
    with np.load(record) as data:
        times = data["time"]
        for k in np.unique(np.linspace(0, len(times) - 1, count).round().astype(int)):
            for i, rod in enumerate(rods):
                rod.positions[:] = data[f"rod{i}_positions"][k]
                rod.directors[:] = data[f"rod{i}_directors"][k]
            frame = renderer.render(cam)
            saved = frame.save(out, stem=f"t{times[k]:.2f}s_")
            paths.append(saved["rgb"])
    return paths


@app.command()
def run(
    scene_file: Path = typer.Argument(..., help="YAML scene file.", exists=False),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Output directory (overrides output.directory)."),
    duration: Optional[float] = typer.Option(None, "--duration", "-d", min=1e-9, help="Override the scene duration (s)."),
    video: Optional[bool] = typer.Option(None, "--video/--no-video", help="Override output.video."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar (and a spinner while kernels compile)."),
) -> None:
    """Run a YAML scene file and write NAME.npz, NAME.png (and NAME.mp4)."""
    scene = _load_for_cli(scene_file, duration, {} if video is None else {"video": video})
    _run_and_report(scene, out, f"DeformX: {scene_file.name}", progress)


def _load_for_cli(scene_file: Path, duration: float | None, output: dict):
    from .apps.scenes import load_scene

    try:
        scene = load_scene(scene_file)
    except (FileNotFoundError, ValueError) as err:
        _fail(str(err))
    if duration is not None:
        scene = scene.model_copy(update={"duration": duration})
    if output:
        scene = scene.model_copy(update={"output": scene.output.model_copy(update=output)})
    return scene


@app.command()
def render(
    scene_file: Path = typer.Argument(..., help="YAML scene file.", exists=False),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Output directory (overrides output.directory)."),
    duration: Optional[float] = typer.Option(None, "--duration", "-d", min=1e-9, help="Override the scene duration (s)."),
    video: bool = typer.Option(True, "--video/--no-video", help="Write NAME.mp4."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar (and a spinner while kernels compile)."),
) -> None:
    """Run a YAML scene file and render it with the fast renderer: NAME.mp4, NAME.png (contact
    sheet), NAME.npz and frames/ (the last frame's RGB, depth, instance masks, camera.json);
    the scene's output.camera, or a camera that sees everything."""
    scene = _load_for_cli(scene_file, duration, {"render": True, "video": video})
    _run_and_report(scene, out, f"DeformX render: {scene_file.name}", progress)


@app.command()
def precompile() -> None:
    """Compile every kind of kernel now (``pip install .`` does this while it builds; run it
    after an editable install or with DEFORMX_PRECOMPILE=0): a few minutes, once."""
    from .precompile import precompile as compile_all

    console.print("Compiling DeformX's numba kernels into numba's cache (once; a few minutes "
                  "on two cores)...")
    compile_all(echo=console.print)


@app.command()
def bench(
    quick: bool = typer.Option(False, "--quick", help="Fewer steps (a rough number in seconds)."),
    elastica: bool = typer.Option(True, "--elastica/--no-elastica",
                                  help="Also time PyElastica when it is installed."),
    steps: Optional[int] = typer.Option(None, "--steps", min=1, help="Steps per case (overrides the default)."),
) -> None:
    """Seconds per step: 1 rod x 100 elements and 64 rods x 50 elements, DeformX vs PyElastica."""
    import numpy as np

    from .apps import bench as b

    with_elastica = elastica and b.elastica_available()
    if steps is not None:
        n_steps = steps
    elif quick:
        n_steps = {"1x100": 2000, "64x50": 200}
    else:
        n_steps = {"1x100": 20000, "64x50": 2000}
    console.print("[bold]DeformX benchmark[/bold] (explicit Verlet, clamped cantilevers under gravity; "
                  "warm-up and numba compilation excluded)")
    if elastica and not with_elastica:
        console.print("PyElastica is not installed: timing DeformX only "
                      "(pip install 'deformx[test]' for the comparison).")

    table = Table(show_header=True, header_style="bold", box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("rods x\nelements", no_wrap=True)
    table.add_column("dt\n[s]", justify="right", no_wrap=True)
    table.add_column("steps", justify="right", no_wrap=True)
    table.add_column("DeformX\nµs/step", justify="right", min_width=7, no_wrap=True)
    table.add_column("x real\ntime", justify="right", no_wrap=True)
    if with_elastica:
        table.add_column("PyElastica\nµs/step", justify="right", min_width=10, no_wrap=True)
        table.add_column("speed-\nup", justify="right", no_wrap=True)
        table.add_column("tip diff\n[m]", justify="right", no_wrap=True)

    def on_result(case, ours, theirs):
        console.print(f"  {case.label()}: DeformX {ours.seconds_per_step * 1e6:.1f} µs/step"
                      + (f", PyElastica {theirs.seconds_per_step * 1e6:.1f} µs/step" if theirs else ""))

    t0 = time.perf_counter()
    results = b.run_cases(n_steps=n_steps, with_elastica=with_elastica, on_result=on_result)
    for ours, theirs in results:
        row = [f"{ours.case.n_rods} x {ours.case.n_elements}", f"{ours.case.dt:.0e}", str(ours.n_steps),
               f"{ours.seconds_per_step * 1e6:.1f}", f"{ours.realtime_factor:.2f}"]
        if with_elastica:
            tip_diff = float(np.linalg.norm(ours.final_tip - theirs.final_tip))
            row += [f"{theirs.seconds_per_step * 1e6:.1f}",
                    f"{theirs.seconds_per_step / ours.seconds_per_step:.1f}x", f"{tip_diff:.1e}"]
        table.add_row(*row)
    console.print(table)
    if with_elastica:
        console.print("tip diff: distance between the two engines' free-end positions of the first "
                      "rod after the same steps (same discretization, so it should be tiny).")
    console.print(f"total wall time {time.perf_counter() - t0:.1f} s")


@app.command()
def calibrate(
    markers: Path = typer.Argument(..., help="Markers CSV (time, marker, x, y, z), e.g. motion capture."),
    motion: Path = typer.Option(..., "--motion", help="Tool-tip path CSV (time, x, y, z) the robot followed."),
    rope: str = typer.Option("cosserat", "--rope", help="cosserat or capsule."),
    density: float = typer.Option(700.0, "--density", min=1e-9, help="kg/m^3, from the measured mass per length."),
    length: float = typer.Option(2.0, "--length", min=1e-9, help="Rope length (m)."),
    radius: float = typer.Option(0.00635, "--radius", min=1e-9, help="Rope radius (m)."),
    evals: int = typer.Option(60, "--evals", min=2, help="Simulations CMA-ES may run."),
    out: Path = typer.Option(Path("deformx-calibration"), "--out", "-o", help="Output directory."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
) -> None:
    """Fit a rope model (Young's modulus and damping) to recorded markers by replaying the
    recorded tool motion in the paper's calibration setup; writes fit.json and
    calibration.png (marker error over time before and after the fit)."""
    import json
    from dataclasses import replace

    from .apps import calibration as cal
    from .apps import rope_fit as rf

    try:
        table = rf.read_markers(markers)
        path = rf.read_motion(motion)
        setup = replace(cal.Setup(), density=density, length=length, radius=radius)
        if rope not in rf.FITTED:
            raise ValueError(f"rope must be one of {tuple(rf.FITTED)}, got {rope!r}")
    except (OSError, ValueError) as err:
        _fail(str(err))
    out.mkdir(parents=True, exist_ok=True)
    n = int(table[:, 1].max()) + 1
    before = cal.marker_error(rf.simulate(rope, replace(setup, markers=n), path,
                                          table[::n, 0]), table)
    t0 = time.perf_counter()
    try:
        result = rf.calibrate(table, path, rope, setup=setup, max_evals=evals, progress=progress)
    except ImportError as err:
        _fail(str(err))
    rf.plot_fit(result, out / "calibration.png", initial=before)
    (out / "fit.json").write_text(json.dumps({
        "rope": rope, "parameters": result.parameters, "mean_error_m": result.error,
        "mean_error_before_m": float(before.mean()), "evaluations": len(result.evaluations),
        "density": density}, indent=1))
    table_out = Table(title=f"DeformX calibrate ({rope}): {len(result.evaluations)} simulations "
                            f"in {time.perf_counter() - t0:.1f} s")
    table_out.add_column("parameter")
    table_out.add_column("fitted", justify="right")
    for k, v in result.parameters.items():
        table_out.add_row(k, f"{v:.4g}")
    table_out.add_row("mean marker error", f"{100 * result.error:.2f} cm (before "
                                           f"{100 * before.mean():.2f} cm)")
    console.print(table_out)
    console.print(f"outputs in {escape(str(out))}: fit.json, calibration.png")


TASKS = ("hit-target",)


@app.command()
def train(
    task: str = typer.Argument(..., help="The task: hit-target."),
    target: tuple[float, float, float] = typer.Option((0.0, 2.0, 2.3), "--target",
                                                      help="Target x y z (m, environment frame)."),
    rope: str = typer.Option("cosserat", "--rope", help="cosserat or capsule."),
    steps: int = typer.Option(200_000, "--steps", min=1, help="Environment steps (all environments)."),
    envs: int = typer.Option(16, "--envs", min=1, help="Environments stepped together."),
    out: Path = typer.Option(Path("deformx-train"), "--out", "-o", help="Run directory."),
    seed: int = typer.Option(0, "--seed"),
    resume: bool = typer.Option(True, "--resume/--restart", help="Continue checkpoints/latest.zip in --out."),
    randomise: float = typer.Option(0.0, "--randomise", min=0.0, max=0.9,
                                    help="Randomise the rope's E, density and damping by +- this fraction."),
    rope_dt: Optional[float] = typer.Option(None, "--rope-dt", help="Cosserat rope step (s), a divisor of 2 ms."),
    rope_elements: Optional[int] = typer.Option(None, "--rope-elements", min=2, help="Elements of the Cosserat rope (task default 20)."),
    rope_order: Optional[int] = typer.Option(None, "--rope-order", min=1, max=2, help="Cosserat rope's stable integrator: 2 BDF2 (task default), 1 backward Euler."),
    continuous_clamp: Optional[bool] = typer.Option(None, "--continuous-clamp/--jumped-clamp", help="Carry the Cosserat rope's clamp on continuously between control steps, or jump it to the arm at each (default: continuous where --rope-dt sub-steps the 2 ms control step)."),
    video: bool = typer.Option(True, "--video/--no-video", help="Write best_rollout.mp4."),
    normalize: bool = typer.Option(False, "--normalize", help="Normalise observations and rewards (SB3's VecNormalize)."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
    rollouts: int = typer.Option(64, "--rollouts", min=1, help="Trajectories the trained policy generates (the deterministic one and the rest with its exploration noise); the best is exported."),
    select: str = typer.Option("best", "--select", help="best: least d_min on the training rope (the paper); robust: least worst d_min over it and finer-step, perturbed and 40-element ropes (Cosserat only; with --deploy-*: over the deployment rope and --robust-draws perturbed draws of it)."),
    robust_draws: int = typer.Option(2, "--robust-draws", min=1, help="Perturbed draws of the deployment rope a robust choice replays every trajectory on (with --deploy-*; more: a choice less lucky on its draws, each draw one more replay of all the rollouts)."),
    robust_pool: int = typer.Option(0, "--robust-pool", min=0, help="A robust choice replays only this many trajectories, the best on the rope they were generated on (0: all): with more --rollouts, a larger sample for the same replays."),
    robust_within: float = typer.Option(0.0, "--robust-within", min=0.0, help="m: a robust choice only among the trajectories within this d_min on the rope they were generated on, e.g. the paper's in-sim figure (0: no bound; none within: among all)."),
    deploy_rope_dt: Optional[float] = typer.Option(None, "--deploy-rope-dt", help="Generate and choose the trajectories on a Cosserat rope of this step (s) instead of the training rope's (e.g. 1.25e-5, finer than training affords)."),
    deploy_rope_elements: Optional[int] = typer.Option(None, "--deploy-rope-elements", min=2, help="Elements of the rope the trajectories are generated on (default: the training rope's)."),
    deploy_rope_order: Optional[int] = typer.Option(None, "--deploy-rope-order", min=1, max=2, help="Its stable integrator's order (default: the training rope's)."),
) -> None:
    """Train PPO (stable-baselines3) on a task; resumable. Writes checkpoints, episodes.csv,
    TensorBoard logs (tb/), learning_curve.png, best_rollout.csv (the joint commands a UR5e
    replays) and .mp4, summary.json. Needs the [learn] extra."""
    if task not in TASKS:
        _fail(f"task must be one of {', '.join(TASKS)}, got {task!r}")
    try:
        from .learn.train import TrainSettings, train as run_training
    except ImportError as err:
        _fail(f"{err}")
    overrides: dict = {"target": tuple(target), "rope": rope}
    if randomise > 0:
        from .learn.task import RANDOMISABLE

        overrides["randomise"] = dict.fromkeys(RANDOMISABLE, randomise)
    for key, value in (("rope_dt", rope_dt), ("n_elements", rope_elements),
                       ("order", rope_order), ("continuous_drivers", continuous_clamp)):
        if value is not None:
            overrides[key] = value
    deploy = {key: value for key, value in (("rope_dt", deploy_rope_dt),
                                            ("n_elements", deploy_rope_elements),
                                            ("order", deploy_rope_order)) if value is not None}
    try:
        settings = TrainSettings(total_steps=steps, num_envs=envs, seed=seed, video=video,
                                 normalize=normalize, rollouts=rollouts, select=select,
                                 robust_draws=robust_draws, robust_pool=robust_pool,
                                 robust_within=robust_within,
                                 task=overrides, deploy=deploy)
        from .learn.task import HitTargetConfig
        from .learn.train import deployed

        # bad task or deployment numbers fail here, before any work
        deployed(HitTargetConfig(**overrides), deploy)
    except ValueError as err:
        _fail(str(err))
    t0 = time.perf_counter()
    summary = run_training(out, settings, resume=resume, progress=progress)
    console.print(f"[bold]DeformX train {task}[/bold]: {summary['timesteps']} environment steps "
                  f"in {time.perf_counter() - t0:.1f} s; {summary['select']} of "
                  f"{summary['rollouts']} rollouts d_min {100 * summary['d_min']:.1f} cm (3D "
                  f"{100 * summary['d_min_3d']:.1f} cm; deterministic "
                  f"{100 * summary['d_min_deterministic']:.1f} cm)")
    console.print(f"outputs in {escape(str(out))}: policy.zip, checkpoints/, episodes.csv, tb/, "
                  "learning_curve.png, best_rollout.csv/.mp4, rollout_scores.csv, summary.json")


if __name__ == "__main__":  # pragma: no cover
    app()
