"""Colliders: triangle meshes and analytic primitives the rods touch, and their packed tables.

A :class:`Collider` is a handle returned by ``World.add_mesh`` / ``add_sphere`` / ``add_box`` /
``add_capsule`` / ``add_cylinder``. Its pose and velocity may change between steps (co-simulation
drives them); after each step it holds the reaction wrench the rods put on it. Mesh geometry and
its BVH are built once, in the mesh's local frame.
"""

from __future__ import annotations

import os
from typing import Any, Sequence

import numpy as np

from .. import validation as check
from ..drivers import Driver, pose_from, put3, rotation, vec3
from ..geometry.bvh import bvh_from_mesh, pseudonormals
from ..kernels.bundles import D_P, D_V, D_W
from ..packing import Packed
from ..geometry.faces import face_frames
from .primitives import BOX, CAPSULE, CYLINDER, SPHERE
from .segments import (
    MESH,
    N_PAR,
    P_AUTO,
    P_C,
    P_K,
    P_MUK,
    P_MUS,
    P_REPULSION,
    P_SHAPE,
    P_TWO_SIDED,
)

KINDS = {"mesh": MESH, "sphere": SPHERE, "box": BOX, "capsule": CAPSULE, "cylinder": CYLINDER}


MESH_FORMATS = (".obj", ".stl", ".ply", ".glb", ".gltf", ".off")


def load_mesh(mesh: Any) -> tuple[np.ndarray, np.ndarray, bool]:
    """Vertices (V, 3) m, faces (F, 3) and watertightness of a mesh given as a file path
    (OBJ/STL/PLY/GLB/glTF/OFF), a ``trimesh.Trimesh`` or a ``(vertices, faces)`` pair.

    A file that cannot be read, holds no triangles, has faces pointing at missing vertices or
    non-finite vertices gives a ``ValueError`` naming the file and the problem (trimesh alone
    would drop such vertices and faces without a word, or raise from deep inside).
    """
    import trimesh  # only needed here; the kernels take plain arrays

    what = "mesh"
    if isinstance(mesh, (str, os.PathLike)):
        path = os.fspath(mesh)
        what = f"mesh file {path!r}"
        if not os.path.exists(path):
            raise ValueError(f"mesh: file not found: {path!r}")
        ext = os.path.splitext(path)[1].lower()
        if ext not in MESH_FORMATS:
            raise ValueError(f"{what}: unsupported format {ext or '(no extension)'!r}; "
                             f"valid: {', '.join(MESH_FORMATS)}")
        if ext == ".obj":
            _check_obj(path, what)
        try:
            # process=False keeps what the file says (trimesh would merge and drop vertices).
            mesh = trimesh.load(path, force="mesh", process=False)
        except Exception as err:  # any reader failure: malformed, truncated, wrong format
            raise ValueError(f"{what}: cannot be read as {ext[1:].upper()} "
                             f"({type(err).__name__}: {err})") from None
        if not isinstance(mesh, trimesh.Trimesh):
            raise ValueError(f"{what}: holds no triangle mesh (got {type(mesh).__name__})")
    if isinstance(mesh, trimesh.Trimesh):
        V, F = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    elif isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        V = np.asarray(mesh[0], dtype=np.float64)
        F = np.asarray(mesh[1])
        if V.ndim != 2 or V.shape[1] != 3 or F.ndim != 2 or F.shape[1] != 3:
            raise ValueError("mesh: (vertices, faces) must have shapes (V, 3) and (F, 3), got "
                             f"{V.shape} and {F.shape}")
        if F.size and not np.issubdtype(F.dtype, np.integer):
            raise ValueError(f"mesh: faces must be integer vertex indices, got {F.dtype}")
    else:
        raise ValueError("mesh must be a file path, a trimesh.Trimesh or a (vertices, faces) "
                         f"pair, got {type(mesh).__name__}")
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if F.shape[0] == 0:
        raise ValueError(f"{what}: has no triangles (empty, truncated or not a mesh file?)")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise ValueError(f"{what}: {int(bad.sum())} vertices are NaN or infinite (first: "
                         f"vertex {int(np.argmax(bad))})")
    if F.min() < 0 or F.max() >= V.shape[0]:
        raise ValueError(f"{what}: face indices must lie in [0, {V.shape[0] - 1}], got "
                         f"[{int(F.min())}, {int(F.max())}]")
    if what != "mesh":  # a file: merge duplicate vertices as trimesh.load does by default
        tm = trimesh.Trimesh(V, F)
        V = np.ascontiguousarray(tm.vertices, dtype=np.float64)
        F = np.ascontiguousarray(tm.faces, dtype=np.int64)
    else:
        tm = mesh if isinstance(mesh, trimesh.Trimesh) else trimesh.Trimesh(V, F, process=False)
    return V, F, bool(tm.is_watertight)


