"""DeformX: physically faithful, fast simulation of deformable linear objects (Cosserat rods)."""

from ._kernel_cache import invalidate_stale_kernel_caches

invalidate_stale_kernel_caches()

from .engine import Clamp, Recorder, Rod, World  # noqa: E402
from .errors import SimulationDiverged

__version__ = "0.1.0"
__all__ = ["Clamp", "Recorder", "Rod", "SimulationDiverged", "World", "__version__"]
