"""DeformX: physically faithful, fast simulation of deformable linear objects (Cosserat rods)."""

from ._kernel_cache import invalidate_stale_kernel_caches

invalidate_stale_kernel_caches()

from .engine import Clamp, Recorder, Rod, World  # noqa: E402
from .errors import SimulationDiverged

__version__ = "0.1.0"
__all__ = ["Clamp", "Recorder", "Rod", "SimulationDiverged", "World", "__version__"]


def _register_environments() -> None:
    """Make ``gymnasium.make("deformx/HitTarget-v0")`` work after ``import deformx`` where
    Gymnasium is installed (the [learn] extra); the environments load on first use."""
    try:
        from gymnasium.envs.registration import register, registry
    except ImportError:
        return
    if "deformx/HitTarget-v0" not in registry:
        register(id="deformx/HitTarget-v0", entry_point="deformx.learn.hit_target:HitTargetEnv",
                 vector_entry_point="deformx.learn.vector:HitTargetVecEnv")


_register_environments()
