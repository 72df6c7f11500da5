"""The paper's rope calibration experiment, for both rope models.

A 2 m rope, one end anchored to the ground, the other held by a UR5e's tool, which traces a
vertical sinusoid (1.2 Hz, 0.2 m amplitude) through its position servos (inverse kinematics
each control step); markers spaced evenly along the rope are recorded to CSV (time, marker,
x, y, z). ``rope="cosserat"`` co-simulates a DeformX rod with MuJoCo (Algorithm 1);
``rope="capsule"`` is the linked-capsule baseline inside MuJoCo. Both start from the same
sagging shape and are driven by the same robot.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
import numpy as np

from ..engine.running import progress_bar


@dataclass
class Setup:
    """Every number of the experiment (SI units)."""

    length: float = 2.0                      # rope (m)
    n_elements: int = 40                     # rod elements = capsules (20 diverged once:
                                             # a 10 cm element folded > 170 deg at 0.65 s)
    radius: float = 0.00635                  # m
    density: float = 700.0                   # kg/m^3
    youngs_modulus: float = 2e5              # Pa
    damping: float = 0.1                     # 1/s (rod)
    capsule_damping: float = 1e-2            # N m s/rad per ball joint (capsule rope)
    capsule_armature: float = 1e-3           # kg m^2 per ball joint: 1e-4 or less diverges
                                             # at the 2 ms step (measured)
    frequency: float = 1.2                   # Hz
    amplitude: float = 0.2                   # m, vertical
    base: tuple = (0.0, 0.0, 0.5)            # UR5e DH base on a pedestal (m)
    tool_length: float = 0.1                 # a short stub holding the rope (m)
    start: tuple = (0.45, 0.0, 1.0)          # tool tip at rest (m)
    anchor: tuple = (1.85, 0.0, 0.00635)     # rope end on the ground (m)
    markers: int = 20
    dt: float = 2e-3                         # control and MuJoCo step (s)
    integrator: str = "stable"


def sag_curve(a: np.ndarray, b: np.ndarray, length: float, n: int,
              floor: float = -np.inf) -> np.ndarray:
    """``n + 1`` points spaced ``length / n`` apart from ``a`` to ``b`` along a downward
    parabolic sag, lying on the ground ``z = floor`` where it would dip below, whose arc length
    is ``length`` (needs ``|b - a| < length``)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    chord = float(np.linalg.norm(b - a))
    if chord >= length:
        raise ValueError(f"the rope ({length:g} m) must be longer than the distance between its "
                         f"ends ({chord:g} m)")
    u = np.linspace(0.0, 1.0, 4001)

    def curve(s):
        p = a + np.outer(u, b - a) - np.outer(4.0 * s * u * (1.0 - u), [0.0, 0.0, 1.0])
        p[:, 2] = np.maximum(p[:, 2], floor)
        return p

    lo, hi = 0.0, 100.0 * length
    for _ in range(100):
        s = 0.5 * (lo + hi)
        arc = np.linalg.norm(np.diff(curve(s), axis=0), axis=1).sum()
        lo, hi = (s, hi) if arc < length else (lo, s)
    return resample(curve(0.5 * (lo + hi)), n, exact=length / n)


