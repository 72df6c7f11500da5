"""The fast renderer: MuJoCo's OpenGL renderer (EGL, or OSMesa where there is no GPU driver).

A render model is built once from a world (or a co-simulation: the MuJoCo model's own bodies
plus the rods): one tube mesh per rod, the world's colliders as mocap bodies, its planes, a
light with shadows and a camera. Each :meth:`FastRenderer.render` refreshes the tube vertices
(numba kernel, then ``mjr_uploadMesh``), the colliders' poses (and the co-simulation's joint
state), and draws two passes: RGB with multisampling and shadows, then one pass without
antialiasing for depth and instance ids, so no id is blended at an edge. MuJoCo stores mesh
vertices in the mesh's inertial frame (recentred and rotated at compile time): uploads use it.
"""

from __future__ import annotations

import ctypes.util
import os
from typing import Any

import numpy as np

if not os.environ.get("MUJOCO_GL"):  # headless: EGL where its library is, else OSMesa
    os.environ["MUJOCO_GL"] = "egl" if ctypes.util.find_library("EGL") else "osmesa"

import mujoco  # noqa: E402

from .camera import Camera  # noqa: E402
from .frame import Frame  # noqa: E402
from .materials import Material, texture_image  # noqa: E402
from .tube import Tube  # noqa: E402


def _gl_context_class():
    """The OpenGL context class for MUJOCO_GL (egl, osmesa or glfw), whatever mujoco chose
    when it was first imported (possibly before this module set MUJOCO_GL)."""
    choice = os.environ.get("MUJOCO_GL", "").lower()
    try:
        if choice == "egl":
            from mujoco.egl import GLContext
        elif choice == "osmesa":
            from mujoco.osmesa import GLContext
        else:
            from mujoco.glfw import GLContext
    except Exception as err:  # a missing system library, or PyOpenGL bound to another one
        raise RuntimeError(
            f"FastRenderer: no OpenGL context for MUJOCO_GL={choice!r} ({err}). Install the "
            "system package libegl1 (EGL) or libosmesa6 (OSMesa, with MUJOCO_GL=osmesa), and "
            "set MUJOCO_GL before anything imports OpenGL") from err
    return GLContext

#: Collider colours in order (RGB 0-1): wood, porcelain, blue, slate.
COLLIDER_COLORS = ((0.55, 0.40, 0.26), (0.90, 0.89, 0.86), (0.22, 0.45, 0.78),
                   (0.45, 0.47, 0.50))

#: Wire colours (RGB 0-1), the authors' twelve-colour palette in spirit.
PALETTE = ((0.85, 0.16, 0.14), (0.12, 0.47, 0.80), (0.98, 0.75, 0.10), (0.16, 0.62, 0.30),
           (0.95, 0.45, 0.10), (0.55, 0.27, 0.68), (0.10, 0.10, 0.10), (0.92, 0.92, 0.90),
           (0.40, 0.26, 0.13), (0.95, 0.55, 0.70), (0.20, 0.75, 0.78), (0.55, 0.55, 0.57))


def _quat(R: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=np.float64).ravel())
    return q


def world_and_sim(source: Any) -> tuple[Any, Any]:
    """``(world, co_simulation or None)`` of what a renderer is given."""
    from ..engine.world import World

    if isinstance(source, World):
        return source, None
    if hasattr(source, "world") and hasattr(source, "backend"):
        return source.world, source
    raise ValueError(f"source must be a deformx.World or a CoSimulation, got "
                     f"{type(source).__name__}")


def drawn_by_bodies(sim) -> tuple[set, set]:
    """Colliders (by id) and plane indices that stand for a co-simulation's MuJoCo geoms:
    renderers draw those geoms instead."""
    colliders, planes = set(), set()
    if sim is not None:
        for bc in sim.bodies.values():
            colliders.update(id(c) for c in bc.colliders)
            planes.update(bc.planes)
    return colliders, planes


class _Pass:
    """An OpenGL context and MuJoCo render context of a given size and multisampling."""

    def __init__(self, model, width: int, height: int, samples: int) -> None:
        model.vis.global_.offwidth = max(width, model.vis.global_.offwidth)
        model.vis.global_.offheight = max(height, model.vis.global_.offheight)
        keep = model.vis.quality.offsamples
        model.vis.quality.offsamples = samples
        self.gl = _gl_context_class()(width, height)
        self.gl.make_current()
        self.ctx = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self.ctx)
        self.ctx.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        model.vis.quality.offsamples = keep
        self.rect = mujoco.MjrRect(0, 0, width, height)
        self.size = (width, height)

    def draw(self, scene, rgb: np.ndarray | None, depth: np.ndarray | None) -> None:
        self.gl.make_current()
        mujoco.mjr_render(self.rect, scene, self.ctx)
        mujoco.mjr_readPixels(rgb, depth, self.rect, self.ctx)

    def upload(self, model, mesh_id: int) -> None:
        self.gl.make_current()
        mujoco.mjr_uploadMesh(model, self.ctx, mesh_id)

    def close(self) -> None:
        self.ctx.free()
        self.gl.free()


