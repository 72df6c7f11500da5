"""A pinhole camera: intrinsics ``K`` and pose in OpenCV's convention, with the conversions
renderers and exporters need.

Conventions: the camera frame is OpenCV's (x right, y down, z forward, along the optical
axis); ``pose`` is world-from-camera (4x4); pixel ``(u, v)`` covers ``[u, u + 1) x [v, v + 1)``
with ``u`` to the right and ``v`` down, so a point at camera coordinates (X, Y, Z) lands at
``u = fx X / Z + cx``, ``v = fy Y / Z + cy``. ``fov_y`` is in degrees (as MuJoCo and Blender
give it; everything else in DeformX is radians). The OpenGL / USD / MuJoCo camera looks along
its -z with y up: :meth:`Camera.gl_rotation`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np


def _vec(name: str, v, n: int = 3) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be {n} finite numbers, got {v!r}")
    return a


@dataclass
class Camera:
    """``Camera(position, look_at, up=(0, 0, 1), fov_y=45.0, width=640, height=480)`` or with
    ``K`` (3x3 intrinsics, square pixels, principal point at the image centre) instead of
    ``fov_y``; ``near`` / ``far`` (m) bound what is drawn."""

    position: Sequence[float]
    look_at: Sequence[float]
    up: Sequence[float] = (0.0, 0.0, 1.0)
    fov_y: float | None = 45.0
    width: int = 640
    height: int = 480
    K: np.ndarray | None = None
    near: float = 0.01
    far: float = 50.0

    def __post_init__(self) -> None:
        self.position = _vec("position", self.position)
        self.look_at = _vec("look_at", self.look_at)
        self.up = _vec("up", self.up)
        for name in ("width", "height"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or not 1 <= v <= 16384:
                raise ValueError(f"{name} must be an integer in [1, 16384] pixels, got {v!r}")
        forward = self.look_at - self.position
        if np.linalg.norm(forward) == 0.0:
            raise ValueError("look_at must differ from position")
        if np.linalg.norm(np.cross(forward, self.up)) < 1e-9 * np.linalg.norm(forward):
            raise ValueError("up must not be parallel to the viewing direction")
        if self.K is not None:
            K = np.asarray(self.K, dtype=np.float64)
            if K.shape != (3, 3) or not np.all(np.isfinite(K)):
                raise ValueError("K must be a finite 3x3 matrix")
            fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
            if not (fx > 0 and abs(fx - fy) <= 1e-9 * fx and abs(cx - self.width / 2) < 1e-6
                    and abs(cy - self.height / 2) < 1e-6):
                raise ValueError("K: only square pixels (fx = fy > 0) with the principal point "
                                 f"at the image centre ({self.width / 2}, {self.height / 2}) "
                                 "are supported")
            self.fov_y = math.degrees(2.0 * math.atan(0.5 * self.height / fy))
        if self.fov_y is None or not 0.0 < float(self.fov_y) < 180.0:
            raise ValueError(f"fov_y must be in (0, 180) degrees, got {self.fov_y!r}")
        self.fov_y = float(self.fov_y)
        if not 0.0 < self.near < self.far:
            raise ValueError(f"near and far must satisfy 0 < near < far (m), got {self.near}, "
                             f"{self.far}")

    # ------------------------------------------------------------------ intrinsics / pose
    @property
    def focal(self) -> float:
        """Focal length in pixels (fx = fy)."""
        return 0.5 * self.height / math.tan(math.radians(self.fov_y) / 2.0)

    @property
    def intrinsics(self) -> np.ndarray:
        """K (3x3): fx = fy = :attr:`focal`, principal point at the image centre."""
        f = self.focal
        return np.array([[f, 0.0, self.width / 2.0], [0.0, f, self.height / 2.0],
                         [0.0, 0.0, 1.0]])

    @property
    def rotation(self) -> np.ndarray:
        """World-from-camera rotation, OpenCV axes (columns: x right, y down, z forward)."""
        z = self.look_at - self.position
        z = z / np.linalg.norm(z)
        x = np.cross(z, self.up)
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        return np.column_stack([x, y, z])

    @property
    def pose(self) -> np.ndarray:
        """World-from-camera (4x4), OpenCV axes."""
        T = np.eye(4)
        T[:3, :3] = self.rotation
        T[:3, 3] = self.position
        return T

    def gl_rotation(self) -> np.ndarray:
        """World-from-camera rotation in OpenGL / USD / MuJoCo axes (x right, y up, looking
        along -z)."""
        return self.rotation @ np.diag([1.0, -1.0, -1.0])

    # ------------------------------------------------------------------ projection
    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) in camera coordinates (OpenCV axes, m)."""
        p = np.asarray(points, dtype=np.float64)
        return (p - self.position) @ self.rotation

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (..., 2) (u right, v down; continuous) and z-depth (..., m) of
        world points; points behind the camera get NaN pixels."""
        c = self.to_camera(points)
        z = c[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            f = self.focal
            uv = np.stack([f * c[..., 0] / z + self.width / 2.0,
                           f * c[..., 1] / z + self.height / 2.0], axis=-1)
        uv[z <= 0.0] = np.nan
        return uv, z

    def rays(self) -> np.ndarray:
        """Unit-depth rays (H, W, 3) through the pixel centres, camera frame (z = 1)."""
        u = np.arange(self.width) + 0.5
        v = np.arange(self.height) + 0.5
        uu, vv = np.meshgrid(u, v)
        f = self.focal
        return np.stack([(uu - self.width / 2.0) / f, (vv - self.height / 2.0) / f,
                         np.ones_like(uu)], axis=-1)

    def to_dict(self) -> dict:
        """What ``camera.json`` holds: K, pose (world-from-camera, OpenCV), resolution."""
        return {"K": self.intrinsics.tolist(), "pose": self.pose.tolist(),
                "pose_convention": "world-from-camera, OpenCV axes (x right, y down, z forward)",
                "width": int(self.width), "height": int(self.height), "fov_y_deg": self.fov_y,
                "near": self.near, "far": self.far}

    def save_json(self, path, extra: dict | None = None) -> None:
        """Write :meth:`to_dict` (plus ``extra``) as JSON."""
        with open(path, "w") as f:
            json.dump({**self.to_dict(), **(extra or {})}, f, indent=1)
