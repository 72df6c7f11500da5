"""Parameter checks that raise ``ValueError`` naming the parameter and its valid range."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np


def positive(name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as float if finite and > 0, else raise ``ValueError``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number{_u(unit)}, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be > 0{_u(unit)} (valid range: (0, inf)), got {value!r}")
    return v


def non_negative(name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as float if finite and >= 0, else raise ``ValueError``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number >= 0{_u(unit)}, got {value!r}") from None
    if not math.isfinite(v) or v < 0.0:
        raise ValueError(f"{name} must be >= 0{_u(unit)} (valid range: [0, inf)), got {value!r}")
    return v


def in_range(name: str, value: float, low: float, high: float, *, low_open: bool = False,
             high_open: bool = False) -> float:
    """Return ``value`` as float if inside the interval, else raise ``ValueError``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    lo_ok = v > low if low_open else v >= low
    hi_ok = v < high if high_open else v <= high
    if not (math.isfinite(v) and lo_ok and hi_ok):
        interval = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
        raise ValueError(f"{name} must lie in {interval}, got {value!r}")
    return v


def integer_at_least(name: str, value: int, minimum: int) -> int:
    """Return ``value`` as int if it is an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def vector3(name: str, value: Sequence[float], *, unit: bool = False) -> np.ndarray:
    """Return a finite float64 3-vector (normalised if ``unit``)."""
    try:
        v = np.asarray(value, dtype=np.float64).reshape(3)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a 3-vector (x, y, z), got {value!r}") from None
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if unit:
        norm = float(np.linalg.norm(v))
        if norm < 1e-12:
            raise ValueError(f"{name} must be a non-zero 3-vector, got {value!r}")
        v = v / norm
    return v


def _u(unit: str) -> str:
    return f" ({unit})" if unit else ""