class FastRenderer:
    """Renders a :class:`deformx.World` or a :class:`deformx.cosim.CoSimulation`.

    ``sides``: vertices around each tube; ``shadows`` and ``shadow_size`` (shadow map, pixels:
    MuJoCo's default 4096 costs ~0.25 s a frame on a CPU); ``colors``: one RGB per rod
    (default :data:`PALETTE`); ``samples``: multisampling of the RGB pass; ``skins``: rod
    index -> :class:`~deformx.visual.skin.Skin` (e.g. ``assets.usb_c_cable(...).skin(rod)``)
    drawn instead of that rod's tube, one material per part of a cable asset; ``materials``:
    rod index -> :class:`~deformx.visual.materials.Material` (colour, roughness, texture),
    overriding ``colors``.
    """

    def __init__(self, source: Any, sides: int = 12, shadows: bool = True,
                 shadow_size: int = 1024, colors: Any = None, samples: int = 4,
                 skins: dict | None = None, materials: Any = None) -> None:
        world, sim = world_and_sim(source)
        self.world, self.sim = world, sim
        self.samples = int(samples)
        spec = self._base_spec(sim)
        spec.visual.quality.shadowsize = int(shadow_size) if shadows else 0
        spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
        spec.visual.headlight.diffuse = [0.3, 0.3, 0.3]
        spec.stat.extent = 1.0  # near and far are set from the camera, in metres
        spec.stat.center = [0.0, 0.0, 0.0]
        spec.worldbody.add_light(name="deformx_key", type=mujoco.mjtLightType.mjLIGHT_SPOT,
                                 pos=[0.6, -0.4, 3.0], dir=[-0.2, 0.13, -1.0], cutoff=45.0,
                                 exponent=1.0, diffuse=[0.8, 0.8, 0.8], specular=[0.2, 0.2, 0.2],
                                 castshadow=bool(shadows))
        spec.add_texture(name="deformx_grid", type=mujoco.mjtTexture.mjTEXTURE_2D,
                         builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, width=256, height=256,
                         rgb1=[0.92, 0.92, 0.90], rgb2=[0.80, 0.80, 0.78])
        # checker squares of 10 cm (texrepeat per metre with texuniform)
        spec.add_material(name="deformx_ground", texrepeat=[5, 5], texuniform=True,
                          textures=["", "deformx_grid"])
        spec.worldbody.add_camera(name="deformx_camera", pos=[0, 0, 1])
        ids: list[dict] = []
        # rods first: instance ids 1..n in world order
        skins = skins or {}
        self.tubes = [skins[i] if i in skins else Tube(rod, sides=sides)
                      for i, rod in enumerate(world.rods)]
        self.materials = rod_materials(len(self.tubes), colors, materials)
        self._rod_geoms: list[list[str]] = []  # per rod: its geoms (one per part)
        parts: list[tuple] = []  # (drawable, geom name, vertex subset or None)
        for i, tube in enumerate(self.tubes):
            names = []
            for k, (mat, faces, subset) in enumerate(_mesh_parts(tube, self.materials[i])):
                name = f"deformx_rod{i}" + (f"_{k}" if k else "")
                V = tube.vertices if subset is None else tube.vertices[subset]
                N = tube.normals if subset is None else tube.normals[subset]
                mesh = dict(name=name, uservert=V.ravel().tolist(),
                            userface=faces.ravel().tolist(), usernormal=N.ravel().tolist())
                texture = texture_image(mat) if isinstance(tube, Tube) else None
                if texture is not None:
                    uv = tube.uv / np.array([mat.texture_scale, 1.0])
                    mesh["usertexcoord"] = uv.ravel().tolist()
                spec.add_mesh(**mesh)
                _add_material(spec, name, mat, texture)
                spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH,
                                        meshname=name, material=name, contype=0,
                                        conaffinity=0)
                names.append(name)
                parts.append((tube, name, subset))
            self._rod_geoms.append(names)
            ids.append({"id": len(ids) + 1, "kind": "rod", "name": f"rod {i}"})
        # colliders standing for co-simulated bodies are drawn by MuJoCo's own geoms
        from_bodies, body_planes = drawn_by_bodies(sim)
        self._planes = [k for k in range(len(world.planes)) if k not in body_planes]
        self._colliders = [c for c in world.colliders if id(c) not in from_bodies]
        for k, c in enumerate(self._colliders):
            body = spec.worldbody.add_body(name=f"deformx_collider{k}", mocap=True)
            kw = dict(name=f"deformx_collider{k}", contype=0, conaffinity=0,
                      rgba=[*COLLIDER_COLORS[k % len(COLLIDER_COLORS)], 1.0])
            size = c.size
            if c.kind == "sphere":
                body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[size[0], 0, 0], **kw)
            elif c.kind == "box":
                body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=list(size), **kw)
            elif c.kind in ("capsule", "cylinder"):
                t = mujoco.mjtGeom.mjGEOM_CAPSULE if c.kind == "capsule" else \
                    mujoco.mjtGeom.mjGEOM_CYLINDER
                body.add_geom(type=t, size=[size[0], size[1], 0], **kw)
            else:
                spec.add_mesh(name=f"deformx_collider{k}", uservert=c.vertices.ravel().tolist(),
                              userface=c.faces.ravel().tolist())
                body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"deformx_collider{k}",
                              **kw)
            ids.append({"id": len(ids) + 1, "kind": "collider", "name": f"collider {c.index} "
                        f"({c.kind})"})
        for k in self._planes:
            p, n = world.planes[k]
            spec.worldbody.add_geom(name=f"deformx_plane{k}", type=mujoco.mjtGeom.mjGEOM_PLANE,
                                    size=[100.0, 100.0, 0.1], pos=list(p), quat=list(
                                        _quat(_frame_z(n))), material="deformx_ground",
                                    contype=0, conaffinity=0)
            ids.append({"id": len(ids) + 1, "kind": "plane", "name": f"plane {k}"})
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self._geom_instance = self._instances(ids, sim)
        self.ids = ids
        self._rod_mesh = [(tube, self.model.mesh(name).id, subset)
                          for tube, name, subset in parts]
        self._mocap = [self.model.body(f"deformx_collider{k}").mocapid[0]
                       for k in range(len(self._colliders))]
        self._camera_id = self.model.camera("deformx_camera").id
        self.scene = mujoco.MjvScene(self.model, maxgeom=10000)
        self.option = mujoco.MjvOption()
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._cam.fixedcamid = self._camera_id
        self._passes: dict[str, _Pass] = {}

    # ------------------------------------------------------------------ building
    @staticmethod
    def _base_spec(sim) -> "mujoco.MjSpec":
        if sim is None:
            return mujoco.MjSpec()
        source = getattr(sim.backend, "source", None)
        if source is None:
            raise ValueError("FastRenderer: the co-simulation's backend must have been made "
                             "from an MJCF string or file (MujocoBackend(xml or path))")
        if isinstance(source, str) and source.lstrip().startswith("<"):
            return mujoco.MjSpec.from_string(source)
        return mujoco.MjSpec.from_file(os.fspath(source))

    def _instances(self, ids: list[dict], sim) -> np.ndarray:
        """Instance id of every geom of the render model (0: not an instance)."""
        m = self.model
        out = np.zeros(m.ngeom, dtype=np.uint16)
        for i, names in enumerate(self._rod_geoms):
            for name in names:
                out[m.geom(name).id] = i + 1
        n_rods = len(self.tubes)
        k = n_rods
        for j in range(len(self._colliders)):
            out[m.geom(f"deformx_collider{j}").id] = k + 1 + j
        k += len(self._colliders)
        for j, plane in enumerate(self._planes):
            out[m.geom(f"deformx_plane{plane}").id] = k + 1 + j
        if sim is not None:  # one id per MuJoCo body with visible geoms ("world": static ones)
            nxt = len(ids) + 1
            for b in range(m.nbody):
                geoms = [g for g in np.flatnonzero(m.geom_bodyid == b)
                         if not m.geom(g).name.startswith("deformx_")]
                if not geoms:
                    continue
                name = m.body(b).name or "world"
                ids.append({"id": nxt, "kind": "body", "name": name})
                out[geoms] = nxt
                nxt += 1
        return out

    # ------------------------------------------------------------------ per frame
    def _sync(self) -> None:
        m, d = self.model, self.data
        if self.sim is not None:
            src = self.sim.backend.data
            d.qpos[: src.qpos.shape[0]] = src.qpos
            if src.mocap_pos.shape[0]:
                d.mocap_pos[: src.mocap_pos.shape[0]] = src.mocap_pos
                d.mocap_quat[: src.mocap_quat.shape[0]] = src.mocap_quat
        for k, c in zip(self._mocap, self._colliders):
            d.mocap_pos[k] = c.position
            d.mocap_quat[k] = _quat(c.rotation)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_camlight(m, d)  # light positions (the camera is set afterwards)
        self._upload_tubes(None)

    def _upload_tubes(self, camera: Camera | None) -> None:
        """Tube vertices into the render model and every context; with ``camera``, for the
        id pass only: wires thinner than 1.5 px are drawn 1.5 px wide, so that a wire down to
        a pixel still gets a mask (depth there is off by less than a pixel's footprint)."""
        m = self.model
        updated = set()
        for tube, mid, subset in self._rod_mesh:
            radius = None
            if camera is not None and not isinstance(tube, Tube):
                continue  # skinned meshes are drawn as they are
            if camera is not None:
                z = np.maximum(camera.to_camera(tube.rod.positions)[:, 2], 0.0)
                floor = 0.75 * z / camera.focal
                if np.all(tube.radius >= floor):
                    continue
                radius = np.maximum(tube.radius, floor)
            if id(tube) not in updated:  # a skin's parts share one update
                tube.update() if radius is None else tube.update(radius)
                updated.add(id(tube))
            V = tube.vertices if subset is None else tube.vertices[subset]
            N = tube.normals if subset is None else tube.normals[subset]
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, m.mesh_quat[mid])
            R = R.reshape(3, 3)
            v0, nv = m.mesh_vertadr[mid], m.mesh_vertnum[mid]
            m.mesh_vert[v0:v0 + nv] = (V - m.mesh_pos[mid]) @ R
            n0 = m.mesh_normaladr[mid]
            m.mesh_normal[n0:n0 + nv] = N @ R
            for kind, p in self._passes.items():
                if camera is None or kind == "ids":
                    p.upload(m, mid)

    def _pass(self, kind: str, camera: Camera) -> _Pass:
        p = self._passes.get(kind)
        if p is None or p.size != (camera.width, camera.height):
            if p is not None:
                p.close()
            p = _Pass(self.model, camera.width, camera.height,
                      self.samples if kind == "rgb" else 0)
            self._passes[kind] = p
            for _, mid, _ in self._rod_mesh:
                p.upload(self.model, mid)
        return p

    def _update_scene(self, camera: Camera) -> None:
        m, d = self.model, self.data
        m.vis.map.znear = camera.near / m.stat.extent
        m.vis.map.zfar = camera.far / m.stat.extent
        m.cam_fovy[self._camera_id] = camera.fov_y
        d.cam_xpos[self._camera_id] = camera.position
        d.cam_xmat[self._camera_id] = camera.gl_rotation().ravel()
        mujoco.mjv_updateScene(m, d, self.option, None, self._cam, mujoco.mjtCatBit.mjCAT_ALL,
                               self.scene)

    def _id_pass(self, camera: Camera, want_depth: bool = True):
        """Instance ids (H, W) and metric z-depth (H, W) from a pass without antialiasing."""
        W, H = camera.width, camera.height
        p = self._pass("ids", camera)
        flags = self.scene.flags
        flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = 1
        flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = 1
        seg = np.empty((H, W, 3), dtype=np.uint8)
        z = np.empty((H, W), dtype=np.float32) if want_depth else None
        try:
            p.draw(self.scene, seg, z)
        finally:
            flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = 0
            flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = 0
        segid = (seg[..., 0].astype(np.int64) + (seg[..., 1].astype(np.int64) << 8)
                 + (seg[..., 2].astype(np.int64) << 16))[::-1]
        n = self.scene.ngeom
        lut = np.zeros(n + 1, dtype=np.uint16)
        for k in range(n):
            g = self.scene.geoms[k]
            if g.objtype == mujoco.mjtObj.mjOBJ_GEOM and 0 <= g.objid < self.model.ngeom:
                lut[k + 1] = self._geom_instance[g.objid]
        instances = lut[np.clip(segid, 0, n)]
        depth = None
        if want_depth:
            near, far = np.float32(camera.near), np.float32(camera.far)
            c = -(far + near) / (far - near)
            dd = -(np.float32(2) * far * near) / (far - near)
            c = np.float32(-0.5) * c - np.float32(0.5)
            dd = np.float32(-0.5) * dd
            depth = (dd / (z[::-1].astype(np.float64) + c)).astype(np.float32)
            depth[segid == 0] = np.inf
        return instances, depth

    def render(self, camera: Camera, amodal: bool = False) -> Frame:
        """RGB, depth, instance ids, rod keypoints (and, with ``amodal``, each rod's full
        silhouette) seen by ``camera`` now."""
        if not isinstance(camera, Camera):
            raise ValueError(f"camera must be a deformx.visual.Camera, got {type(camera).__name__}")
        W, H = camera.width, camera.height
        self._pass("rgb", camera)
        self._pass("ids", camera)
        self._sync()
        self._update_scene(camera)
        rgb = np.empty((H, W, 3), dtype=np.uint8)
        self._passes["rgb"].draw(self.scene, rgb, None)
        rgb = rgb[::-1].copy()
        self._upload_tubes(camera)  # sub-pixel wires widened for the id pass only
        instances, depth = self._id_pass(camera)
        frame = Frame(rgb=rgb, depth=depth, instances=instances, ids=list(self.ids),
                      camera=camera)
        frame.add_keypoints(self.world.rods)
        if amodal:
            frame.amodal = self._amodal(camera)
        return frame

    def _amodal(self, camera: Camera) -> dict[int, np.ndarray]:
        """Each rod drawn alone: every other geom made fully transparent, which MuJoCo leaves
        out of the scene."""
        rgba = self.model.geom_rgba
        keep = rgba[:, 3].copy()
        out = {}
        try:
            for i, names in enumerate(self._rod_geoms):
                gids = [self.model.geom(name).id for name in names]
                rgba[:, 3] = 0.0
                rgba[gids, 3] = keep[gids]
                self._update_scene(camera)
                ids, _ = self._id_pass(camera, want_depth=False)
                out[i + 1] = ids == i + 1
        finally:
            rgba[:, 3] = keep
            self._update_scene(camera)
        return out

    def close(self) -> None:
        """Free the OpenGL contexts."""
        for p in self._passes.values():
            p.close()
        self._passes.clear()

    def __del__(self) -> None:  # pragma: no cover - best effort
        try:
            self.close()
        except Exception:
            pass


