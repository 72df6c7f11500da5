"""Cable models the project generates itself (no downloads), as the paper's CAD import would use:
a USB-C-like cable with moulded plugs and strain reliefs, an Ethernet-like cable with RJ45-like
plugs and their clips, a twisted pair and a braided rope. Each is a triangle mesh in its bind
pose, lying along +x from the origin (the cable's axis), with per-vertex labels (0 skinned,
1 rigid with the start, 2 rigid with the end) and a material; :meth:`CableAsset.skin` binds it
to a straight rod of the same length wherever that rod lies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .materials import Material

#: The authors' dataset used radii of 1, 3 and 5 mm, twelve colours and roughness 0.75.
RADII = (0.001, 0.003, 0.005)


@dataclass
class CableAsset:
    """A cable mesh in its bind pose (along +x from the origin, ``length`` m long)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    labels: np.ndarray
    length: float
    materials: dict = field(default_factory=dict)  # part name -> Material
    part: np.ndarray | None = None  # per face: index into list(materials)

    def skin(self, rod):
        """A :class:`~deformx.visual.skin.Skin` of this cable on ``rod`` (open, straight now,
        as long as the cable): the cable's x axis goes along the rod, its y and z along the
        first element's d1 and d2."""
        from .skin import Skin

        if abs(rod.length - self.length) > 1e-6 * self.length:
            raise ValueError(f"the rod is {rod.length:g} m long, the cable {self.length:g} m")
        Q = rod.directors[0]
        R = np.column_stack([Q[2], Q[0], Q[1]])  # cable (x, y, z) -> (d3, d1, d2)
        world = self.vertices @ R.T + rod.positions[0]
        skin = Skin(rod, (world, self.faces), rigid=self.labels)
        skin.materials, skin.part = list(self.materials.values()), self.part  # per face
        return skin

    def trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


def _ring_tube(xs: np.ndarray, radii: np.ndarray, sides: int, offset=None, caps: bool = True
               ) -> tuple[np.ndarray, np.ndarray]:
    """Rings of ``sides`` vertices at stations ``xs`` along x with ``radii``; ``offset``
    (n, 2) moves each ring's centre in (y, z) (helices); caps close both ends."""
    n = len(xs)
    ang = 2.0 * np.pi * np.arange(sides) / sides
    cy, cz = (np.zeros(n), np.zeros(n)) if offset is None else (offset[:, 0], offset[:, 1])
    V = np.empty((n, sides, 3))
    V[..., 0] = xs[:, None]
    V[..., 1] = cy[:, None] + radii[:, None] * np.cos(ang)[None]
    V[..., 2] = cz[:, None] + radii[:, None] * np.sin(ang)[None]
    V = V.reshape(-1, 3)
    j = np.arange(sides)
    jn = (j + 1) % sides
    F = []
    for i in range(n - 1):  # outward: angles turn from +y to +z, counter-clockwise about +x
        a, b = i * sides, (i + 1) * sides
        F.append(np.column_stack([a + j, a + jn, b + j]))
        F.append(np.column_stack([a + jn, b + jn, b + j]))
    if caps:
        c0, c1 = len(V), len(V) + 1
        V = np.vstack([V, [[xs[0], cy[0], cz[0]], [xs[-1], cy[-1], cz[-1]]]])
        last = (n - 1) * sides
        F.append(np.column_stack([np.full(sides, c0), jn, j]))
        F.append(np.column_stack([np.full(sides, c1), last + j, last + jn]))
    return V, np.vstack(F)


def _box(center, half) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    b = trimesh.creation.box(extents=2.0 * np.asarray(half, dtype=float))
    return np.asarray(b.vertices) + center, np.asarray(b.faces)


class _Builder:
    def __init__(self) -> None:
        self.V, self.F, self.L, self.P = [], [], [], []
        self.n = 0

    def add(self, V, F, label: int, part: int) -> None:
        self.V.append(V)
        self.F.append(F + self.n)
        self.L.append(np.full(len(V), label))
        self.P.append(np.full(len(F), part))
        self.n += len(V)

    def build(self, name, length, materials) -> CableAsset:
        V = np.vstack(self.V)
        F = np.vstack(self.F).astype(np.int64)
        return CableAsset(name=name, vertices=V, faces=F, labels=np.concatenate(self.L),
                          length=length, materials=materials, part=np.concatenate(self.P))


def _stations(length: float, step: float) -> np.ndarray:
    return np.linspace(0.0, length, max(2, int(math.ceil(length / step)) + 1))


