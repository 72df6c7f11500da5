"""The visual layer: tube meshes of rods (``tube``), a pinhole camera (``camera``), the fast
renderer on MuJoCo (``fast``: RGB, z-depth, instance masks, keypoints), the photoreal renderer
on Blender Cycles (``photoreal``), skinned cable meshes (``skin``, ``assets``), rendered runs
(``movie``), export (``export``: USD, PLY/glTF), plots and videos of recorded runs (``plots``).

``visual.Camera``, ``visual.FastRenderer``, ``visual.PhotorealRenderer`` and ``visual.Frame``
are loaded on first use: importing this package loads no plotting or rendering library. See
``docs/visual.md``.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_LAZY = {"Camera": "camera", "Frame": "frame", "FastRenderer": "fast",
         "PhotorealRenderer": "photoreal", "Tube": "tube", "Skin": "skin",
         "UsdWriter": "export"}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'deformx.visual' has no attribute {name!r}")
    return getattr(import_module(f".{module}", __name__), name)