def rod_materials(n: int, colors: Any = None, materials: Any = None) -> list[Material]:
    """One :class:`Material` per rod: ``materials`` (rod index -> Material, or a list) where
    given, else the rod's colour from ``colors`` (default :data:`PALETTE`)."""
    palette = PALETTE if colors is None else [tuple(c) for c in colors]
    if materials is None:
        materials = {}
    elif not isinstance(materials, dict):
        materials = dict(enumerate(materials))
    out = []
    for i in range(n):
        m = materials.get(i)
        if m is not None and not isinstance(m, Material):
            raise ValueError(f"materials[{i}] must be a deformx.visual.materials.Material, got "
                             f"{type(m).__name__}")
        out.append(m if m is not None else Material(tuple(palette[i % len(palette)])))
    return out


def _mesh_parts(drawable, material: Material) -> list[tuple]:
    """(material, faces, vertex subset or None) per part: a cable asset's skin has one per
    material (jacket, plug, ...), everything else one."""
    parts = getattr(drawable, "materials", None)
    part = getattr(drawable, "part", None)
    if not parts or part is None:
        return [(material, drawable.faces, None)]
    out = []
    for k, mat in enumerate(parts):
        F = drawable.faces[np.asarray(part) == k]
        if not len(F):
            continue
        subset, local = np.unique(F, return_inverse=True)
        out.append((mat, local.reshape(F.shape), subset))
    return out


def _add_material(spec, name: str, material: Material, texture: np.ndarray | None) -> None:
    """A MuJoCo material for ``material``: Phong specular and shininess from roughness."""
    kw = dict(name=name, rgba=[*material.color, 1.0],
              specular=0.5 * (1.0 - material.roughness) + 0.3 * material.metallic,
              shininess=1.0 - material.roughness, reflectance=0.0)
    if texture is not None:
        t = spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D,
                             width=texture.shape[1], height=texture.shape[0], nchannel=3)
        t.data = np.ascontiguousarray(texture).tobytes()
        kw.update(textures=["", name], rgba=[1.0, 1.0, 1.0, 1.0])
    spec.add_material(**kw)


def _frame_z(normal: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is ``normal``."""
    z = np.asarray(normal, dtype=np.float64)
    z = z / np.linalg.norm(z)
    a = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])
