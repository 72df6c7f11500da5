"""The paper's linked-capsule baseline: a rope as a chain of rigid capsules joined by ball
joints with spring stiffness and damping, in MJCF (MuJoCo 4 dropped its cable plugin).

Segment ``i`` is body ``{name}_{i}``, its frame at the segment's start with local z along the
rope; a site ``{name}_tip`` marks the free end. :class:`deformx.cosim.CapsuleRope` reads such
a chain through the same small interface as a DeformX rod (node positions, tip position and
velocity), so an experiment can swap the two.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..engine import validation as check


def _frame_z(direction: np.ndarray) -> np.ndarray:
    """A quaternion (w, x, y, z) turning local z onto ``direction``."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(np.dot(z, direction))
    if c < -1.0 + 1e-12:
        return np.array([0.0, 1.0, 0.0, 0.0])
    axis = np.cross(z, direction)
    q = np.array([1.0 + c, *axis])
    return q / np.linalg.norm(q)


def capsule_rope(model: str | None = None, parent: str = "world", *, length: float = 1.0,
                 n_segments: int = 20, radius: float = 0.00635, density: float = 700.0,
                 youngs_modulus: float = 2e5, bend_stiffness: float | None = None,
                 damping: float = 1e-3, armature: float = 1e-5,
                 start: Sequence[float] = (0.0, 0.0, 0.0),
                 direction: Sequence[float] = (0.0, 0.0, -1.0),
                 end_anchor: Sequence[float] | None = None, friction: float = 0.5,
                 name: str = "rope", timestep: float = 2e-3) -> str:
    """MJCF string: ``model`` (an MJCF string; None: an empty world with ``timestep``) with a
    capsule rope added, hanging from body ``parent`` by a ball joint at ``start`` (m, in the
    parent's frame) along ``direction``.

    ``length`` (m), ``n_segments``, ``radius`` (m), ``density`` (kg/m^3). Each ball joint's
    spring ``bend_stiffness`` (N m/rad) defaults to E I / l (``youngs_modulus`` E, I = pi r^4/4,
    l the segment length), the discrete rod's bending stiffness; ``damping`` (N m s/rad) and
    ``armature`` (kg m^2) per joint. ``end_anchor`` (m, world): pin the free end to that point
    with an equality constraint between the sites ``{name}_tip`` and ``{name}_anchor`` (the
    calibration experiment's ground anchor); give the rope a shape that ends there with
    :meth:`deformx.cosim.CapsuleRope.set_shape`. The chain is straight in the model, so the
    joint springs rest at the straight rope.
    """
    import mujoco

    length = check.positive("length", length, "m")
    if not isinstance(n_segments, (int, np.integer)) or n_segments < 1:
        raise ValueError(f"n_segments must be an integer >= 1, got {n_segments!r}")
    radius = check.positive("radius", radius, "m")
    density = check.positive("density", density, "kg/m^3")
    d = np.array(check.vector3("direction", direction, unit=True))
    seg = length / n_segments
    k = (check.positive("youngs_modulus", youngs_modulus, "Pa") * math.pi * radius ** 4 / 4 / seg
         if bend_stiffness is None else check.non_negative("bend_stiffness", bend_stiffness,
                                                           "N m/rad"))
    if model is None:
        model = f'<mujoco><option timestep="{timestep:g}"/><worldbody/></mujoco>'
    spec = mujoco.MjSpec.from_string(model)
    body = spec.worldbody if parent == "world" else spec.body(parent)
    if body is None:
        raise ValueError(f"parent: no body named {parent!r} in the model")
    mass = density * math.pi * radius ** 2 * seg
    for i in range(n_segments):
        kw = dict(name=f"{name}_{i}", pos=list(start) if i == 0 else [0.0, 0.0, seg])
        if i == 0:
            kw["quat"] = list(_frame_z(d))
        body = body.add_body(**kw)
        body.add_joint(name=f"{name}_joint_{i}", type=mujoco.mjtJoint.mjJNT_BALL,
                       stiffness=k, damping=check.non_negative("damping", damping, "N m s/rad"),
                       armature=armature)
        body.add_geom(name=f"{name}_geom_{i}", type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                      fromto=[0.0, 0.0, 0.0, 0.0, 0.0, seg], size=[radius, 0.0, 0.0],
                      mass=mass, friction=[friction, 0.005, 0.0001],
                      rgba=[0.85, 0.45, 0.1, 1.0])
    body.add_site(name=f"{name}_tip", pos=[0.0, 0.0, seg], size=[radius, 0.0, 0.0])
    if end_anchor is not None:
        a = check.vector3("end_anchor", end_anchor)
        spec.worldbody.add_site(name=f"{name}_anchor", pos=list(a), size=[radius, 0.0, 0.0])
        eq = spec.add_equality(type=mujoco.mjtEq.mjEQ_CONNECT, name1=f"{name}_tip",
                               name2=f"{name}_anchor", objtype=mujoco.mjtObj.mjOBJ_SITE)
        eq.solref = [2.0 * spec.option.timestep, 1.0]  # stiffer than the default 0.02 s
    # adjacent capsules touch at their joints; MuJoCo's parent-child filter leaves them out
    return spec.to_xml()