def resample(poly: np.ndarray, n: int, exact: float | None = None) -> np.ndarray:
    """``n + 1`` points evenly spaced by arc length along a polyline; with ``exact`` walk
    chords of exactly that length (so a chain of rigid segments fits them)."""
    seg = np.linalg.norm(np.diff(poly, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if exact is None:
        t = np.linspace(0.0, s[-1], n + 1)
        return np.column_stack([np.interp(t, s, poly[:, k]) for k in range(3)])
    out = [poly[0]]
    j = 0
    for _ in range(n):  # next point on the polyline at chord distance `exact`
        p = out[-1]
        while j < len(poly) - 1 and np.linalg.norm(poly[j + 1] - p) < exact:
            j += 1
        if j >= len(poly) - 1:
            out.append(p + exact * (poly[-1] - p) / max(np.linalg.norm(poly[-1] - p), 1e-300))
            continue
        q0, q1 = poly[j], poly[j + 1]
        d = q1 - q0
        f = q0 - p
        A, B, C = d @ d, 2 * f @ d, f @ f - exact ** 2
        t = (-B + math.sqrt(max(B * B - 4 * A * C, 0.0))) / (2 * A)
        out.append(q0 + t * d)
    return np.array(out)


def markers_along(points: np.ndarray, count: int) -> np.ndarray:
    """``count`` markers evenly spaced by arc length along the rope, both ends included."""
    return resample(points, count - 1)


class Experiment:
    """The calibration experiment, ready to step: ``step()`` one control step, ``time``,
    ``rope`` (the :class:`deformx.cosim.Rope` interface), ``markers()``."""

    def __init__(self, rope: str = "cosserat", setup: Setup | None = None,
                 motion: tuple | None = None) -> None:
        import deformx as dx
        from deformx import cosim, robots
        from deformx.robots.ik import solve_position

        if rope not in ("cosserat", "capsule"):
            raise ValueError(f"rope must be 'cosserat' or 'capsule', got {rope!r}")
        self.kind = rope
        self.setup = s = setup or Setup()
        self._motion = None
        if motion is not None:  # (times (T,), tool positions (T, 3)): a recorded path
            t, p = (np.asarray(a, dtype=np.float64) for a in motion)
            if t.ndim != 1 or p.shape != (len(t), 3) or len(t) < 2 or np.any(np.diff(t) <= 0):
                raise ValueError("motion: times (T,) increasing and positions (T, 3), T >= 2")
            self._motion = (t, p)
        xml = robots.ur5e(tool_length=s.tool_length, base_position=s.base, floor=True,
                          timestep=s.dt)
        model = cosim.mujoco_backend.load_model(xml)
        rest = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])  # tool pointing down
        q = solve_position(model, "tool_tip", s.start, rest, rest=rest, iterations=200)
        self._solve, self._rest, self._ik_model = solve_position, rest, model  # arm only
        shape = sag_curve(np.array(s.start), np.array(s.anchor), s.length, s.n_elements,
                          floor=s.radius)
        if rope == "capsule":
            xml = robots.capsule_rope(xml, parent="tool_tip", length=s.length,
                                      n_segments=s.n_elements, radius=s.radius,
                                      density=s.density, youngs_modulus=s.youngs_modulus,
                                      damping=s.capsule_damping,
                                      armature=s.capsule_armature, end_anchor=s.anchor,
                                      timestep=s.dt)
        self.backend = cosim.MujocoBackend(xml)
        m, d = self.backend.model, self.backend.data
        self._arm = np.array([m.jnt_qposadr[m.joint(j).id] for j in robots.JOINTS])
        d.qpos[self._arm] = q[:6]
        d.ctrl[:] = q[:6]
        self._q = q.copy()
        if rope == "capsule":
            self.rope = cosim.CapsuleRope(self.backend)
            self.rope.set_shape(shape)
            self.sim = None
        else:
            world = dx.World(dt=s.dt, integrator=s.integrator)
            rod = world.add_rod(dx.Rod.from_points(shape, radius=s.radius, density=s.density,
                                                   youngs_modulus=s.youngs_modulus,
                                                   damping=s.damping))
            self.sim = cosim.CoSimulation(world, self.backend)
            self.sim.add_colliders("world")  # the floor
            self.sim.attach(rod, "start", body="tool_tip")
            rod.pin(-1)
            self.rod = rod
            self.rope = cosim.RodRope(rod)
        self.backend.begin()

    @property
    def time(self) -> float:
        return self.backend.time

    def tool_target(self, t: float) -> np.ndarray:
        """The tool tip's commanded position (m) at time ``t`` (s): the recorded motion
        (interpolated, held after its end) or the setup's sinusoid."""
        if self._motion is not None:
            times, pos = self._motion
            return np.array([np.interp(t, times, pos[:, k]) for k in range(3)])
        s = self.setup
        return np.array(s.start) + np.array([0.0, 0.0, s.amplitude * math.sin(
            2.0 * math.pi * s.frequency * t)])

    def step(self) -> None:
        """One control step: servo targets from the tool's path, then one macro step."""
        d = self.backend.data
        target = self.tool_target(self.time + self.setup.dt)
        self._q = self._solve(self._ik_model, "tool_tip", target, self._q, rest=self._rest,
                              iterations=3)
        d.ctrl[:] = self._q
        if self.sim is not None:
            self.sim.step()
        else:
            self.backend.step()

    def markers(self) -> np.ndarray:
        """Marker positions (markers, 3) m now."""
        return markers_along(self.rope.positions, self.setup.markers)


def run(rope: str = "cosserat", duration: float = 3.0, out: str | Path | None = None,
        setup: Setup | None = None, every: float = 0.01, progress: bool = False,
        motion: tuple | None = None) -> np.ndarray:
    """Run the experiment for ``duration`` s and record the markers every ``every`` s;
    returns rows (time, marker, x, y, z) and writes them to ``out`` (CSV) if given.
    ``motion``: (times, tool positions) replayed instead of the sinusoid."""
    exp = Experiment(rope, setup, motion=motion)
    n = int(round(duration / exp.setup.dt))
    k_every = max(1, int(round(every / exp.setup.dt)))
    rows = []

    def record():
        for i, p in enumerate(exp.markers()):
            rows.append((exp.time, i, *p))

    with progress_bar(f"calibration experiment ({rope})", n, progress) as update:
        record()
        for k in range(1, n + 1):
            exp.step()
            if k % k_every == 0:
                record()
            if k % 50 == 0:
                update(k)
    table = np.array(rows)
    if out is not None:
        write_csv(out, table)
    return table


def write_csv(path: str | Path, table: np.ndarray) -> Path:
    """Rows (time s, marker, x, y, z m) to a CSV file with a header."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time", "marker", "x", "y", "z"])
        for t, i, x, y, z in table:
            w.writerow([f"{t:.6f}", int(i), f"{x:.6f}", f"{y:.6f}", f"{z:.6f}"])
    return path


def marker_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The paper's error per recorded time: the mean marker distance between two runs'
    tables (same times and markers), metres."""
    n = int(a[:, 1].max()) + 1
    da = a[:, 2:5].reshape(-1, n, 3)
    db = b[:, 2:5].reshape(-1, n, 3)
    return np.linalg.norm(da - db, axis=2).mean(axis=1)


__all__ = ["Experiment", "Setup", "marker_error", "markers_along", "resample", "run", "sag_curve",
           "write_csv"]
