"""The photoreal renderer: Blender Cycles on the CPU through ``bpy`` (extra ``[photoreal]``),
with the fast renderer's interface: ``render(camera)`` -> :class:`~deformx.visual.frame.Frame`.

Path tracing with bounces and OpenImageDenoise; each render writes one multilayer EXR whose
Depth pass (z-depth along the optical axis, Blender's 1e10 where nothing is hit -> +inf) and
Object Index pass (an integer per pixel, not filtered: instance ids, the same table as the
fast renderer's) are read back with the ``OpenEXR`` package, and the colour-managed RGB is
saved from the render result. Wire meshes are updated in place between frames
(``foreach_set``), with persistent data on. ``bpy`` is one Blender per process: one
PhotorealRenderer at a time (a new one resets Blender's scene).

Python 3.11 has bpy 5.0.1 (numpy < 2); Python 3.13 has bpy 5.2.x (numpy >= 2.2).
"""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from .camera import Camera
from .export import _collider_mesh, _drawables
from .fast import COLLIDER_COLORS, _frame_z, drawn_by_bodies, rod_materials, world_and_sim
from .frame import Frame
from .materials import texture_image

_BACKGROUND_DEPTH = 1e9  # Blender writes 1e10 where a ray hits nothing


class _Quiet:
    """Blender prints a line per render tile and file to the C-level stdout: silence it."""

    def __enter__(self):
        import sys

        sys.stdout.flush()
        self._saved = os.dup(1)
        self._null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self._null, 1)
        return self

    def __exit__(self, *exc):
        os.dup2(self._saved, 1)
        os.close(self._saved)
        os.close(self._null)
        return False


def _bpy():
    try:
        import bpy
    except ImportError as err:
        raise ImportError("PhotorealRenderer needs Blender's bpy: python -m pip install "
                          "'deformx[photoreal]' (bpy 5.0.1 on Python 3.11 with numpy<2, "
                          "bpy 5.2 on Python 3.13)") from err
    return bpy


def _texture(bpy, mat, image: np.ndarray, name: str) -> None:
    """Base colour from ``image`` (rows round the wire from t = 0, columns along it) through
    the mesh's UV map; the image repeats along the wire."""
    H, W = image.shape[:2]
    img = bpy.data.images.new(name, W, H)
    rgba = np.ones((H, W, 4), dtype=np.float32)
    rgba[..., :3] = (image / 255.0) ** 2.2  # sRGB bytes -> linear (close enough for albedo)
    img.pixels.foreach_set(rgba.ravel())  # Blender's first row is the bottom: t = 0
    img.pack()
    nodes = mat.node_tree.nodes
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = img
    tex.extension = "REPEAT"
    mat.node_tree.links.new(tex.outputs["Color"], nodes.get("Principled BSDF").inputs[
        "Base Color"])


def _material(bpy, name: str, color, roughness: float = 0.75, metallic: float = 0.0,
              checker: bool = False):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:  # Blender < 5 makes node trees on request
        mat.use_nodes = True
    nodes = mat.node_tree.nodes
    bsdf = nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    if checker:
        tex = nodes.new("ShaderNodeTexChecker")
        tex.inputs["Scale"].default_value = 100.0  # 10 cm squares on the 20 m plane
        tex.inputs["Color1"].default_value = (0.85, 0.85, 0.83, 1.0)
        tex.inputs["Color2"].default_value = (0.68, 0.68, 0.66, 1.0)
        mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    return mat


