"""What a rigid-body simulator offers the co-simulation (the backend protocol).

A backend owns bodies (robots, fixtures, free objects) and advances them by its own step
``dt``. The co-simulation reads each coupled body's motion at the start of a macro step,
predicts it inside the rod substeps, and hands back the mean wrench the rods put on the body.
MuJoCo's is :class:`deformx.cosim.MujocoBackend`; another simulator (Isaac Sim, Genesis,
Newton) is one module implementing these methods.

Conventions: SI units, world frame; a body's *frame* is its origin and orientation (the
frame geoms and attachments are given in), distinct from its centre of mass.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

import numpy as np


@dataclass
class BodyMotion:
    """A body frame's pose, twist and acceleration now (world frame).

    ``position`` (m) and ``rotation`` (world-from-body) of the frame's origin; ``velocity``
    (m/s) and ``acceleration`` (m/s^2) of that origin; ``angular_velocity`` (rad/s) and
    ``angular_acceleration`` (rad/s^2); ``com`` (m), the centre of mass, where wrenches apply.
    """

    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    acceleration: np.ndarray
    angular_acceleration: np.ndarray
    com: np.ndarray


@dataclass
class Geom:
    """One collision shape of a body, in the body's frame.

    ``kind``: "plane", "sphere", "capsule", "cylinder", "box" or "mesh"; ``size``: radius
    (sphere), (radius, half-length along local z) (capsule, cylinder), half extents (box),
    unused (plane: local z is the normal); ``position`` (3) and ``rotation`` (3x3,
    body-from-geom); ``vertices`` (V, 3) / ``faces`` (F, 3) for meshes (geom frame);
    ``friction``: Coulomb coefficient.
    """

    name: str
    kind: str
    size: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    friction: float
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None


class Backend(Protocol):
    """The rigid-body side of a co-simulation."""

    @property
    def dt(self) -> float:
        """The backend's step (s): one macro step of the co-simulation."""

    @property
    def time(self) -> float:
        """Simulated time (s)."""

    def has_body(self, name: str) -> bool:
        """Whether a body of that name exists ("world" is the fixed frame)."""

    def begin(self) -> None:
        """Make everything :meth:`motion` reads current (called once per macro step, before
        the rods advance); may use the wrenches of the last :meth:`apply_wrench`."""

    def motion(self, name: str) -> BodyMotion:
        """The body's frame motion now (after :meth:`begin`)."""

    def geoms(self, name: str) -> Sequence[Geom]:
        """The body's collision shapes."""

    def apply_wrench(self, name: str, force: np.ndarray, torque: np.ndarray) -> None:
        """Apply ``force`` (N) and ``torque`` (N m, about the centre of mass) to the body,
        world frame, during the coming :meth:`step` (replaces the previous one)."""

    def step(self) -> None:
        """Advance the bodies by ``dt``."""
