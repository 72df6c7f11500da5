"""Reference (semi-)analytical solutions that simulator tests compare against."""

from tests.reference.rod_statics import (
    ALPHA_C,
    clamped_rod_sag,
    planar_rod_statics,
    timoshenko_cantilever_deflection,
)

__all__ = [
    "ALPHA_C",
    "clamped_rod_sag",
    "planar_rod_statics",
    "timoshenko_cantilever_deflection",
]
