"""A UR5e in MJCF, built from Universal Robots' published DH parameters.

Frames: the MJCF's ``base`` body is the **DH base frame** (z up along the first joint axis,
x such that the DH table holds), so the pose of body ``flange`` equals :func:`forward_kinematics`
exactly. UR's own ``base_link`` (URDF, ROS, Isaac Sim, MuJoCo Menagerie) is the DH base rotated
by pi about z; joint angles are the same in both (UR's controller angles). A user whose robot
stands with its ``base_link`` at a pose passes ``ur_base_link=True``: the model then places
``base_link`` at ``base_position`` / ``base_rotation`` and the DH base inside it, rotated by pi
about z, so joint angles taken from such a setup (the paper's, Isaac Sim) mean the same here.

Bodies are placed by explicit offsets (``pos``) and rotations (``quat``) with joints about
their local z axes; the shapes are capsules and cylinders in UR's colours (no meshes are
downloaded). Link masses are UR's URDF values; inertias are those of solid cylinders of the
link's size at its centre. Actuators are position servos with torque limits (150 N m for
base, shoulder, elbow; 28 N m for the wrists); the speed limit (180 deg/s) is recorded as
the custom numeric ``max_joint_speed`` (rad/s) for controllers to respect; the links' weight
is compensated by default (``gravcomp``), as UR's controller does.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

#: UR5e DH parameters (standard convention): d, a, alpha per joint (m, m, rad).
D = (0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996)
A = (0.0, -0.425, -0.3922, 0.0, 0.0, 0.0)
ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)

JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
          "wrist_2_joint", "wrist_3_joint")
LINKS = ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link",
         "wrist_3_link")
MASSES = {"base": 4.0, "shoulder_link": 3.7, "upper_arm_link": 8.393, "forearm_link": 2.275,
          "wrist_1_link": 1.219, "wrist_2_link": 1.219, "wrist_3_link": 0.1889}
TORQUE_LIMITS = (150.0, 150.0, 150.0, 28.0, 28.0, 28.0)  # N m
JOINT_RANGES = ((-2 * math.pi, 2 * math.pi),) * 2 + ((-math.pi, math.pi),) + (
    (-2 * math.pi, 2 * math.pi),) * 3
MAX_JOINT_SPEED = math.pi  # rad/s (180 deg/s)
#: The authors' default pose of the hit-target task (their base_link frame; same angles here).
HOME = (-1.5935, -2.2756, -1.1913, -0.3241, 1.5707, 3.1415)

_GREY = "0.78 0.80 0.82 1"
_BLUE = "0.36 0.55 0.72 1"
_DARK = "0.15 0.15 0.17 1"


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Rz(theta) Tz(d) Tx(a) Rx(alpha) as a 4x4 matrix."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct],
                     [st, ct * ca, -ct * sa, a * st],
                     [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


def forward_kinematics(q: Sequence[float], tool_length: float = 0.0) -> np.ndarray:
    """Pose (4x4, DH base frame) of the tool flange - or of the tip of a stick of
    ``tool_length`` (m) along the flange's z axis - at joint angles ``q`` (6, rad)."""
    q = np.asarray(q, dtype=np.float64).reshape(-1)
    if q.shape != (6,) or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be 6 finite joint angles (rad), got shape {q.shape}")
    T = np.eye(4)
    for i in range(6):
        T = T @ dh_transform(q[i], D[i], A[i], ALPHA[i])
    if tool_length:
        T = T @ np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, tool_length], [0, 0, 0, 1.0]])
    return T


def _quat_x(angle: float) -> str:
    return f"{math.cos(angle / 2):.17g} {math.sin(angle / 2):.17g} 0 0"


def _quat(R: np.ndarray) -> str:
    import mujoco

    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.asarray(R, dtype=np.float64).ravel())
    return " ".join(f"{v:.17g}" for v in q)


def _cylinder_inertia(mass: float, radius: float, length: float, axis: int) -> str:
    """Diagonal inertia (kg m^2) of a solid cylinder along local ``axis``."""
    ax = 0.5 * mass * radius ** 2
    tr = mass * (3 * radius ** 2 + length ** 2) / 12.0
    diag = [tr, tr, tr]
    diag[axis] = ax
    return " ".join(f"{v:.6g}" for v in diag)