def _check_obj(path: str, what: str) -> None:
    """Vertex and face records of an OBJ file: numbers that parse and are finite, face
    indices (1-based or negative) that name existing vertices."""
    n_vertices = 0
    with open(path, "rb") as fh:
        for line_no, raw in enumerate(fh, 1):
            parts = raw.split()
            if not parts:
                continue
            if parts[0] == b"v":
                try:
                    xyz = [float(x) for x in parts[1:4]]
                except ValueError:
                    raise ValueError(f"{what}: line {line_no}: vertex is not three numbers: "
                                     f"{raw.strip()[:60]!r}") from None
                if len(xyz) < 3 or not all(np.isfinite(xyz)):
                    raise ValueError(f"{what}: line {line_no}: vertex must be three finite "
                                     f"numbers, got {raw.strip()[:60]!r}")
                n_vertices += 1
            elif parts[0] == b"f":
                for token in parts[1:]:
                    try:
                        k = int(token.split(b"/")[0])
                    except ValueError:
                        raise ValueError(f"{what}: line {line_no}: bad face index "
                                         f"{token[:20]!r}") from None
                    if k == 0 or k > n_vertices or k < -n_vertices:
                        raise ValueError(f"{what}: line {line_no}: face index {k} names no "
                                         f"vertex ({n_vertices} defined before it)")


def pose_matrix(pose: Any, name: str = "pose") -> np.ndarray:
    """A 4x4 world-from-local rigid transform from None (identity), a 4x4 matrix, a
    ``(position, rotation 3x3)`` pair or a position 3-vector."""
    if pose is None:
        return np.eye(4)
    if isinstance(pose, (tuple, list)) and len(pose) == 2:
        T = np.eye(4)
        T[:3, 3] = check.vector3(f"{name} position", pose[0])
        T[:3, :3] = rotation(f"{name} rotation", pose[1])
        return T
    arr = np.asarray(pose, dtype=np.float64)
    if arr.shape == (3,):
        T = np.eye(4)
        T[:3, 3] = check.vector3(name, arr)
        return T
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a finite 4x4 matrix, a (position, rotation) pair or a "
                         f"position, got shape {arr.shape}")
    T = arr.copy()
    T[:3, :3] = rotation(f"{name} rotation", arr[:3, :3])
    T[3] = (0.0, 0.0, 0.0, 1.0)
    return T


