"""Photoreal renderer: seconds per frame against PSNR to a high-sample reference of the same
frame, over sample counts, with and without OpenImageDenoise (Blender Cycles on the CPU).

Scene: the demo's table (five cables, the blob and the box, the ground), camera as in
``deformx demo``; ``--settle S`` first simulates S seconds so that the cables lie draped on the
objects (contact shadows, more occlusion). Needs the [photoreal] extra (bpy, OpenEXR).

    python benchmarks/bench_photoreal.py                       # 640x480, reference 1024 spp
    python benchmarks/bench_photoreal.py --width 320 --height 240 --reference 256 --quick
    python benchmarks/bench_photoreal.py --quick --settle 1.5  # the draped frame
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from rich.console import Console
from rich.table import Table


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10.0 * np.log10(255.0 ** 2 / mse)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--reference", type=int, default=1024, help="samples of the reference")
    parser.add_argument("--quick", action="store_true", help="fewer sample counts")
    parser.add_argument("--settle", type=float, default=0.0,
                        help="simulated seconds before the frame (cables fall and drape)")
    args = parser.parse_args()
    from deformx.apps.scenes import build_world
    from deformx.cli import demo_scene
    from deformx.visual.camera import Camera
    from deformx.visual.photoreal import PhotorealRenderer

    scene = demo_scene()
    world, _ = build_world(scene)
    if args.settle > 0:
        world.run(args.settle, progress=True)
    c = scene.output.camera
    cam = Camera(position=c.position, look_at=c.look_at, fov_y=c.fov_y, width=args.width,
                 height=args.height)
    console = Console()
    renderer = PhotorealRenderer(world, samples=args.reference, denoise=False)
    t0 = time.perf_counter()
    ref = renderer.render(cam).rgb
    t_ref = time.perf_counter() - t0
    console.print(f"reference: {args.reference} samples, {t_ref:.1f} s (t = {world.time:.2f} s)")
    counts = (4, 16, 64) if args.quick else (4, 8, 16, 32, 64, 128)
    table = Table(title=f"Cycles CPU, {args.width}x{args.height}, PSNR to the reference "
                        f"({args.reference} spp, not denoised)")
    for col in ("samples", "denoise", "s per frame", "PSNR (dB)", "goal"):
        table.add_column(col, justify="right")
    for n in counts:
        for denoise in (False, True):
            s = renderer.scene
            s.cycles.samples, s.cycles.use_denoising = n, denoise
            t0 = time.perf_counter()
            img = renderer.render(cam).rgb
            dt = time.perf_counter() - t0
            table.add_row(str(n), "OIDN" if denoise else "-", f"{dt:.2f}", f"{psnr(img, ref):.1f}",
                          ">= 30 dB in <= 4 s")
    console.print(table)
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores[/dim]")


if __name__ == "__main__":
    main()
