"""Co-simulation of DeformX rods with a rigid-body simulator (MuJoCo): the paper's
Algorithm 1, two-way. See ``docs/cosim.md``."""

from .backend import Backend, BodyMotion, Geom
from .coupling import Attachment, CoSimulation
from .mujoco_backend import MujocoBackend
from .ropes import CapsuleRope, Rope, RodRope

__all__ = ["Attachment", "Backend", "BodyMotion", "CapsuleRope", "CoSimulation", "Geom",
           "MujocoBackend", "Rope", "RodRope"]
