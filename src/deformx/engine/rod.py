"""Rod: parameters and rest configuration of one discrete Cosserat rod, plus views of its state.

A rod owns its arrays until it is added to a :class:`~deformx.engine.world.World`; from then on
``positions``, ``velocities``, ... are views into the world's packed arrays (re-fetch them after
adding further rods, which repacks).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

import numpy as np

from . import validation as check
from .constraints import Clamp
from .kernels.so3 import curvature_from_directors

if TYPE_CHECKING:
    from .world import World

ALPHA_SHEAR = 27.0 / 28.0  # shear correction of a circular section (PyElastica's alpha_c)
DEFAULT_POISSON = 0.5


def shear_modulus_from(youngs_modulus: float, shear_modulus: float | None,
                       poisson_ratio: float | None) -> float:
    """Shear modulus (Pa) from E and either G or the Poisson ratio (default 0.5)."""
    if shear_modulus is not None and poisson_ratio is not None:
        raise ValueError("give either shear_modulus or poisson_ratio, not both")
    if shear_modulus is not None:
        return check.positive("shear_modulus", shear_modulus, "Pa")
    nu = DEFAULT_POISSON if poisson_ratio is None else check.in_range(
        "poisson_ratio", poisson_ratio, -1.0, 0.5, low_open=True)
    return youngs_modulus / (2.0 * (1.0 + nu))


def explicit_time_step(element_length: float, radius: float, density: float,
                       youngs_modulus: float, shear_modulus: float, safety: float = 0.3) -> float:
    """A conservative position-Verlet time step (s) for a rod discretisation.

    The two fastest modes bound the step: an axial wave crossing one element,
    ``dl sqrt(rho / E)``, and the shear-rotation oscillation of one cross-section,
    ``r / sqrt(k G / rho)`` with the circle's shear coefficient k = 4/3. ``safety`` = 0.3
    gives PyElastica's usual 1e-4 s for its 1 m, 100-element test rod (measured limit ~2e-4 s).
    Stiff contacts and large deformations can tighten it.
    """
    t_axial = element_length * math.sqrt(density / youngs_modulus)
    t_shear = radius * math.sqrt(density / (4.0 / 3.0 * shear_modulus))
    return safety * min(t_axial, t_shear)


def _perpendicular(t: np.ndarray) -> np.ndarray:
    helper = np.array([0.0, 0.0, 1.0]) if abs(t[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    n = helper - np.dot(helper, t) * t
    return n / np.linalg.norm(n)


def _transported_directors(tangents: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Frames with d3 = tangent and d1 parallel-transported from ``normal`` (twist-free)."""
    n = tangents.shape[0]
    Q = np.empty((n, 3, 3))
    d1 = normal
    for k in range(n):
        t = tangents[k]
        if k > 0:
            d1 = d1 - np.dot(d1, t) * t  # minimal rotation for small turning angles
            norm = np.linalg.norm(d1)
            d1 = d1 / norm if norm > 1e-12 else _perpendicular(t)
        Q[k, 0] = d1
        Q[k, 1] = np.cross(t, d1)
        Q[k, 2] = t
    return Q