class PhotorealRenderer:
    """Renders a :class:`deformx.World` (rods, colliders, planes) or a co-simulation (and
    its MuJoCo geoms) with Cycles.

    ``samples`` per pixel, ``denoise`` (OpenImageDenoise), ``max_bounces``, ``sides`` of the
    tubes, ``skins`` (rod index -> Skin), ``colors`` and ``materials`` (rod index ->
    Material, textures included) as for the fast renderer; ``threads`` (default: all cores).
    """

    def __init__(self, source: Any, samples: int = 32, denoise: bool = True,
                 max_bounces: int = 6, sides: int = 16, skins: dict | None = None,
                 colors: Any = None, threads: int | None = None,
                 materials: Any = None) -> None:
        world, sim = world_and_sim(source)
        self.sim = sim
        bpy = self.bpy = _bpy()
        import addon_utils

        with _Quiet():
            bpy.ops.wm.read_factory_settings(use_empty=True)
            addon_utils.enable("cycles", default_set=True)
        self.world = world
        s = self.scene = bpy.context.scene
        s.render.engine = "CYCLES"
        s.cycles.device = "CPU"
        s.cycles.samples = int(samples)
        s.cycles.use_denoising = bool(denoise)
        if denoise:
            s.cycles.denoiser = "OPENIMAGEDENOISE"
        s.cycles.max_bounces = int(max_bounces)
        s.render.use_persistent_data = True
        s.render.threads_mode = "FIXED"
        s.render.threads = int(threads or os.cpu_count() or 1)
        s.render.resolution_percentage = 100
        s.view_settings.view_transform = "Standard"
        layer = s.view_layers[0]
        layer.use_pass_z = True
        layer.use_pass_object_index = True
        sky = bpy.data.worlds.new("sky")
        if sky.node_tree is None:
            sky.use_nodes = True
        bg = sky.node_tree.nodes.get("Background")
        bg.inputs["Color"].default_value = (0.78, 0.82, 0.88, 1.0)
        bg.inputs["Strength"].default_value = 0.25
        s.world = sky
        sun = bpy.data.lights.new("sun", "SUN")
        sun.energy = 1.6
        sun.angle = math.radians(8.0)
        sun_obj = bpy.data.objects.new("sun", sun)
        s.collection.objects.link(sun_obj)
        sun_obj.matrix_world = self._matrix(_frame_z(-np.array([-0.3, 0.2, -1.0])),
                                            np.array([0.0, 0.0, 5.0]))
        cam = bpy.data.cameras.new("camera")
        self.camera_obj = bpy.data.objects.new("camera", cam)
        s.collection.objects.link(self.camera_obj)
        s.camera = self.camera_obj
        # rods, colliders, planes: pass indices = instance ids, in the fast renderer's order
        self.meshes = _drawables(world, sides, skins)
        self.materials = rod_materials(len(self.meshes), colors, materials)
        self.ids: list[dict] = []
        self._rod_data = []
        for i, m in enumerate(self.meshes):
            m.update()
            look = self.materials[i]
            mat = _material(bpy, f"rod_{i}", look.color, look.roughness, look.metallic)
            obj = self._mesh_object(f"rod_{i}", m.vertices, m.faces, mat)
            image = texture_image(look) if hasattr(m, "uv") else None
            if image is not None:
                uv = m.uv / np.array([look.texture_scale, 1.0])
                layer = obj.data.uv_layers.new(name="UVMap")
                loops = np.empty(len(obj.data.loops), dtype=np.int64)
                obj.data.loops.foreach_get("vertex_index", loops)
                layer.data.foreach_set("uv", uv[loops].astype(np.float32).ravel())
                _texture(bpy, mat, image, f"rod_{i}_texture")
            parts = getattr(m, "materials", None)
            if parts:  # a cable asset: one material per part (jacket, plug, shell, ...)
                obj.data.materials.clear()
                for k, mat in enumerate(parts):
                    obj.data.materials.append(_material(bpy, f"rod_{i}_part{k}", mat.color,
                                                        mat.roughness, mat.metallic))
                obj.data.polygons.foreach_set("material_index",
                                              np.asarray(m.part, dtype=np.int32))
            self._rod_data.append(obj.data)
            self._add_id(obj, "rod", f"rod {i}")
        # colliders and planes standing for MuJoCo geoms are drawn as those geoms
        from_bodies, body_planes = drawn_by_bodies(sim)
        self._collider_objs = []
        for k, c in enumerate(c for c in world.colliders if id(c) not in from_bodies):
            V, F = _collider_mesh(c)
            obj = self._mesh_object(f"collider_{k}", V, F, _material(
                bpy, f"collider_{k}", COLLIDER_COLORS[k % len(COLLIDER_COLORS)], 0.6),
                smooth=c.kind in ("sphere", "capsule", "mesh"))
            self._collider_objs.append((obj, c))
            self._add_id(obj, "collider", f"collider {c.index} ({c.kind})")
        for k, (p, n) in enumerate(world.planes):
            if k in body_planes:
                continue
            R = _frame_z(n)
            quad = np.array([[-10, -10, 0], [10, -10, 0], [10, 10, 0], [-10, 10, 0.0]])
            obj = self._mesh_object(f"plane_{k}", quad, np.array([[0, 1, 2], [0, 2, 3]]),
                                    _material(bpy, f"plane_{k}", (0.8, 0.8, 0.78), 0.8,
                                              checker=True), smooth=False)
            obj.matrix_world = self._matrix(R, p)
            self._add_id(obj, "plane", f"plane {k}")
        self._geom_objs = self._mujoco_geoms(sim) if sim is not None else []
        self._tmp = tempfile.TemporaryDirectory(prefix="deformx-cycles-")

    def _mujoco_geoms(self, sim) -> list:
        """One object per visible MuJoCo geom (groups 0-2, not transparent), an instance id per
        body with geoms (as the fast renderer numbers them), posed each frame."""
        import trimesh

        m = sim.backend.model
        out = []
        for b in range(m.nbody):
            geoms = np.flatnonzero(m.geom_bodyid == b)
            if not len(geoms):
                continue
            pass_index = len(self.ids) + 1
            self.ids.append({"id": pass_index, "kind": "body", "name": m.body(b).name or "world"})
            for g in geoms:
                if m.geom_group[g] > 2 or m.geom_rgba[g, 3] == 0.0:
                    continue
                t, size = int(m.geom_type[g]), m.geom_size[g]
                if t == 0:  # plane
                    V = np.array([[-10, -10, 0], [10, -10, 0], [10, 10, 0], [-10, 10, 0.0]])
                    F = np.array([[0, 1, 2], [0, 2, 3]])
                elif t == 2:
                    tm = trimesh.creation.icosphere(subdivisions=3, radius=size[0])
                elif t == 3:
                    tm = trimesh.creation.capsule(height=2 * size[1], radius=size[0],
                                                  count=[24, 24])
                elif t == 4:
                    tm = trimesh.creation.icosphere(subdivisions=3)
                    tm.vertices *= size
                elif t == 5:
                    tm = trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=32)
                elif t == 6:
                    tm = trimesh.creation.box(extents=2 * size)
                elif t == 7:
                    k = int(m.geom_dataid[g])
                    v0, nv = m.mesh_vertadr[k], m.mesh_vertnum[k]
                    f0, nf = m.mesh_faceadr[k], m.mesh_facenum[k]
                    tm = trimesh.Trimesh(m.mesh_vert[v0:v0 + nv], m.mesh_face[f0:f0 + nf],
                                         process=False)
                else:
                    continue  # heightfields, SDFs: not drawn
                if t != 0:
                    V, F = np.asarray(tm.vertices), np.asarray(tm.faces)
                rgba = m.geom_rgba[g]
                if m.geom_matid[g] >= 0:
                    rgba = m.mat_rgba[m.geom_matid[g]]
                obj = self._mesh_object(f"geom_{g}", V, F, _material(
                    self.bpy, f"geom_{g}", tuple(float(c) for c in rgba[:3]), 0.5,
                    checker=t == 0), smooth=t in (2, 3, 4, 5))
                obj.pass_index = pass_index
                out.append((obj, int(g)))
        return out

    # ------------------------------------------------------------------ building
    def _add_id(self, obj, kind: str, name: str) -> None:
        obj.pass_index = len(self.ids) + 1
        self.ids.append({"id": len(self.ids) + 1, "kind": kind, "name": name})

    @staticmethod
    def _matrix(R: np.ndarray, p: np.ndarray):
        from mathutils import Matrix

        M = np.eye(4)
        M[:3, :3], M[:3, 3] = R, p
        return Matrix(M.tolist())

    def _mesh_object(self, name: str, V: np.ndarray, F: np.ndarray, material,
                     smooth: bool = True):
        bpy = self.bpy
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(np.asarray(V, dtype=float).tolist(), [],
                         np.asarray(F, dtype=int).tolist())
        mesh.update()
        if smooth:
            mesh.shade_smooth()
        mesh.materials.append(material)
        obj = bpy.data.objects.new(name, mesh)
        self.scene.collection.objects.link(obj)
        return obj

    # ------------------------------------------------------------------ per frame
    def _sync(self) -> None:
        for m, data in zip(self.meshes, self._rod_data):
            m.update()
            data.vertices.foreach_set("co", m.vertices.astype(np.float32).ravel())
            data.update()
        for obj, c in self._collider_objs:
            obj.matrix_world = self._matrix(c.rotation, c.position)
        if self._geom_objs:
            import mujoco

            m, d = self.sim.backend.model, self.sim.backend.data
            mujoco.mj_kinematics(m, d)  # after mj_step the poses are one step stale
            for obj, g in self._geom_objs:
                obj.matrix_world = self._matrix(d.geom_xmat[g].reshape(3, 3), d.geom_xpos[g])

    def _set_camera(self, camera: Camera) -> None:
        s, cam = self.scene, self.camera_obj.data
        s.render.resolution_x, s.render.resolution_y = camera.width, camera.height
        cam.sensor_fit = "VERTICAL"
        cam.angle_y = math.radians(camera.fov_y)
        cam.clip_start, cam.clip_end = camera.near, camera.far
        self.camera_obj.matrix_world = self._matrix(camera.gl_rotation(), camera.position)

    def _render_exr(self, samples: int | None = None) -> dict[str, np.ndarray]:
        import OpenEXR

        s = self.scene
        keep = s.cycles.samples, s.cycles.use_denoising
        if samples is not None:
            s.cycles.samples, s.cycles.use_denoising = samples, False
        settings = s.render.image_settings
        settings.media_type = "MULTI_LAYER_IMAGE"
        settings.color_depth = "32"
        path = os.path.join(self._tmp.name, "frame.exr")
        s.render.filepath = path
        try:
            with _Quiet():
                self.bpy.ops.render.render(write_still=True)
        finally:
            s.cycles.samples, s.cycles.use_denoising = keep
        channels = {}
        with OpenEXR.File(path) as f:
            for part in f.parts:
                channels.update({k: np.array(v.pixels) for k, v in part.channels.items()})
        return channels

    def _save_rgb(self) -> np.ndarray:
        import imageio.v3 as iio

        settings = self.scene.render.image_settings
        settings.media_type = "IMAGE"
        settings.file_format = "PNG"
        settings.color_mode = "RGB"
        settings.color_depth = "8"
        path = os.path.join(self._tmp.name, "rgb.png")
        with _Quiet():
            self.bpy.data.images["Render Result"].save_render(filepath=path)
        return np.asarray(iio.imread(path))[..., :3]

    def render(self, camera: Camera, amodal: bool = False) -> Frame:
        """RGB (colour-managed, "Standard" view transform), z-depth, instance ids, keypoints
        (and amodal masks) seen by ``camera``."""
        if not isinstance(camera, Camera):
            raise ValueError(f"camera must be a deformx.visual.Camera, got {type(camera).__name__}")
        self._sync()
        self._set_camera(camera)
        ch = self._render_exr()
        rgb = self._save_rgb()
        depth = ch["ViewLayer.Depth.Z"].astype(np.float32)
        depth[depth >= _BACKGROUND_DEPTH] = np.inf
        index = np.rint(ch["ViewLayer.Object Index.X"]).astype(np.uint16)
        frame = Frame(rgb=rgb, depth=depth, instances=index, ids=list(self.ids), camera=camera)
        frame.add_keypoints(self.world.rods)
        if amodal:
            frame.amodal = self._amodal()
        return frame

    def _amodal(self) -> dict[int, np.ndarray]:
        """Each rod alone (every other object hidden), one sample: its object-index mask."""
        objs = [o for o in self.scene.objects if o.type == "MESH"]
        out = {}
        try:
            for i in range(len(self.meshes)):
                for o in objs:
                    o.hide_render = o.name != f"rod_{i}"
                ch = self._render_exr(samples=1)
                out[i + 1] = np.rint(ch["ViewLayer.Object Index.X"]) == i + 1
        finally:
            for o in objs:
                o.hide_render = False
        return out

    def save_blend(self, path: str | Path) -> Path:
        """Save the scene as a .blend file (the current frame) to open in Blender."""
        path = Path(path).resolve()
        path.parent.mkdir(parents=True, exist_ok=True)
        self._sync()
        with _Quiet():
            self.bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
        return path
