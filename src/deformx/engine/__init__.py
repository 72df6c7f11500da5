"""The Cosserat rod engine: rods, world, clamps, contact, integrators, kernels."""

from .constraints import Clamp
from .recorder import Recorder
from .rod import Rod
from .world import World

__all__ = ["Clamp", "Recorder", "Rod", "World"]
