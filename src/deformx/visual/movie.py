"""Rendering a run: frames from the fast renderer at a fixed rate (a callback), then an MP4,
a contact sheet of key frames and the last frame's RGB, depth, masks and camera files."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .camera import Camera


def auto_camera(world, width: int = 640, height: int = 480, fov_y: float = 45.0) -> Camera:
    """A camera looking at everything in ``world`` (rods and colliders) from the front-left,
    above: the bounding box fills about 70 % of the view."""
    pts = [r.positions for r in world.rods] + [c.position[None] for c in world.colliders]
    for c in world.colliders:
        if c.vertices is not None:
            pts.append(c.vertices @ c.rotation.T + c.position)
        elif c.kind == "box":
            pts.append(np.array([c.position - c.rotation @ c.size, c.position + c.rotation @ c.size]))
    p = np.vstack(pts)
    lo, hi = p.min(axis=0), p.max(axis=0)
    centre = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo)) + 1e-3
    dist = radius / np.tan(np.radians(fov_y) / 2.0) / 0.8
    direction = np.array([0.55, -0.75, 0.45])
    direction /= np.linalg.norm(direction)
    return Camera(position=centre + dist * direction, look_at=centre, up=(0, 0, 1),
                  fov_y=fov_y, width=width, height=height)


class FrameRecorder:
    """A callback (``every`` s) that renders ``source`` (a world or co-simulation) with
    :class:`~deformx.visual.fast.FastRenderer` and keeps the RGB frames; :meth:`finish`
    writes ``{name}.mp4``, ``{name}.png`` (a contact sheet) and ``frames/`` (the last
    frame's rgb, depth, instances, camera.json); ``materials`` and ``skins`` as for the
    renderer."""

    def __init__(self, source: Any, camera: Camera | None = None, every: float = 1 / 30,
                 shadows: bool = True, materials: Any = None, skins: dict | None = None
                 ) -> None:
        from .fast import FastRenderer

        self.renderer = FastRenderer(source, shadows=shadows, materials=materials, skins=skins)
        world = self.renderer.world
        self.camera = camera or auto_camera(world)
        self.every = every
        self.times: list[float] = []
        self.frames: list[np.ndarray] = []
        self.last = None
        self._source = source

    def __call__(self, _source: Any) -> None:
        self.last = self.renderer.render(self.camera)
        self.frames.append(self.last.rgb)
        self.times.append(self.renderer.world.time)

    def finish(self, out: str | Path, name: str, video: bool = True) -> dict[str, Path]:
        """Write the outputs; returns kind -> path."""
        import imageio.v2 as imageio

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        paths: dict[str, Path] = {}
        if not self.frames:
            self(self._source)
        if video:
            fps = 30.0 if len(self.times) < 2 else min(60.0, max(1.0, (len(self.times) - 1) / max(
                self.times[-1] - self.times[0], 1e-9)))
            paths["mp4"] = out / f"{name}.mp4"
            with imageio.get_writer(paths["mp4"], fps=fps, codec="libx264", quality=7,
                                    macro_block_size=16) as w:
                for f in self.frames:
                    w.append_data(_pad16(f))
        paths["png"] = out / f"{name}.png"
        imageio.imwrite(paths["png"], contact_sheet(self.frames, self.times))
        saved = self.last.save(out / "frames", stem="last_")
        paths["frames"] = saved["rgb"].parent
        self.renderer.close()
        return paths


def _pad16(img: np.ndarray) -> np.ndarray:
    h, w = img.shape[:2]
    H, W = -(-h // 16) * 16, -(-w // 16) * 16
    if (H, W) == (h, w):
        return img
    out = np.zeros((H, W, 3), dtype=img.dtype)
    out[:h, :w] = img
    return out


def contact_sheet(frames: list[np.ndarray], times: list[float], n: int = 8,
                  columns: int = 4) -> np.ndarray:
    """``n`` frames evenly spread over the run, half size, in a grid with their times."""
    idx = np.unique(np.linspace(0, len(frames) - 1, min(n, len(frames))).round().astype(int))
    tiles = [frames[i][::2, ::2] for i in idx]
    h, w = tiles[0].shape[:2]
    rows = -(-len(tiles) // columns)
    sheet = np.full((rows * h, columns * w, 3), 255, dtype=np.uint8)
    for k, (i, tile) in enumerate(zip(idx, tiles)):
        r, c = divmod(k, columns)
        sheet[r * h:(r + 1) * h, c * w:(c + 1) * w] = tile
        _stamp(sheet[r * h:(r + 1) * h, c * w:(c + 1) * w], f"{times[i]:.2f}s")
    return sheet


_DIGITS = {  # 3x5 pixel font for time stamps
    "0": "111101101101111", "1": "010110010010111", "2": "111001111100111",
    "3": "111001111001111", "4": "101101111001001", "5": "111100111001111",
    "6": "111100111101111", "7": "111001001001001", "8": "111101111101111",
    "9": "111101111001111", ".": "000000000000010", "s": "000011010001110",
}


def _stamp(tile: np.ndarray, text: str, scale: int = 3) -> None:
    x = 6
    for ch in text:
        bits = _DIGITS.get(ch)
        if bits is None:
            continue
        g = np.array([int(b) for b in bits], dtype=bool).reshape(5, 3)
        g = np.kron(g, np.ones((scale, scale), dtype=bool))
        region = tile[6:6 + g.shape[0], x:x + g.shape[1]]
        region[g[:region.shape[0], :region.shape[1]]] = (20, 20, 20)
        x += g.shape[1] + scale