def ur5e(tool_length: float = 0.65, tool_radius: float = 0.01, tool_mass: float = 0.1,
         base_position: Sequence[float] = (0.0, 0.0, 0.0),
         base_rotation: np.ndarray | None = None, ur_base_link: bool = False,
         q0: Sequence[float] | None = None,
         kp: Sequence[float] = (2e4, 2e4, 1e4, 2e3, 2e3, 1e3),
         kv: Sequence[float] = (200, 200, 100, 20, 20, 10), timestep: float = 2e-3,
         floor: bool = False, gravity_compensation: bool = True, name: str = "ur5e") -> str:
    """MJCF string of a UR5e with a stick tool (see the module docstring).

    ``tool_length`` (m): a stick along the flange's z axis (0: none) with a body ``tool_tip``
    at its end; ``base_position`` / ``base_rotation`` (3x3, world-from-base): where the DH base
    (or, with ``ur_base_link``, UR's ``base_link``) stands; ``q0`` (6 rad): initial joint
    angles and servo targets (default all zero); ``kp`` (N m/rad) / ``kv`` (N m s/rad):
    servo gains per joint (kv / kp = 10 ms: the servo lags a moving target by about
    10 ms; MuJoCo's position servo has no velocity feed-forward); ``timestep`` (s); ``floor``: add a ground plane at z = 0;
    ``gravity_compensation``: the links' weight is compensated (MuJoCo's ``gravcomp``), as
    UR's controller does, so the servos track without a steady error (the tool is not).
    """
    if not tool_length >= 0.0:
        raise ValueError(f"tool_length must be >= 0 m, got {tool_length!r}")
    q0 = np.zeros(6) if q0 is None else np.asarray(q0, dtype=np.float64).reshape(-1)
    if q0.shape != (6,):
        raise ValueError(f"q0 must hold 6 joint angles (rad), got {q0.shape}")
    kp, kv = np.asarray(kp, float).reshape(6), np.asarray(kv, float).reshape(6)
    R = np.eye(3) if base_rotation is None else np.asarray(base_rotation, dtype=np.float64)
    bp = " ".join(f"{v:.17g}" for v in base_position)
    r_link = (0.06, 0.054, 0.045, 0.038, 0.038, 0.035)
    lines = [f'<mujoco model="{name}">',
             '  <compiler angle="radian" autolimits="true"/>',
             f'  <option timestep="{timestep:g}" integrator="implicitfast"/>',
             f'  <custom><numeric name="max_joint_speed" data="{MAX_JOINT_SPEED:.17g}"/></custom>',
             '  <default>',
             '    <geom contype="1" conaffinity="1" friction="0.8 0.005 0.0001"/>',
             '    <joint damping="1.0" armature="0.1"/>',
             '  </default>',
             '  <worldbody>',
             '    <light pos="0 0 3" dir="0 0 -1"/>']
    if floor:
        lines.append('    <geom name="floor" type="plane" size="0 0 0.05" rgba="0.55 0.55 0.5 1"/>')
    indent = "    "
    closing = []
    if ur_base_link:
        lines.append(f'{indent}<body name="base_link" pos="{bp}" quat="{_quat(R)}">')
        closing.append(indent + "</body>")
        indent += "  "
        lines.append(f'{indent}<body name="base" quat="0 0 0 1">')
    else:
        lines.append(f'{indent}<body name="base" pos="{bp}" quat="{_quat(R)}">')
    closing.append(indent + "</body>")
    lines.append(f'{indent}  <inertial pos="0 0 0.04" mass="{MASSES["base"]}" '
                 f'diaginertia="{_cylinder_inertia(MASSES["base"], 0.075, 0.09, 2)}"/>')
    lines.append(f'{indent}  <geom name="base_geom" type="cylinder" size="0.075 0.045" '
                 f'pos="0 0 0.045" rgba="{_GREY}"/>')
    # Body i+1 sits in body i at Tz(d_i) Tx(a_i) Rx(alpha_i); every joint turns about local z.
    pos = "0 0 0.0"
    quat = "1 0 0 0"
    for i in range(6):
        indent += "  "
        link, m = LINKS[i], MASSES[LINKS[i]]
        lo, hi = JOINT_RANGES[i]
        gc = ' gravcomp="1"' if gravity_compensation else ""
        lines.append(f'{indent}<body name="{link}" pos="{pos}" quat="{quat}"{gc}>')
        closing.append(indent + "</body>")
        lines.append(f'{indent}  <joint name="{JOINTS[i]}" axis="0 0 1" range="{lo:.17g} {hi:.17g}" '
                     f'actuatorfrcrange="{-TORQUE_LIMITS[i]:g} {TORQUE_LIMITS[i]:g}"/>')
        r = r_link[i]
        if A[i] != 0.0:  # a link along local x (upper arm, forearm), a joint housing at its root
            half = 0.5 * A[i]
            lines.append(f'{indent}  <inertial pos="{half:.6g} 0 0" mass="{m}" '
                         f'diaginertia="{_cylinder_inertia(m, r, abs(A[i]), 0)}"/>')
            lines.append(f'{indent}  <geom name="{link}_geom" type="capsule" '
                         f'fromto="0 0 0 {A[i]:.17g} 0 0" size="{0.75 * r:.4g}" rgba="{_GREY}"/>')
            lines.append(f'{indent}  <geom name="{link}_joint" type="cylinder" size="{r:.4g} {r:.4g}" '
                         f'rgba="{_BLUE}"/>')
        else:  # a housing along local z up to the next joint
            h = max(D[i], 0.04)
            lines.append(f'{indent}  <inertial pos="0 0 {0.5 * h:.6g}" mass="{m}" '
                         f'diaginertia="{_cylinder_inertia(m, r, h, 2)}"/>')
            lines.append(f'{indent}  <geom name="{link}_geom" type="cylinder" size="{r:.4g} {0.5 * h:.6g}" '
                         f'pos="0 0 {0.5 * h:.6g}" rgba="{_BLUE if i in (0, 3, 4) else _GREY}"/>')
        pos = f"{A[i]:.17g} 0 {D[i]:.17g}"
        quat = _quat_x(ALPHA[i])
    indent += "  "
    lines.append(f'{indent}<body name="flange" pos="{pos}" quat="{quat}">')
    closing.append(indent + "</body>")
    if tool_length > 0.0:
        lines.append(f'{indent}  <inertial pos="0 0 {0.5 * tool_length:.6g}" mass="{tool_mass}" '
                     f'diaginertia="{_cylinder_inertia(tool_mass, tool_radius, tool_length, 2)}"/>')
        lines.append(f'{indent}  <geom name="tool_geom" type="capsule" fromto="0 0 0 0 0 '
                     f'{tool_length:.17g}" size="{tool_radius:g}" rgba="{_DARK}"/>')
        lines.append(f'{indent}  <body name="tool_tip" pos="0 0 {tool_length:.17g}">')
        lines.append(f'{indent}    <site name="tool_tip" size="0.005"/>')
        lines.append(f'{indent}  </body>')
    lines.extend(reversed(closing))
    lines.append('  </worldbody>')
    # the base is welded to the world, so MuJoCo's parent-child filter does not cover it
    lines.append('  <contact><exclude body1="base" body2="shoulder_link"/>'
                 '<exclude body1="base" body2="upper_arm_link"/></contact>')
    lines.append('  <actuator>')
    for i, j in enumerate(JOINTS):
        lines.append(f'    <position name="{j.replace("_joint", "")}" joint="{j}" kp="{kp[i]:g}" '
                     f'kv="{kv[i]:g}" ctrlrange="{JOINT_RANGES[i][0]:.17g} {JOINT_RANGES[i][1]:.17g}" '
                     f'forcerange="{-TORQUE_LIMITS[i]:g} {TORQUE_LIMITS[i]:g}"/>')
    lines.append('  </actuator>')
    qs = " ".join(f"{v:.17g}" for v in q0)
    lines.append(f'  <keyframe><key name="home" qpos="{qs}" ctrl="{qs}"/></keyframe>')
    lines.append('</mujoco>')
    return "\n".join(lines)
