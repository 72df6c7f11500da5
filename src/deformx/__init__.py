"""DeformX: physically faithful, fast simulation of deformable linear objects (Cosserat rods)."""

from .engine import Clamp, Recorder, Rod, World
from .errors import SimulationDiverged

__version__ = "0.1.0"
__all__ = ["Clamp", "Recorder", "Rod", "SimulationDiverged", "World", "__version__"]
