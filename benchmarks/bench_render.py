"""Fast renderer speed: seconds per 640x480 frame (RGB with shadows + z-depth + instance ids,
tube vertices refreshed and uploaded) against MuJoCo's own ``mujoco.Renderer`` drawing RGB only
of the same model in the same run, for shadow maps of 0 (off), 512, 1024, 2048 and 4096 px;
and the tube kernel's cost per 1,000 vertices.

Scene: four ropes (40 elements each) draped over a box and a blob mesh on the ground, camera
at 1.4 m. Rounds interleave the two renderers; the table gives min-max over rounds of the median.

    python benchmarks/bench_render.py            # 3 rounds
    python benchmarks/bench_render.py --quick    # 1 round
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from statistics import median

import numpy as np
from rich.console import Console
from rich.table import Table

import deformx as dx
from deformx.visual.camera import Camera
from deformx.visual.fast import FastRenderer
from deformx.visual.tube import Tube

import mujoco  # noqa: E402  (after deformx.visual.fast chose the headless GL backend)


def scene():
    world = dx.World(dt=1e-3, integrator="stable")
    for k in range(4):
        world.add_rod(dx.Rod.straight(n_elements=40, start=(-0.35, -0.15 + 0.1 * k, 0.12 + 0.02 * k),
                                      direction=(1, 0, 0.1 * (k - 1.5)), length=0.7, radius=0.006))
    world.add_plane()
    world.add_box((0.08, 0.25, 0.05), pose=(0.1, 0.0, 0.05))
    import trimesh

    blob = trimesh.creation.icosphere(subdivisions=3, radius=0.07)
    blob.vertices *= [1.0, 0.8, 0.7]
    world.add_mesh(blob, pose=(-0.15, 0.05, 0.05))
    return world


def time_calls(fn, n: int, repeats: int) -> float:
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        out.append((time.perf_counter() - t0) / n)
    return median(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--rounds", type=int, default=None)
    args = parser.parse_args()
    rounds = args.rounds or (1 if args.quick else 3)
    n, repeats = (5, 2) if args.quick else (10, 3)
    console = Console()
    world = scene()
    cam = Camera(position=(0.9, -1.0, 0.7), look_at=(0.0, 0.0, 0.05), width=640, height=480)
    rows = {}
    for shadow in (0, 512, 1024, 2048, 4096):
        ours = FastRenderer(world, shadows=shadow > 0, shadow_size=max(shadow, 1))
        ours.render(cam)  # contexts, first upload
        peer = mujoco.Renderer(ours.model, cam.height, cam.width)
        ours._sync()
        ours._update_scene(cam)

        def peer_frame():
            peer.update_scene(ours.data, camera="deformx_camera")
            peer.render()

        peer_frame()
        t_ours, t_peer = [], []
        for _ in range(rounds):
            t_ours.append(time_calls(lambda: ours.render(cam), n, repeats))
            t_peer.append(time_calls(peer_frame, n, repeats))
        rows[shadow] = (t_ours, t_peer)
        peer.close()
        ours.close()

    def span(v, scale=1e3):
        lo, hi = min(v) * scale, max(v) * scale
        return f"{lo:.1f}" if len(v) == 1 else f"{lo:.1f}-{hi:.1f}"

    table = Table(title=f"640x480 frame, ms (min-max over {rounds} rounds of medians)")
    for col in ("shadow map", "FastRenderer: RGB + depth + ids + tube upload",
                "mujoco.Renderer: RGB only", "target"):
        table.add_column(col, justify="right")
    for shadow, (o, p) in rows.items():
        table.add_row("off" if shadow == 0 else f"{shadow} px", span(o), span(p), "<= 100")
    console.print(table)

    tube = Tube(world.rods[0], sides=12)
    nv = tube.vertices.shape[0]
    t = time_calls(tube.update, 2000, 5)
    console.print(f"tube kernel: {t * 1e6:.2f} us per update of {nv} vertices = "
                  f"{t * 1e6 * 1000 / nv:.2f} us per 1,000 vertices")
    from deformx.visual import assets

    rod = world.rods[0]
    cable = assets.usb_c_cable(length=rod.length, radius=0.004)
    straight = dx.World()
    bind = straight.add_rod(dx.Rod.straight(n_elements=rod.n_elements, length=rod.length,
                                            radius=0.004))
    skin = cable.skin(bind)
    bind.positions[:, 2] += 0.01 * np.sin(np.linspace(0, 6, bind.n_nodes))  # bent a little
    t = time_calls(skin.update, 500, 5)
    nv = skin.vertices.shape[0]
    console.print(f"skinning (USB-C-like cable, slerped frames): {t * 1e6:.1f} us per update of "
                  f"{nv} vertices = {t * 1e6 * 1000 / nv:.2f} us per 1,000 vertices")
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores, MUJOCO_GL={os.environ.get('MUJOCO_GL')}[/dim]")


if __name__ == "__main__":
    main()
