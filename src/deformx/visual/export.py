"""Exporting runs: USD (usd-core) with the wires as time-sampled meshes plus the static scene,
which Isaac Sim, Omniverse and Blender open; PLY / glTF meshes per frame (trimesh).

USD stage: Z up, metres (``metersPerUnit = 1``), ``timeCodesPerSecond`` = the export rate;
``/World/Rods/rod_i`` meshes with time-sampled ``points`` and ``normals`` (topology fixed),
``/World/Colliders/...`` meshes (and their poses, time-sampled when they move), planes as
large quads, each with a display colour.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .fast import COLLIDER_COLORS, PALETTE
from .tube import Tube


def _drawables(world, sides: int, skins: dict | None) -> list:
    skins = skins or {}
    return [skins[i] if i in skins else Tube(rod, sides=sides)
            for i, rod in enumerate(world.rods)]


def _collider_mesh(c) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    if c.vertices is not None:
        return np.asarray(c.vertices), np.asarray(c.faces)
    size = c.size
    if c.kind == "sphere":
        m = trimesh.creation.icosphere(subdivisions=3, radius=size[0])
    elif c.kind == "box":
        m = trimesh.creation.box(extents=2.0 * size)
    elif c.kind == "capsule":
        m = trimesh.creation.capsule(height=2.0 * size[1], radius=size[0], count=[16, 16])
    else:
        m = trimesh.creation.cylinder(radius=size[0], height=2.0 * size[1], sections=32)
    return np.asarray(m.vertices), np.asarray(m.faces)


class UsdWriter:
    """A callback (``every`` = 1 / ``fps`` s) that records the rods' meshes (tubes, or the
    given skins) and the colliders' poses; :meth:`save` writes the ``.usd`` / ``.usda`` /
    ``.usdc`` stage. Use with ``world.run(..., callbacks=[writer])`` or
    ``CoSimulation.run``."""

    def __init__(self, world, path: str | Path, fps: float = 30.0, sides: int = 12,
                 skins: dict | None = None) -> None:
        try:
            from pxr import Usd  # noqa: F401
        except ImportError as err:  # pragma: no cover - usd-core is in the extras
            raise ImportError("USD export needs usd-core: python -m pip install "
                              "'deformx[usd]'") from err
        self.world = world
        self.path = Path(path)
        self.fps = float(fps)
        self.every = 1.0 / self.fps
        self.meshes = _drawables(world, sides, skins)
        self.times: list[float] = []
        self.points: list[list[np.ndarray]] = []
        self.normals: list[list[np.ndarray]] = []
        self.poses: list[list[np.ndarray]] = []

    def __call__(self, _source: Any = None) -> None:
        self.times.append(float(self.world.time))
        pts, nrm = [], []
        for m in self.meshes:
            m.update()
            pts.append(m.vertices.copy())
            nrm.append(m.normals.copy())
        self.points.append(pts)
        self.normals.append(nrm)
        self.poses.append([c.pose.copy() for c in self.world.colliders])

    def save(self) -> Path:
        """Write the stage; returns its path."""
        from pxr import Gf, Usd, UsdGeom, Vt

        if not self.times:
            self()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        stage = Usd.Stage.CreateNew(str(self.path))
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        stage.SetTimeCodesPerSecond(self.fps)
        codes = [round(t * self.fps, 6) for t in self.times]
        stage.SetStartTimeCode(codes[0])
        stage.SetEndTimeCode(codes[-1])
        world_prim = UsdGeom.Xform.Define(stage, "/World")
        stage.SetDefaultPrim(world_prim.GetPrim())
        UsdGeom.Scope.Define(stage, "/World/Rods")
        for i, m in enumerate(self.meshes):
            mesh = UsdGeom.Mesh.Define(stage, f"/World/Rods/rod_{i}")
            faces = np.asarray(m.faces)
            mesh.CreateFaceVertexCountsAttr(Vt.IntArray([3] * len(faces)))
            mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(faces.ravel().tolist()))
            mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
            mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
            mesh.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(*PALETTE[i % len(PALETTE)])]))
            pts, nrm = mesh.CreatePointsAttr(), mesh.CreateNormalsAttr()
            for code, frame_pts, frame_nrm in zip(codes, self.points, self.normals):
                pts.Set(Vt.Vec3fArray.FromNumpy(frame_pts[i].astype(np.float32)), code)
                nrm.Set(Vt.Vec3fArray.FromNumpy(frame_nrm[i].astype(np.float32)), code)
        UsdGeom.Scope.Define(stage, "/World/Colliders")
        for k, c in enumerate(self.world.colliders):
            V, F = _collider_mesh(c)
            xf = UsdGeom.Xform.Define(stage, f"/World/Colliders/collider_{k}")
            op = xf.AddTransformOp()
            moving = any(not np.allclose(p[k], self.poses[0][k]) for p in self.poses)
            for code, poses in (zip(codes, self.poses) if moving else [(None, self.poses[0])]):
                M = Gf.Matrix4d(poses[k].T.tolist())  # USD: row vectors, translation last row
                op.Set(M) if code is None else op.Set(M, code)
            mesh = UsdGeom.Mesh.Define(stage, f"/World/Colliders/collider_{k}/mesh")
            mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
            mesh.CreateFaceVertexCountsAttr(Vt.IntArray([3] * len(F)))
            mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(np.asarray(F).ravel().tolist()))
            mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
            mesh.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(
                *COLLIDER_COLORS[k % len(COLLIDER_COLORS)])]))
        for k, (p, n) in enumerate(self.world.planes):
            from .fast import _frame_z

            R = _frame_z(n)
            half = 5.0
            corners = [p + half * (sx * R[:, 0] + sy * R[:, 1])
                       for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            mesh = UsdGeom.Mesh.Define(stage, f"/World/plane_{k}")
            mesh.CreatePointsAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, c)) for c in corners]))
            mesh.CreateFaceVertexCountsAttr(Vt.IntArray([4]))
            mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([0, 1, 2, 3]))
            mesh.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(0.8, 0.8, 0.78)]))
        stage.GetRootLayer().Save()
        return self.path


def export_meshes(world, directory: str | Path, stem: str = "", fmt: str = "ply",
                  sides: int = 12, skins: dict | None = None) -> list[Path]:
    """Each rod's mesh now (tube or skin) as ``{stem}rod_{i}.{fmt}`` (ply, glb, obj, stl)."""
    import trimesh

    if fmt not in ("ply", "glb", "obj", "stl"):
        raise ValueError(f"fmt must be 'ply', 'glb', 'obj' or 'stl', got {fmt!r}")
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    out = []
    for i, m in enumerate(_drawables(world, sides, skins)):
        m.update()
        tm = trimesh.Trimesh(m.vertices.copy(), np.asarray(m.faces), process=False)
        tm.visual.face_colors = (np.array([*PALETTE[i % len(PALETTE)], 1.0]) * 255).astype(np.uint8)
        path = d / f"{stem}rod_{i}.{fmt}"
        tm.export(path)
        out.append(path)
    return out
