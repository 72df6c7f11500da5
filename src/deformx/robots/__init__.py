"""Robots and rigid-body models for co-simulation, as MJCF: a UR5e from UR's DH parameters
and the linked-capsule rope baseline."""

from .capsules import capsule_rope
from .ur import HOME, JOINTS, forward_kinematics, ur5e

__all__ = ["HOME", "JOINTS", "capsule_rope", "forward_kinematics", "ur5e"]