def usb_c_cable(length: float = 1.0, radius: float = 0.002, color=(0.08, 0.08, 0.09),
                sides: int = 16) -> CableAsset:
    """A USB-C-like cable: a round jacket, tapered strain reliefs at both ends (skinned) and
    moulded plugs with a metal shell beyond the ends (rigid)."""
    b = _Builder()
    xs = _stations(length, radius * 2.0)
    b.add(*_ring_tube(xs, np.full(len(xs), radius), sides), 0, 0)
    relief = min(0.02, 0.1 * length)
    for start, sign in ((0.0, 1.0), (length, -1.0)):  # strain reliefs hug the ends
        rx = start + sign * np.linspace(0.0, relief, 8)
        rr = radius * (1.8 - 0.7 * np.linspace(0.0, 1.0, 8))
        order = np.argsort(rx)
        b.add(*_ring_tube(rx[order], rr[order], sides), 0, 1)
    for end, label, sign in ((0.0, 1, -1.0), (length, 2, 1.0)):
        body_half = np.array([0.0125, 0.0062, 0.0032])
        shell_half = np.array([0.0045, 0.0042, 0.0013])
        c_body = np.array([end + sign * body_half[0], 0.0, 0.0])
        c_shell = np.array([end + sign * (2 * body_half[0] + shell_half[0]), 0.0, 0.0])
        b.add(*_box(c_body, body_half), label, 1)
        b.add(*_box(c_shell, shell_half), label, 2)
    return b.build("usb_c_cable", length, {
        "jacket": Material(tuple(color), 0.75), "plug": Material((0.1, 0.1, 0.1), 0.5),
        "shell": Material((0.8, 0.8, 0.82), 0.25, 1.0)})


def ethernet_cable(length: float = 1.0, radius: float = 0.003, color=(0.15, 0.35, 0.75),
                   sides: int = 16) -> CableAsset:
    """An Ethernet-like cable: jacket, RJ45-like transparent plug bodies and their clips."""
    b = _Builder()
    xs = _stations(length, radius * 2.0)
    b.add(*_ring_tube(xs, np.full(len(xs), radius), sides), 0, 0)
    for end, label, sign in ((0.0, 1, -1.0), (length, 2, 1.0)):
        body_half = np.array([0.011, 0.0058, 0.0042])
        b.add(*_box(np.array([end + sign * body_half[0], 0.0, 0.0]), body_half), label, 1)
        clip_half = np.array([0.007, 0.0025, 0.0006])
        b.add(*_box(np.array([end + sign * 0.012, 0.0, body_half[2] + clip_half[2] + 0.0004]),
                    clip_half), label, 1)
    return b.build("ethernet_cable", length, {
        "jacket": Material(tuple(color), 0.6), "plug": Material((0.85, 0.88, 0.9), 0.2)})


def twisted_pair(length: float = 1.0, radius: float = 0.001, pitch: float = 0.02,
                 colors=((0.9, 0.5, 0.1), (0.95, 0.95, 0.95)), sides: int = 10) -> CableAsset:
    """Two insulated wires of ``radius`` twisted about the axis with ``pitch`` (m per turn)."""
    b = _Builder()
    xs = _stations(length, min(radius, pitch / 24.0))
    for k in range(2):
        phase = 2.0 * np.pi * xs / pitch + k * np.pi
        off = radius * np.column_stack([np.cos(phase), np.sin(phase)])
        b.add(*_ring_tube(xs, np.full(len(xs), radius), sides, offset=off), 0, k)
    return b.build("twisted_pair", length, {"wire a": Material(tuple(colors[0]), 0.5),
                                            "wire b": Material(tuple(colors[1]), 0.5)})


def braided_rope(length: float = 1.0, radius: float = 0.005, strands: int = 8,
                 pitch: float = 0.03, color=(0.75, 0.6, 0.35), sides: int = 32) -> CableAsset:
    """A rope whose surface carries the ridges of ``strands`` braided strands."""
    b = _Builder()
    xs = _stations(length, radius / 2.0)
    n = len(xs)
    ang = 2.0 * np.pi * np.arange(sides) / sides
    V, F = _ring_tube(xs, np.full(n, radius), sides)
    ring = V[: n * sides].reshape(n, sides, 3)
    ridge = 1.0 + 0.12 * np.abs(np.cos(0.5 * strands * (ang[None] - 2 * np.pi * xs[:, None] / pitch)))
    ring[..., 1] *= ridge
    ring[..., 2] *= ridge
    V[: n * sides] = ring.reshape(-1, 3)
    b.add(V, F, 0, 0)
    return b.build("braided_rope", length, {"rope": Material(tuple(color), 0.9)})


ASSETS = {"usb_c": usb_c_cable, "ethernet": ethernet_cable, "twisted_pair": twisted_pair,
          "braided_rope": braided_rope}
