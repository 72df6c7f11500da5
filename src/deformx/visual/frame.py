"""A rendered frame and its files: RGB, z-depth, instance ids, keypoints, camera."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .camera import Camera


@dataclass
class Frame:
    """``rgb`` (H, W, 3) uint8; ``depth`` (H, W) float32, z-depth along the optical axis (m),
    +inf where nothing is hit; ``instances`` (H, W) uint16, 0 background, then the ids of
    ``ids`` (rods 1..n in world order first); ``keypoints``: per rod its nodes' pixels (n+1, 2)
    (u right, v down) and ``visible`` (n+1,) flags; ``amodal``: per rod id, its full
    silhouette (H, W) bool, when asked for."""

    rgb: np.ndarray
    depth: np.ndarray
    instances: np.ndarray
    ids: list[dict]
    camera: Camera
    keypoints: list[np.ndarray] = field(default_factory=list)
    visible: list[np.ndarray] = field(default_factory=list)
    amodal: dict[int, np.ndarray] = field(default_factory=dict)

    def add_keypoints(self, rods) -> None:
        """Project each rod's nodes with the camera; a node is visible where the depth image
        is not nearer than the node less 1.5 radii (plus 1 mm)."""
        cam, depth = self.camera, self.depth
        W, H = cam.width, cam.height
        for rod in rods:
            uv, z = cam.project(rod.positions)
            vis = np.zeros(len(z), dtype=bool)
            ok = np.isfinite(uv).all(axis=1) & (uv[:, 0] >= 0) & (uv[:, 0] < W) & \
                (uv[:, 1] >= 0) & (uv[:, 1] < H)
            iu, iv = uv[ok, 0].astype(int), uv[ok, 1].astype(int)
            vis[ok] = z[ok] - depth[iv, iu] <= 1.5 * rod.node_radius[ok] + 1e-3
            self.keypoints.append(uv)
            self.visible.append(vis)

    def mask(self, instance: int) -> np.ndarray:
        """(H, W) bool mask of one instance id."""
        return self.instances == instance

    def save(self, directory: str | Path, stem: str = "") -> dict[str, Path]:
        """Write ``{stem}rgb.png``, ``{stem}depth.npy`` (float32 m, inf = nothing),
        ``{stem}depth_mm.png`` (uint16 mm, 0 = nothing or beyond 65.5 m),
        ``{stem}instances.png`` (uint16 ids), ``{stem}camera.json`` (K, pose, resolution, the
        id table, keypoints) and ``{stem}amodal_{id}.png`` per amodal mask."""
        import imageio.v3 as iio

        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        out = {"rgb": d / f"{stem}rgb.png", "depth": d / f"{stem}depth.npy",
               "depth_mm": d / f"{stem}depth_mm.png", "instances": d / f"{stem}instances.png",
               "camera": d / f"{stem}camera.json"}
        iio.imwrite(out["rgb"], self.rgb)
        np.save(out["depth"], self.depth)
        mm = np.where(np.isfinite(self.depth), np.round(self.depth * 1000.0), 0.0)
        iio.imwrite(out["depth_mm"], np.where(mm > 65535, 0, mm).astype(np.uint16))
        iio.imwrite(out["instances"], self.instances.astype(np.uint16))
        for k, m in self.amodal.items():
            out[f"amodal_{k}"] = d / f"{stem}amodal_{k}.png"
            iio.imwrite(out[f"amodal_{k}"], (m * 255).astype(np.uint8))
        self.camera.save_json(out["camera"], {
            "instances": self.ids,
            "keypoints": [{"rod": i + 1, "uv": kp.tolist(), "visible": v.tolist()}
                          for i, (kp, v) in enumerate(zip(self.keypoints, self.visible))]})
        return out


def load_camera_json(path: str | Path) -> dict:
    """The dict a :meth:`Frame.save` wrote to ``camera.json``."""
    return json.loads(Path(path).read_text())