class Collider(Driver):
    """A mesh or primitive in the world, moved by its kinematic driver: ``pose`` (4x4, world
    from local), velocity and acceleration may be set between steps and are integrated inside
    ``step(n)`` (see :mod:`deformx.engine.drivers`); ``force`` (N) and ``torque`` (N m, about
    the collider's origin), world frame, are the rods' load on it during the last step."""

    def __init__(self, index: int, kind: str, pose: np.ndarray, params: np.ndarray,
                 mesh: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        super().__init__()
        self.index = index
        self.kind = kind
        self._own[D_P:D_P + 3] = pose[:3, 3]
        self._set_rotation(pose[:3, :3])
        self._params = params
        self._mesh = mesh

    @property
    def pose(self) -> np.ndarray:
        """World-from-local transform (4x4) now; assign a new one to move the collider."""
        T = np.eye(4)
        T[:3, :3] = self.rotation
        T[:3, 3] = self.position
        return T

    @pose.setter
    def pose(self, value: Any) -> None:
        T = pose_matrix(value)
        self._row[D_P:D_P + 3] = T[:3, 3]
        self._set_rotation(T[:3, :3])

    def set_pose(self, position: Sequence[float] | None = None,
                 rotation: np.ndarray | None = None) -> None:
        """Move the collider now: ``position`` (m) of its origin and/or ``rotation`` (3x3,
        world from local)."""
        p, R = pose_from(position, rotation)
        if p is not None:
            put3(self._row, D_P, p)
        if R is not None:
            self._set_rotation(R)

    def set_velocity(self, linear: Sequence[float] | None = (0.0, 0.0, 0.0),
                     angular: Sequence[float] | None = (0.0, 0.0, 0.0), *,
                     velocity: Sequence[float] | None = None,
                     angular_velocity: Sequence[float] | None = None) -> None:
        """Velocity of the collider's origin (m/s) and angular velocity (rad/s), world frame,
        from now on (``velocity`` / ``angular_velocity`` are the same as for clamps)."""
        linear = linear if velocity is None else velocity
        angular = angular if angular_velocity is None else angular_velocity
        row = self._row
        if linear is not None:
            put3(row, D_V, vec3("linear", linear))
        if angular is not None:
            put3(row, D_W, vec3("angular", angular))

    @property
    def vertices(self) -> np.ndarray | None:
        """Mesh vertices in the local frame (m); None for a primitive."""
        return None if self._mesh is None else self._mesh[0]

    @property
    def faces(self) -> np.ndarray | None:
        return None if self._mesh is None else self._mesh[1]

    @property
    def size(self) -> np.ndarray:
        """Shape sizes (m): sphere (radius,), box half extents (3), capsule and cylinder
        (radius, half length along local z); empty for a mesh."""
        n = {"sphere": 1, "box": 3, "capsule": 2, "cylinder": 2}.get(self.kind, 0)
        return self._params[P_SHAPE:P_SHAPE + n].copy()

    def __repr__(self) -> str:
        extra = "" if self._mesh is None else f", {self._mesh[1].shape[0]} triangles"
        return f"Collider({self.kind}{extra}, position={self.position.round(4).tolist()})"


def contact_params(stiffness: float | None, damping: float | None, friction: float | None,
                   static_friction: float | None, kinetic_friction: float | None) -> np.ndarray:
    """The parameter row shared by all colliders (validated); shape columns left zero."""
    par = np.zeros(N_PAR)
    par[P_AUTO] = 1.0 if stiffness is None else 0.0
    par[P_K] = 0.0 if stiffness is None else check.positive("stiffness", stiffness, "N/m")
    par[P_C] = -1.0 if damping is None else check.non_negative("damping", damping, "N s/m")
    if friction is not None:
        mu = check.non_negative("friction", friction)
        mu_s = mu if static_friction is None else static_friction
        mu_k = mu if kinetic_friction is None else kinetic_friction
    else:
        mu_s = 0.5 if static_friction is None else static_friction
        mu_k = mu_s if kinetic_friction is None else kinetic_friction
    par[P_MUS] = check.non_negative("static_friction", mu_s)
    par[P_MUK] = check.non_negative("kinetic_friction", mu_k)
    if par[P_MUK] > par[P_MUS]:
        raise ValueError(f"kinetic_friction ({par[P_MUK]}) must be <= static_friction "
                         f"({par[P_MUS]})")
    return par


def mesh_params(par: np.ndarray, watertight: bool, two_sided: bool | None,
                repulsion_distance: float | None, size: float) -> np.ndarray:
    """Mesh columns: two-sided unless closed (or as asked); repulsion depth (m, default 10 %
    of the mesh's size)."""
    if two_sided is None:
        two_sided = not watertight
    elif not two_sided and not watertight:
        raise ValueError("two_sided=False needs a watertight (closed) mesh: an open mesh has "
                         "no inside")
    par[P_TWO_SIDED] = 1.0 if two_sided else 0.0
    par[P_REPULSION] = (0.1 * size if repulsion_distance is None else
                        check.non_negative("repulsion_distance", repulsion_distance, "m"))
    return par


def shape_params(par: np.ndarray, values: Sequence[float]) -> np.ndarray:
    par[P_SHAPE:P_SHAPE + len(values)] = values
    par[P_TWO_SIDED] = 0.0
    return par


def pack(colliders: Sequence[Collider], n_rods: int, n_nodes: int, n_slots: int,
         allowed: np.ndarray) -> Packed:
    """The kernels' collider tables (the ``cols`` group; see ``kernels/bundles.py``).

    Meshes are concatenated with global indices: collider c owns vertices, faces and BVH nodes
    ``rng[c, 0]:rng[c, 1]``, ``rng[c, 2]:rng[c, 3]`` and ``rng[c, 4]:rng[c, 5]`` (its root is
    node ``rng[c, 4]``), and its faces, child links, leaf slots and triangle ids point into
    the packed arrays. ``allowed`` (rods x colliders) says which rod may touch which."""
    C = len(colliders)
    rng = np.zeros((C, 6), dtype=np.int64)
    parts: dict[str, list] = {k: [] for k in ("MV", "MF", "Blo", "Bhi", "Bleft", "Bright",
                                              "Bstart", "Bcount", "Border", "Fn", "En", "Vn",
                                              "Fg")}
    nv = nf = nb = 0
    for i, c in enumerate(colliders):
        if c._mesh is None:
            rng[i] = (nv, nv, nf, nf, nb, nb)
            continue
        V, F = c._mesh
        bvh = c._bvh
        fn, en, vn = c._normals
        rng[i] = (nv, nv + V.shape[0], nf, nf + F.shape[0], nb, nb + bvh.lo.shape[0])
        # Indices become global (vertex, face and BVH node ids of the packed tables), so the
        # kernels index them without per-query views; the mesh's root is node nb.
        for key, arr in (("MV", V), ("MF", F + nv), ("Blo", bvh.lo), ("Bhi", bvh.hi),
                         ("Bleft", np.where(bvh.left >= 0, bvh.left + nb, -1)),
                         ("Bright", np.where(bvh.right >= 0, bvh.right + nb, -1)),
                         ("Bstart", bvh.start + nf), ("Bcount", bvh.count),
                         ("Border", bvh.order + nf), ("Fn", fn), ("En", en), ("Vn", vn),
                         ("Fg", c._frames)):
            parts[key].append(arr)
        nv += V.shape[0]
        nf += F.shape[0]
        nb += bvh.lo.shape[0]
    meshes = any(c._mesh is not None for c in colliders)
    b = Packed("cols", dict(C=C, R=n_rods, N=n_nodes, Q=n_slots, QM=n_slots if meshes else 0,
                            QA=n_slots if C else 0, nv=nv, nf=nf, nb=nb))
    b["kind"][:] = [KINDS[c.kind] for c in colliders]
    b["par"][:] = np.array([c._params for c in colliders]).reshape(C, N_PAR)
    b["rng"][:] = rng
    b["allowed"][:] = allowed
    for key, arrs in parts.items():
        if arrs:
            b[key][...] = np.concatenate(arrs)
    # Empty query caches (see ``segments._mesh_nearest``): no collider, no triangles, no
    # flat patch, no hints; no friction anchors.
    b["qc_meta"][:] = -1
    b["qc_meta"][:, 1] = 0
    b["anchor_id"][:] = -1
    return b


def prepare_mesh(collider: Collider) -> None:
    """Build the BVH, pseudonormals and face frames of a mesh collider (once)."""
    V, F = collider._mesh
    collider._bvh = bvh_from_mesh(V, F)
    collider._normals = pseudonormals(V, F)
    collider._frames = face_frames(V, F)
