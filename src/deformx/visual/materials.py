"""Surface materials of wires and parts: base colour, roughness, metallic (glTF / Blender's
Principled BSDF) and an optional texture wrapped on the wire's tube.

Texture coordinates of a tube (:class:`~deformx.visual.tube.Tube`): ``s`` = rest arc length /
``texture_scale`` (the texture repeats every ``texture_scale`` metres along the wire) and ``t`` =
angle about the centreline from the material frame's d1, over 2 pi. So a texture turns with the
rod's twist: a ``"stripe"`` along d1 winds round a twisted wire.

``texture``: ``None`` (plain colour), one of :data:`PROCEDURAL`, an image file path (PNG/JPEG,
columns along the wire, rows around it) or an (H, W, 3) uint8 array laid out the same way.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

#: Procedural textures: "stripe" (one band along the wire on its d1 side: shows twist),
#: "bands" (rings round the wire, one per repeat: shows sliding along it), "checker"
#: (4 x 4 squares per repeat: both).
PROCEDURAL = ("stripe", "bands", "checker")

_SIZE = 64  # pixels of a procedural texture per side


@dataclass
class Material:
    """Base colour (RGB 0-1), roughness and metallic (0-1), as in glTF / Blender's BSDF;
    ``texture`` (see the module), its second colour ``texture_color`` (RGB 0-1, procedural
    textures) and ``texture_scale`` (m along the wire per repeat)."""

    color: tuple = (0.08, 0.08, 0.09)
    roughness: float = 0.75
    metallic: float = 0.0
    texture: Any = None
    texture_color: tuple = (0.95, 0.95, 0.92)
    texture_scale: float = 0.05

    def __post_init__(self) -> None:
        for name in ("roughness", "metallic"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {v!r}")
        for name in ("color", "texture_color"):
            c = np.asarray(getattr(self, name), dtype=float)
            if c.shape != (3,) or not np.all((c >= 0.0) & (c <= 1.0)):
                raise ValueError(f"{name} must be three numbers in [0, 1] (RGB), got "
                                 f"{getattr(self, name)!r}")
        if not self.texture_scale > 0.0:
            raise ValueError(f"texture_scale must be > 0 (m per repeat), got "
                             f"{self.texture_scale!r}")
        t = self.texture
        if isinstance(t, str) and t not in PROCEDURAL and not Path(t).is_file():
            raise ValueError(f"texture must be one of {PROCEDURAL}, an image file or an (H, W, "
                             f"3) uint8 array; {t!r} is neither a procedural name nor a file")


def texture_image(material: Material) -> np.ndarray | None:
    """The material's texture as an (H, W, 3) uint8 array (columns along the wire, one
    repeat; rows round it from d1), or None without one."""
    t = material.texture
    if t is None:
        return None
    if isinstance(t, np.ndarray):
        img = t
    elif t in PROCEDURAL:
        return _procedural(t, material.color, material.texture_color)
    else:
        import imageio.v3 as iio

        img = iio.imread(t)
    img = np.asarray(img)
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=2)
    if img.ndim != 3 or img.shape[2] not in (3, 4) or img.dtype != np.uint8:
        raise ValueError(f"texture must be an (H, W, 3) uint8 image, got shape {img.shape} "
                         f"and dtype {img.dtype}")
    return np.ascontiguousarray(img[..., :3])


def _procedural(kind: str, color, second) -> np.ndarray:
    a = np.round(np.asarray(color) * 255).astype(np.uint8)
    b = np.round(np.asarray(second) * 255).astype(np.uint8)
    row = (np.arange(_SIZE) + 0.5) / _SIZE  # t: angle / 2 pi
    col = (np.arange(_SIZE) + 0.5) / _SIZE  # s: along the wire, one repeat
    if kind == "stripe":  # a band of 1/6 of the circumference centred on d1 (t = 0 = 1)
        mask = np.broadcast_to((np.minimum(row, 1.0 - row) < 1.0 / 12.0)[:, None],
                               (_SIZE, _SIZE))
    elif kind == "bands":  # a ring over the first fifth of each repeat
        mask = np.broadcast_to((col < 0.2)[None, :], (_SIZE, _SIZE))
    else:
        mask = ((np.floor(row * 4)[:, None] + np.floor(col * 4)[None, :]) % 2) == 1
    return np.where(mask[..., None], b, a).astype(np.uint8)
