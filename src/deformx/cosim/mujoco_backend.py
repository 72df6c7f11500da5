"""MuJoCo as the co-simulation's rigid-body side (robots, fixtures, free objects).

Facts this module relies on (checked with mujoco 4.0): ``mj_objectVelocity`` returns
(angular; linear) and, for ``mjOBJ_XBODY``, the linear part is the velocity of the body
frame's origin (``xpos``; ``mjOBJ_BODY`` would give the centre of mass's);
``mj_objectAcceleration`` needs ``mj_rnePostConstraint`` and returns the acceleration minus
gravity (+9.81 up at rest); ``xfrc_applied`` is force then torque at the centre of mass
(``xipos``), world frame; after ``mj_step`` the kinematics are one step stale until the next
``mj_forward``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from .backend import BodyMotion, Geom
from .kernels import M_COLS, body_motions

try:
    import mujoco
except ImportError as exc:  # pragma: no cover - mujoco is a dependency
    raise ImportError("deformx.cosim needs mujoco: python -m pip install mujoco") from exc

_G = mujoco.mjtGeom
_KINDS = {int(_G.mjGEOM_PLANE): "plane", int(_G.mjGEOM_SPHERE): "sphere",
          int(_G.mjGEOM_CAPSULE): "capsule", int(_G.mjGEOM_CYLINDER): "cylinder",
          int(_G.mjGEOM_BOX): "box", int(_G.mjGEOM_ELLIPSOID): "mesh", int(_G.mjGEOM_MESH): "mesh"}


def load_model(model: Any) -> "mujoco.MjModel":
    """An ``MjModel`` from a model, an MJCF file path or an MJCF string."""
    if isinstance(model, mujoco.MjModel):
        return model
    if isinstance(model, os.PathLike) or (isinstance(model, str)
                                          and not model.lstrip().startswith("<")):
        path = os.fspath(model)
        if not os.path.isfile(path):
            raise ValueError(f"model: no MJCF file at {path!r} (give a path, an MJCF string "
                             "or a mujoco.MjModel)")
        return mujoco.MjModel.from_xml_path(path)
    if isinstance(model, str):
        return mujoco.MjModel.from_xml_string(model)
    raise ValueError(f"model must be an MJCF string, a path or a mujoco.MjModel, got "
                     f"{type(model).__name__}")


def _quat_to_matrix(q: np.ndarray) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(q, dtype=np.float64))
    return R.reshape(3, 3)


def _ellipsoid_mesh(radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=3)
    return np.asarray(sphere.vertices) * radii, np.asarray(sphere.faces, dtype=np.int64)


class MujocoBackend:
    """A MuJoCo model and its data, stepped by ``mj_step`` (one co-simulation macro step).

    ``model``: an MJCF string, a path to an MJCF file, or a ``mujoco.MjModel``. ``.model``,
    ``.data`` are MuJoCo's own objects (set controls on ``data.ctrl`` as usual); ``.dt`` is
    ``model.opt.timestep``. ``keyframe`` (name or index): start from that keyframe (e.g.
    ``"home"`` of :func:`deformx.robots.ur5e`) instead of the model's reference pose.
    """

    def __init__(self, model: Any, keyframe: str | int | None = None) -> None:
        # what the model was made from (an MJCF string or path), for renderers that rebuild it
        self.source = model if isinstance(model, (str, os.PathLike)) else None
        self.model = load_model(model)
        self.data = mujoco.MjData(self.model)
        if keyframe is not None:
            k = keyframe if isinstance(keyframe, int) else mujoco.mj_name2id(
                self.model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
            if not isinstance(k, int) or not 0 <= k < self.model.nkey:
                raise ValueError(f"keyframe: no keyframe {keyframe!r} in the model "
                                 f"({self.model.nkey} keyframes)")
            mujoco.mj_resetDataKeyframe(self.model, self.data, k)
        mujoco.mj_forward(self.model, self.data)
        self._ids: dict[str, int] = {}
        self._id_arrays: dict[tuple, np.ndarray] = {}
        self._fresh = False  # begin() ran and nothing moved since: step() may skip mj_step1
        self._res = np.zeros(6)

    @property
    def dt(self) -> float:
        return float(self.model.opt.timestep)

    @property
    def time(self) -> float:
        return float(self.data.time)

    def body_id(self, name: str) -> int:
        """MuJoCo's id of body ``name`` ("world" is 0); ``ValueError`` if there is none."""
        i = self._ids.get(name)
        if i is None:
            i = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)
            if i < 0:
                names = [self.model.body(k).name for k in range(self.model.nbody)]
                raise ValueError(f"body: no body named {name!r} in the MuJoCo model "
                                 f"(bodies: {', '.join(repr(n) for n in names)})")
            self._ids[name] = i
        return i

    def has_body(self, name: str) -> bool:
        return mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name) >= 0

    def is_static(self, name: str) -> bool:
        """Whether the body never moves: the world body, or welded to it without joints
        (mocap bodies move: not static)."""
        m, i = self.model, self.body_id(name)
        while i != 0:
            if m.body_jntnum[i] > 0 or m.body_mocapid[i] >= 0:
                return False
            i = int(m.body_parentid[i])
        return True

    def welded(self, name: str) -> list[str]:
        """The bodies rigidly attached to body ``name`` (MuJoCo's weld group), itself included."""
        m = self.model
        w = m.body_weldid[self.body_id(name)]
        return [m.body(i).name for i in np.flatnonzero(m.body_weldid == w)]

    def mass(self, name: str) -> float:
        """The body's own mass (kg)."""
        return float(self.model.body_mass[self.body_id(name)])

    def free_mass(self, name: str) -> float | None:
        """The mass (kg) of a free-floating body (one free joint, no child bodies), else
        None: such a body can ride on a rod node (see ``CoSimulation.attach``)."""
        m, i = self.model, self.body_id(name)
        if (m.body_jntnum[i] != 1
                or int(m.jnt_type[m.body_jntadr[i]]) != int(mujoco.mjtJoint.mjJNT_FREE)):
            return None
        if np.any(m.body_parentid[i + 1:] == i):
            return None
        return float(m.body_mass[i])

    def gravity(self) -> np.ndarray:
        """The model's gravity (m/s^2)."""
        return self.model.opt.gravity.copy()

    def begin(self) -> None:
        mujoco.mj_forward(self.model, self.data)
        mujoco.mj_rnePostConstraint(self.model, self.data)
        self._fresh = True

    def motion(self, name: str) -> BodyMotion:
        m, d, i, res = self.model, self.data, self.body_id(name), self._res
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, i, res, 0)
        w, v = res[:3].copy(), res[3:].copy()
        mujoco.mj_objectAcceleration(m, d, mujoco.mjtObj.mjOBJ_XBODY, i, res, 0)
        alpha, a = res[:3].copy(), res[3:] + m.opt.gravity
        return BodyMotion(position=d.xpos[i].copy(), rotation=d.xmat[i].reshape(3, 3).copy(),
                          velocity=v, angular_velocity=w, acceleration=a,
                          angular_acceleration=alpha, com=d.xipos[i].copy())

    def motion_rows(self, names: list[str]) -> np.ndarray:
        """:meth:`motion` of many bodies, one row each (``deformx.cosim.kernels.M_*``
        columns), computed for all at once from MuJoCo's com-based velocities and
        accelerations as ``mj_objectVelocity`` / ``mj_objectAcceleration`` do."""
        m, d = self.model, self.data
        ids = self._id_array(names)
        out = np.empty((ids.shape[0], M_COLS))
        body_motions(ids, m.body_rootid, d.xpos, d.xmat, d.subtree_com, d.cvel, d.cacc,
                     d.xipos, m.opt.gravity, out)
        return out

    def _id_array(self, names: list[str]) -> np.ndarray:
        key = tuple(names)
        ids = self._id_arrays.get(key)
        if ids is None:
            ids = self._id_arrays[key] = np.array([self.body_id(n) for n in names],
                                                   dtype=np.int64)
        return ids

    def geoms(self, name: str) -> list[Geom]:
        m, i = self.model, self.body_id(name)
        out = []
        for g in np.flatnonzero(m.geom_bodyid == i):
            if m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0:
                continue  # visual only
            t = int(m.geom_type[g])
            kind = _KINDS.get(t)
            gname = m.geom(g).name or f"geom{g}"
            if kind is None:
                raise ValueError(f"add_colliders: geom {gname!r} of body {name!r} is a "
                                 f"{mujoco.mjtGeom(t).name}, which rods cannot collide with "
                                 "(use a mesh, box, sphere, capsule, cylinder or ellipsoid)")
            V = F = None
            size = m.geom_size[g].copy()
            if t == int(_G.mjGEOM_ELLIPSOID):
                V, F = _ellipsoid_mesh(size)
            elif t == int(_G.mjGEOM_MESH):
                k = int(m.geom_dataid[g])
                v0, nv = int(m.mesh_vertadr[k]), int(m.mesh_vertnum[k])
                f0, nf = int(m.mesh_faceadr[k]), int(m.mesh_facenum[k])
                V = m.mesh_vert[v0:v0 + nv].astype(np.float64)
                F = m.mesh_face[f0:f0 + nf].astype(np.int64)
            out.append(Geom(name=gname, kind=kind, size=size, position=m.geom_pos[g].copy(),
                            rotation=_quat_to_matrix(m.geom_quat[g]),
                            friction=float(m.geom_friction[g, 0]), vertices=V, faces=F))
        return out

    def apply_wrench(self, name: str, force: np.ndarray, torque: np.ndarray) -> None:
        i = self.body_id(name)
        self.data.xfrc_applied[i, :3] = force
        self.data.xfrc_applied[i, 3:] = torque

    def apply_wrenches(self, names: list[str], wrenches: np.ndarray) -> None:
        """:meth:`apply_wrench` for many bodies: ``wrenches`` (n, 6) force then torque."""
        self.data.xfrc_applied[self._id_array(names)] = wrenches

    def step(self) -> None:
        """``mj_step``; right after :meth:`begin` only its second half (``mj_step2``: forces,
        accelerations and integration with the new wrenches and controls), since positions
        and velocities have not changed since that forward pass."""
        if self._fresh and self.model.opt.integrator != mujoco.mjtIntegrator.mjINT_RK4:
            mujoco.mj_step2(self.model, self.data)
        else:
            mujoco.mj_step(self.model, self.data)
        self._fresh = False