class Rod:
    """One Cosserat rod: circular cross-section, linear elastic, uniform density.

    Use :meth:`straight` or :meth:`from_points`. SI units throughout. ``stretch_modulus``
    (Pa, default ``youngs_modulus``) sets the axial stiffness E_s A apart from the bending
    E I: a rope or a stranded cable bends like a soft solid but stretches like its fibres.
    ``twist_modulus`` (Pa, default the shear modulus) likewise sets the torsional stiffness
    G_t J apart from the shear stiffness G A: a rope held stiff in shear still twists easily.
    """

    def __init__(self, positions: np.ndarray, directors: np.ndarray, *, radius: float,
                 density: float, youngs_modulus: float, shear_modulus: float | None = None,
                 poisson_ratio: float | None = None, damping: float = 0.0, closed: bool = False,
                 rest_kappa: np.ndarray | None = None, internal_damping: float = 0.0,
                 stretch_modulus: float | None = None,
                 twist_modulus: float | None = None) -> None:
        self.closed = bool(closed)
        self.radius = check.positive("radius", radius, "m")
        self.density = check.positive("density", density, "kg/m^3")
        self.youngs_modulus = check.positive("youngs_modulus", youngs_modulus, "Pa")
        self.shear_modulus = shear_modulus_from(self.youngs_modulus, shear_modulus, poisson_ratio)
        self.stretch_modulus = self.youngs_modulus if stretch_modulus is None else \
            check.positive("stretch_modulus", stretch_modulus, "Pa")
        self.twist_modulus = self.shear_modulus if twist_modulus is None else \
            check.positive("twist_modulus", twist_modulus, "Pa")
        self._damping = check.non_negative("damping", damping, "1/s")
        self._internal_damping = check.non_negative("internal_damping", internal_damping, "s")

        pos = np.array(positions, dtype=np.float64)
        Q = np.array(directors, dtype=np.float64)
        ne = Q.shape[0]
        nn = ne if self.closed else ne + 1
        if pos.shape != (nn, 3) or Q.shape != (ne, 3, 3):
            raise ValueError(f"positions must be ({nn}, 3) and directors ({ne}, 3, 3)")
        if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(Q))):
            raise ValueError("positions and directors must be finite")
        seg = np.roll(pos, -1, axis=0)[:ne] - pos[:ne] if self.closed else np.diff(pos, axis=0)
        rest_len = np.linalg.norm(seg, axis=1)
        if np.any(rest_len < 1e-12):
            raise ValueError("points: consecutive points must be distinct (zero-length element)")
        nv = ne if self.closed else ne - 1

        self.rest_lengths = rest_len
        self.point_masses: dict[int, float] = {}  # node -> extra lumped mass (kg)
        self._derive_material()
        la, lb = rest_len[:nv], np.roll(rest_len, -1)[:nv]
        self.rest_voronoi_lengths = 0.5 * (lb + la)
        self.rest_sigma = np.zeros((ne, 3))
        if rest_kappa is None:
            self.rest_kappa = np.zeros((nv, 3))
        else:
            rk = np.asarray(rest_kappa, dtype=np.float64)
            try:
                self.rest_kappa = np.broadcast_to(rk, (nv, 3)).copy()
            except ValueError:
                raise ValueError(f"rest_curvature must have shape (3,) or ({nv}, 3), got {rk.shape}") from None
        self.node_radius = np.full(nn, self.radius)

        # State (owned until added to a world, then views into its packed block).
        self._positions = pos
        self._velocities = np.zeros((nn, 3))
        self._directors = Q
        self._angular_velocities = np.zeros((ne, 3))
        self._external_forces = np.zeros((nn, 3))
        self._external_torques = np.zeros((ne, 3))
        self._world: World | None = None
        self._index = -1
        self._clamps: list[Clamp] = []
        self._group = 0

    # ------------------------------------------------------------------ factories
    @classmethod
    def straight(cls, n_elements: int = 50, start: Sequence[float] = (0.0, 0.0, 0.0),
                 direction: Sequence[float] = (1.0, 0.0, 0.0), length: float = 1.0, *,
                 radius: float = 0.005, density: float = 1000.0, youngs_modulus: float = 1e6,
                 shear_modulus: float | None = None, poisson_ratio: float | None = None,
                 normal: Sequence[float] | None = None, damping: float = 0.0,
                 rest_curvature: np.ndarray | Sequence[float] | None = None,
                 internal_damping: float = 0.0, stretch_modulus: float | None = None,
                 twist_modulus: float | None = None) -> "Rod":
        """Straight rod of ``length`` m from ``start`` along ``direction``.

        ``normal`` is d1 of the material frames (must be perpendicular to ``direction``);
        ``rest_curvature`` is the intrinsic curvature/twist (1/m, material frame), (3,) or
        (n_elements - 1, 3).
        """
        n = check.integer_at_least("n_elements", n_elements, 2)
        length = check.positive("length", length, "m")
        start = check.vector3("start", start)
        t = check.vector3("direction", direction, unit=True)
        if normal is None:
            d1 = _perpendicular(t)
        else:
            d1 = check.vector3("normal", normal, unit=True)
            if abs(float(np.dot(d1, t))) > 1e-6:
                raise ValueError("normal must be perpendicular to direction (|normal . direction| <= 1e-6)")
        end = start + t * length
        pos = np.empty((n + 1, 3))
        for i in range(3):
            pos[:, i] = np.linspace(start[i], end[i], n + 1)
        seg = np.diff(pos, axis=0)
        tangents = seg / np.linalg.norm(seg, axis=1)[:, None]
        Q = np.empty((n, 3, 3))
        Q[:, 0] = d1
        Q[:, 1] = np.cross(tangents, d1)
        Q[:, 2] = tangents
        return cls(pos, Q, radius=radius, density=density, youngs_modulus=youngs_modulus,
                   shear_modulus=shear_modulus, poisson_ratio=poisson_ratio, damping=damping,
                   rest_kappa=rest_curvature, internal_damping=internal_damping,
                   stretch_modulus=stretch_modulus, twist_modulus=twist_modulus)

    @classmethod
    def from_points(cls, points: np.ndarray | Sequence[Sequence[float]], *, radius: float = 0.005,
                    density: float = 1000.0, youngs_modulus: float = 1e6,
                    shear_modulus: float | None = None, poisson_ratio: float | None = None,
                    closed: bool = False, rest_shape: str = "given",
                    normal: Sequence[float] | None = None, damping: float = 0.0,
                    internal_damping: float = 0.0, stretch_modulus: float | None = None,
                    twist_modulus: float | None = None) -> "Rod":
        """Rod through ``points`` (m, shape (m, 3)); one element per segment.

        ``closed=True`` joins the last point to the first (a ring). ``rest_shape="given"``
        makes the given curve stress-free; ``"straight"`` makes it straight and untwisted at
        rest (a bent wire that wants to straighten). ``normal`` seeds d1 of the first frame;
        later frames are parallel-transported along the curve.
        """
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"points must have shape (m, 3), got {pts.shape}")
        if closed and pts.shape[0] > 3 and np.allclose(pts[0], pts[-1]):
            pts = pts[:-1]
        if pts.shape[0] < (3 if closed else 3):
            raise ValueError(f"points: need at least 3 points, got {pts.shape[0]}")
        if rest_shape not in ("given", "straight"):
            raise ValueError(f"rest_shape must be 'given' or 'straight', got {rest_shape!r}")
        seg = (np.roll(pts, -1, axis=0) - pts) if closed else np.diff(pts, axis=0)
        lens = np.linalg.norm(seg, axis=1)
        if np.any(lens < 1e-12):
            raise ValueError("points: consecutive points must be distinct (zero-length element)")
        tangents = seg / lens[:, None]
        if normal is None:
            d1 = _perpendicular(tangents[0])
        else:
            d1 = check.vector3("normal", normal, unit=True)
            d1 = d1 - np.dot(d1, tangents[0]) * tangents[0]
            if np.linalg.norm(d1) < 1e-9:
                raise ValueError("normal must not be parallel to the first segment")
            d1 /= np.linalg.norm(d1)
        Q = _transported_directors(tangents, d1)
        rod = cls(pts, Q, radius=radius, density=density, youngs_modulus=youngs_modulus,
                  shear_modulus=shear_modulus, poisson_ratio=poisson_ratio, damping=damping,
                  closed=closed, internal_damping=internal_damping,
                  stretch_modulus=stretch_modulus, twist_modulus=twist_modulus)
        if rest_shape == "given":
            rod.rest_kappa = curvature_from_directors(Q, rod.rest_voronoi_lengths, rod.closed)
        return rod

    @property
    def damping(self) -> float:
        """Uniform damping rate (1/s): velocities decay as exp(-damping t)."""
        return self._damping

    @damping.setter
    def damping(self, value: float) -> None:
        self._damping = check.non_negative("damping", value, "1/s")
        if self._world is not None:
            self._world._rod_parameters_changed(self)

    @property
    def internal_damping(self) -> float:
        """Kelvin-Voigt retardation time (s) of the material (stable integrator only).

        Internal stresses get a viscous part ``internal_damping * d(stress)/dt``: a bending
        mode of angular frequency w is damped with ratio ``w * internal_damping / 2``, so
        higher modes lose energy faster, as in real cables.
        """
        return self._internal_damping

    @internal_damping.setter
    def internal_damping(self, value: float) -> None:
        self._internal_damping = check.non_negative("internal_damping", value, "s")
        if self._world is not None:
            self._world._rod_parameters_changed(self)

    @property
    def contact_group(self) -> int:
        """Rods of different contact groups never touch each other (the environments of a
        batch sharing one world); default 0."""
        return self._group

    @contact_group.setter
    def contact_group(self, value: int) -> None:
        if not isinstance(value, (int, np.integer)) or isinstance(value, bool):
            raise ValueError(f"contact_group must be an integer, got {value!r}")
        self._group = int(value)
        if self._world is not None:
            self._world._rod_parameters_changed(self)

    def ignore(self, *colliders) -> None:
        """Never touch these colliders (e.g. the gripper geom this rod is attached to)."""
        if self._world is None:
            raise ValueError("ignore: add the rod to a world first")
        self._world._ignore(self, colliders)

    def unignore(self, *colliders) -> None:
        """Touch these colliders again (undoes :meth:`ignore`; e.g. a gripper let go)."""
        if self._world is None:
            raise ValueError("unignore: add the rod to a world first")
        self._world._ignore(self, colliders, ignore=False)

    # ------------------------------------------------------------------ material
    def _derive_material(self) -> None:
        """Masses, rotational inertia, shear/stretch and bend/twist stiffness from the
        material and the rest lengths (PyElastica's definitions)."""
        rest_len = self.rest_lengths
        ne = rest_len.shape[0]
        nn = ne if self.closed else ne + 1
        area = np.pi * self.radius ** 2
        inertia = area * area / (4.0 * np.pi)  # second moment of area, pi r^4 / 4
        self.element_masses = self.density * area * rest_len
        masses = np.zeros(nn)
        masses[:ne] += 0.5 * self.element_masses
        if self.closed:
            masses += 0.5 * np.roll(self.element_masses, 1)
        else:
            masses[1:] += 0.5 * self.element_masses
        for node, extra in self.point_masses.items():
            masses[node] += extra
        self.masses = masses
        self._inertia = np.outer(self.density * rest_len, [inertia, inertia, 2.0 * inertia])
        self._shear_matrix = np.tile(
            [ALPHA_SHEAR * self.shear_modulus * area, ALPHA_SHEAR * self.shear_modulus * area,
             self.stretch_modulus * area], (ne, 1))
        bend_elem = np.tile([self.youngs_modulus * inertia, self.youngs_modulus * inertia,
                             self.twist_modulus * 2.0 * inertia], (ne, 1))
        nv = ne if self.closed else ne - 1
        la, lb = rest_len[:nv], np.roll(rest_len, -1)[:nv]
        ba, bb = bend_elem[:nv], np.roll(bend_elem, -1, axis=0)[:nv]
        self._bend_matrix = (bb * lb[:, None] + ba * la[:, None]) / (lb + la)[:, None]

    def set_material(self, *, density: float | None = None, youngs_modulus: float | None = None,
                     shear_modulus: float | None = None, poisson_ratio: float | None = None,
                     stretch_modulus: float | None = None,
                     twist_modulus: float | None = None) -> None:
        """Change the rod's material in place (domain randomisation at an episode's reset):
        masses, inertia and stiffness are rewritten in the world's buffers, no rebuild; it
        takes effect at the next step. The shape and the state stay as they are.

        Parameters left out keep their value, except that a new ``youngs_modulus`` carries the
        shear, stretch and twist moduli along in proportion unless they are given
        (``shear_modulus`` or ``poisson_ratio``; ``stretch_modulus``; ``twist_modulus``, which
        otherwise follows a new shear modulus while it equals the shear modulus). Units: kg/m^3
        and Pa.
        """
        rho = self.density if density is None else check.positive("density", density, "kg/m^3")
        E = self.youngs_modulus if youngs_modulus is None else check.positive(
            "youngs_modulus", youngs_modulus, "Pa")
        scale = E / self.youngs_modulus
        if shear_modulus is None and poisson_ratio is None:
            G = self.shear_modulus * scale
        else:
            G = shear_modulus_from(E, shear_modulus, poisson_ratio)
        if stretch_modulus is not None:
            Es = check.positive("stretch_modulus", stretch_modulus, "Pa")
        else:  # the default stretch modulus is E itself: keep it so, bit for bit
            Es = E if self.stretch_modulus == self.youngs_modulus else self.stretch_modulus * scale
        if twist_modulus is not None:
            Gt = check.positive("twist_modulus", twist_modulus, "Pa")
        else:  # likewise the default twist modulus is the shear modulus
            Gt = G if self.twist_modulus == self.shear_modulus else self.twist_modulus * scale
        self.density, self.youngs_modulus, self.shear_modulus, self.stretch_modulus = rho, E, G, Es
        self.twist_modulus = Gt
        self._derive_material()
        if self._world is not None:
            self._world._rod_material_changed(self)

    # ------------------------------------------------------------------ state
    def get_state(self) -> dict:
        """A copy of everything of this rod that the next step depends on (positions,
        velocities, frames, solver memory, friction anchors, its clamps' drivers): numpy
        arrays, picklable. Restore with :meth:`set_state` (one environment of a batch)."""
        if self._world is None:
            raise ValueError("get_state: the rod is not in a world")
        return self._world._rod_state(self)

    def set_state(self, state: dict) -> None:
        """Restore what :meth:`get_state` returned (of this rod, in this world)."""
        if self._world is None:
            raise ValueError("set_state: the rod is not in a world")
        self._world._set_rod_state(self, state)

    # ------------------------------------------------------------------ sizes
    @property
    def n_elements(self) -> int:
        return self._directors.shape[0]

    @property
    def n_nodes(self) -> int:
        return self._positions.shape[0]

    @property
    def length(self) -> float:
        """Rest length (m)."""
        return float(self.rest_lengths.sum())

    @property
    def mass(self) -> float:
        """Total mass (kg)."""
        return float(self.element_masses.sum())

    # ------------------------------------------------------------------ state views
    @property
    def positions(self) -> np.ndarray:
        """Node positions (n_nodes, 3), m."""
        return self._positions

    @property
    def velocities(self) -> np.ndarray:
        """Node velocities (n_nodes, 3), m/s."""
        return self._velocities

    @property
    def directors(self) -> np.ndarray:
        """Element material frames (n_elements, 3, 3); rows d1, d2, d3 in lab coordinates."""
        return self._directors

    @property
    def angular_velocities(self) -> np.ndarray:
        """Element angular velocities (n_elements, 3), rad/s, material frame."""
        return self._angular_velocities

    @property
    def external_forces(self) -> np.ndarray:
        """Applied nodal forces (n_nodes, 3), N, lab frame; persist until changed."""
        return self._external_forces

    @external_forces.setter
    def external_forces(self, value: np.ndarray) -> None:
        self._external_forces[...] = value

    @property
    def external_torques(self) -> np.ndarray:
        """Applied element torques (n_elements, 3), N m, material frame; persist until changed."""
        return self._external_torques

    @external_torques.setter
    def external_torques(self, value: np.ndarray) -> None:
        self._external_torques[...] = value

    # ------------------------------------------------------------------ boundary conditions
    def _add_clamp(self, node: int, element: int | None, position: bool = True) -> Clamp:
        clamp = Clamp(self, node, element, position)
        self._clamps.append(clamp)
        if self._world is not None:
            self._world._register_clamp(clamp)
        return clamp

    def _remove_clamp(self, clamp: Clamp) -> None:
        self._clamps.remove(clamp)
        if self._world is not None:
            self._world._release_clamp(clamp)

    def fix_start(self) -> Clamp:
        """Clamp the first node and first element's frame where they are now."""
        if self.closed:
            raise ValueError("fix_start: a closed rod has no start; use pin(node) instead")
        return self._add_clamp(0, 0)

    def fix_end(self) -> Clamp:
        """Clamp the last node and last element's frame where they are now."""
        if self.closed:
            raise ValueError("fix_end: a closed rod has no end; use pin(node) instead")
        return self._add_clamp(self.n_nodes - 1, self.n_elements - 1)

    def pin(self, node: int) -> Clamp:
        """Hold node ``node`` (negative counts from the end) at its position; frames stay free."""
        if not isinstance(node, (int, np.integer)) or not -self.n_nodes <= node < self.n_nodes:
            raise ValueError(f"node must be an integer in [{-self.n_nodes}, {self.n_nodes - 1}], got {node!r}")
        return self._add_clamp(int(node) % self.n_nodes, None)

    def hold(self, node: int, frame: bool = False, position: bool = True) -> Clamp:
        """Clamp node ``node`` (negative counts from the end) and, with ``frame``, the material
        frame of the element next to it (the element starting there; the last one for the
        last node): ``fix_start`` is ``hold(0, frame=True)``. ``position=False`` (with
        ``frame``) holds the frame only and leaves the node free."""
        if not isinstance(node, (int, np.integer)) or not -self.n_nodes <= node < self.n_nodes:
            raise ValueError(f"node must be an integer in [{-self.n_nodes}, {self.n_nodes - 1}], got {node!r}")
        if not position and not frame:
            raise ValueError("hold: position=False needs frame=True (nothing would be held)")
        node = int(node) % self.n_nodes
        element = min(node, self.n_elements - 1) if frame else None
        return self._add_clamp(node, element, position)

    def set_point_mass(self, node: int, mass: float) -> None:
        """Lump ``mass`` (kg) on node ``node`` (negative counts from the end) on top of the
        rod's own, e.g. a light body the rod carries (0 removes it). ``masses`` includes it;
        ``mass`` (the rod's own) does not. Takes effect at the next step, no rebuild."""
        if not isinstance(node, (int, np.integer)) or not -self.n_nodes <= node < self.n_nodes:
            raise ValueError(f"node must be an integer in [{-self.n_nodes}, {self.n_nodes - 1}], got {node!r}")
        node = int(node) % self.n_nodes
        mass = check.non_negative("mass", mass, "kg")
        self.masses[node] += mass - self.point_masses.get(node, 0.0)
        if mass > 0.0:
            self.point_masses[node] = mass
        else:
            self.point_masses.pop(node, None)
        if self._world is not None:
            self._world._rod_material_changed(self)

    @property
    def clamps(self) -> tuple[Clamp, ...]:
        return tuple(self._clamps)

    # ------------------------------------------------------------------ diagnostics
    def strains(self) -> tuple[np.ndarray, np.ndarray]:
        """Current shear/stretch strain sigma (n, 3) and curvature kappa (n_voronoi, 3)."""
        pos, Q = self._positions, self._directors
        seg = (np.roll(pos, -1, axis=0) - pos) if self.closed else np.diff(pos, axis=0)
        sigma = np.einsum("kij,kj->ki", Q, seg / self.rest_lengths[:, None])
        sigma[:, 2] -= 1.0
        kappa = curvature_from_directors(Q, self.rest_voronoi_lengths, self.closed)
        return sigma, kappa

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy (J)."""
        v, w = self._velocities, self._angular_velocities
        trans = 0.5 * float(np.sum(self.masses * np.sum(v * v, axis=1)))
        rot = 0.5 * float(np.sum(self._inertia * w * w))
        return trans + rot

    def elastic_energy(self) -> dict[str, float]:
        """Strain energy (J) split into stretch, shear, bend and twist."""
        sigma, kappa = self.strains()
        ds = sigma - self.rest_sigma
        dk = kappa - self.rest_kappa
        S, B = self._shear_matrix, self._bend_matrix
        l0, v0 = self.rest_lengths, self.rest_voronoi_lengths
        return {
            "stretch": 0.5 * float(np.sum(S[:, 2] * ds[:, 2] ** 2 * l0)),
            "shear": 0.5 * float(np.sum((S[:, 0] * ds[:, 0] ** 2 + S[:, 1] * ds[:, 1] ** 2) * l0)),
            "bend": 0.5 * float(np.sum((B[:, 0] * dk[:, 0] ** 2 + B[:, 1] * dk[:, 1] ** 2) * v0)),
            "twist": 0.5 * float(np.sum(B[:, 2] * dk[:, 2] ** 2 * v0)),
        }

    def gravitational_energy(self, gravity: Sequence[float]) -> float:
        """Potential energy (J) in a uniform field ``gravity`` (m/s^2), zero at the origin."""
        g = np.asarray(gravity, dtype=np.float64)
        return -float(np.sum(self.masses * (self._positions @ g)))

    def stable_dt(self) -> float:
        """A conservative explicit (Verlet) time step (s) for this rod alone."""
        return explicit_time_step(float(self.rest_lengths.min()), self.radius, self.density,
                                  max(self.youngs_modulus, self.stretch_modulus,
                                      self.twist_modulus),
                                  self.shear_modulus)

    def __repr__(self) -> str:
        kind = "closed" if self.closed else "open"
        return (f"Rod({kind}, n_elements={self.n_elements}, length={self.length:.4g} m, "
                f"radius={self.radius:.4g} m, E={self.youngs_modulus:.3g} Pa)")
