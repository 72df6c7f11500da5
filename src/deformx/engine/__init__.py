"""The Cosserat rod engine: rods, world, clamps, contact, integrators, kernels."""

from . import compile_notice  # noqa: F401  (installs the compile listener)
from .constraints import Clamp
from .recorder import Recorder
from .rod import Rod
from .world import World

__all__ = ["Clamp", "Recorder", "Rod", "World"]
