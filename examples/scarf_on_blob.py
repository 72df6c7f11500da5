"""A soft scarf-like rope dropped around the neck of a bunny-like mesh standing on the floor.

    python examples/scarf_on_blob.py [--wrap drape|loop] [--out DIR] [--duration S]
                                     [--integrator stable|verlet]

Shows: a procedural triangle mesh (``blob_mesh``) as a static collider next to a ground plane,
a rod laid over it (``--wrap drape``) or a closed ring around its neck (``--wrap loop``,
``Rod.from_points(..., closed=True)``), contact with friction on a curved surface, reading the
reaction force on the mesh (``Collider.force``) and checking it against the rope's weight.
Writes scarf_on_blob[_loop].png, snapshots.png and scarf_on_blob[_loop].npz to --out.
"""

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import trimesh
from matplotlib.colors import LightSource
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial import cKDTree

import deformx as dx
from deformx.engine.geometry.shapes import blob_mesh
from deformx.visual.plots import plot_snapshots

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--wrap", default="drape", choices=("drape", "loop"),
                    help="an open rope draped over the head, or a closed ring around the neck")
parser.add_argument("--out", default="out/scarf_on_blob", help="output directory")
parser.add_argument("--duration", type=float,
                    help="simulated time (s); default 3 (drape), 1 (loop)")
parser.add_argument("--integrator", default="stable", choices=("stable", "verlet"))
args = parser.parse_args()
duration = args.duration or (3.0 if args.wrap == "drape" else 1.0)
out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)
name = "scarf_on_blob" if args.wrap == "drape" else "scarf_on_blob_loop"

# The obstacle: a watertight blob about 20 cm tall (ears included), lowest point at z = 0.
blob_tm = blob_mesh(radius=0.08, subdivisions=4, seed=0)


def surface_gap(tm: trimesh.Trimesh, x: np.ndarray, radius: float) -> float:
    """Smallest distance (m) from the rope's surface to the mesh, negative if it dips in:
    5 samples per segment, exact closest points on the 16 triangles nearest to each."""
    t = np.linspace(0, 1, 5)[:, None, None]
    p = (x[:-1] * (1 - t) + x[1:] * t).reshape(-1, 3)
    _, near = cKDTree(tm.triangles_center).query(p, k=16)
    q = trimesh.triangles.closest_point(tm.triangles[near.ravel()], np.repeat(p, 16, axis=0))
    d = np.linalg.norm(np.repeat(p, 16, axis=0) - q, axis=1).reshape(-1, 16)
    k = d.argmin(axis=1)
    side = np.sign(np.einsum("ij,ij->i", p - q.reshape(-1, 16, 3)[np.arange(len(p)), k],
                             tm.face_normals[near[np.arange(len(p)), k]]))
    return float((side * d.min(axis=1)).min() - radius)


def girth(tm: trimesh.Trimesh, z: float) -> float:
    """Perimeter (m) of the mesh's horizontal cross-section at height z."""
    seg = trimesh.intersections.mesh_plane(tm, (0.0, 0.0, 1.0), (0.0, 0.0, z))
    return float(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).sum())


if args.wrap == "drape":
    # The scarf: 70 elements, 0.7 m, r = 5 mm, soft (E = 0.1 MPa), straight at rest. It starts
    # straight and level, 3 cm above the head, running front to back between the ears. It falls
    # into the valley between the ears, its halves swing down the face and the back to the
    # floor, and it settles draped over the head: the ears keep it from sliding sideways,
    # friction and the weight of both halves (a capstan) keep it from sliding lengthwise.
    scarf = dx.Rod.straight(n_elements=70, start=(0.37, 0.0, 0.21), direction=(-1, 0, 0),
                            normal=(0, 0, 1), length=0.7, radius=0.005, density=600.0,
                            youngs_modulus=1e5, damping=1.0)
else:
    # The girth (cross-section perimeter) shrinks from the body's widest, 0.51 m at z = 7 cm,
    # to 0.36 m at the base of the head (z = 12 cm), then stays at ~0.31 m over head and ears.
    # A closed ring of circumference 0.40 m (R = 64 mm, the smallest that clears head and ears
    # with a few mm to spare) slides down until it is snug at girth 0.40 m, on the shoulders
    # just below the head, and cannot pass the body. The blob has no head wider than its neck:
    # nothing but gravity keeps the ring from being lifted off over the head.
    print("girth (mm) at z = 5, 7, ..., 17 cm:",
          " ".join(f"{girth(blob_tm, z) * 1e3:.0f}" for z in np.arange(0.05, 0.18, 0.02)))
    R, tilt = 0.064, np.radians(10)  # front 10 deg lower than the back, like a scarf
    phi = np.linspace(0, 2 * np.pi, 72, endpoint=False)[:, None]
    ring = R * (np.cos(phi) * [np.cos(tilt), 0, -np.sin(tilt)] + np.sin(phi) * [0, 1, 0])
    # Centre it over the neck (which leans forward, +x) at the height of largest clearance.
    z0 = max(np.arange(0.12, 0.16, 0.0025), key=lambda z: surface_gap(
        blob_tm, np.vstack([ring, ring[:1]]) + [0.01, 0.0, z], 0.005))
    scarf = dx.Rod.from_points(ring + [0.01, 0.0, z0], closed=True, radius=0.005,
                               density=600.0, youngs_modulus=3e5, damping=1.0)

dt = 1e-3 if args.integrator == "stable" else 0.5 * scarf.stable_dt()
world = dx.World(gravity=(0, 0, -9.81), dt=dt, integrator=args.integrator)
world.add_rod(scarf)
world.add_plane(normal=(0, 0, 1), static_friction=0.6, kinetic_friction=0.5)
blob = world.add_mesh(blob_tm, static_friction=0.5, kinetic_friction=0.4)
weight = scarf.mass * 9.81

# Run, sampling the shape every 20 ms and the contact forces after each sample.
recorder = dx.Recorder(world, every=0.02)
t_f, on_blob, on_ground = [0.0], [0.0], [0.0]
wall = time.perf_counter()
while world.time < duration - 1e-9:
    world.run(0.02, recorder=recorder)
    # blob.force: what the rope pushes on the blob. The rope's total contact force minus the
    # blob's share is the ground's (rope-on-rope contact cancels out in the sum).
    t_f.append(world.time)
    on_blob.append(-blob.force[2])
    on_ground.append(world.contact_forces(scarf).sum(axis=0)[2] + blob.force[2])
wall = time.perf_counter() - wall
recorder.save(out / f"{name}.npz")


data = recorder.arrays()
positions = data["rod0_positions"]
if scarf.closed:  # repeat the first node: polylines that close the ring
    positions = np.concatenate([positions, positions[:, :1]], axis=1)
gaps = [surface_gap(blob_tm, x, scarf.radius) for x in positions]
k_back = max(0, len(positions) - 1 - int(round(0.1 / recorder.every)))
settled = np.linalg.norm(positions[-1] - positions[k_back], axis=1).max()  # at rest?
print(f"{world}: {duration:g} s simulated in {wall:.1f} s wall")
print(f"scarf weight {weight:.4f} N; at the end the blob carries {on_blob[-1]:.4f} N and the "
      f"ground {on_ground[-1]:.4f} N (sum {(on_blob[-1] + on_ground[-1]) / weight:.3f} W)")
print(f"closest approach of the rope surface to the blob: {min(gaps) * 1e3:+.2f} mm "
      f"(start {gaps[0] * 1e3:+.2f}, final {gaps[-1] * 1e3:+.2f} mm); largest move in the last "
      f"0.1 s {settled * 1e3:.3f} mm")
print("solver:", world.solver_stats())


def shaded_faces(triangles, base_rgb, light=LightSource(azdeg=225, altdeg=45)):
    """Face colours of a polygon set, Lambert-shaded with a fixed light."""
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return light.shade_normals(normals / np.linalg.norm(normals, axis=1, keepdims=True),
                               fraction=0.8)[:, None] * np.asarray(base_rgb)[None, :]


def tube(x, r, sides=8):
    """Quads (4 corners each) of a tube of radius r around the polyline x (closed if its last
    point repeats its first)."""
    tg = np.gradient(x, axis=0)
    if np.allclose(x[0], x[-1]):  # central differences across the seam too
        tg[[0, -1]] = x[1] - x[-2]
    tg /= np.linalg.norm(tg, axis=1, keepdims=True)
    a = np.cross(tg, [0.0, 0.0, 1.0]) + np.cross(tg, [1.0, 0.0, 0.0]) * 1e-3
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(tg, a)
    ang = np.linspace(0, 2 * np.pi, sides + 1)
    ring = x[:, None] + r * (np.cos(ang)[None, :, None] * a[:, None] + np.sin(ang)[None, :, None] * b[:, None])
    return np.stack([ring[:-1, :-1], ring[1:, :-1], ring[1:, 1:], ring[:-1, 1:]], axis=2).reshape(-1, 4, 3)


# Figure: the blob and the scarf (one polygon set, so the painter's sort hides what is behind)
# at four times, and the vertical contact forces against the rope's weight.
picks = [0.25, 0.6] if args.wrap == "drape" else [0.04, 0.08]
frames = [0, *np.searchsorted(data["time"], picks), len(data["time"]) - 1]
fig = plt.figure(figsize=(13, 7.2))
blob_faces = blob_tm.triangles
blob_colors = shaded_faces(blob_faces, (0.85, 0.82, 0.78))
lo, hi = blob_tm.bounds
for k, f in enumerate(frames):
    ax = fig.add_subplot(2, 4, k + 1, projection="3d")
    quads = tube(positions[f], scarf.radius)
    polys = list(blob_faces) + list(quads)
    colors = np.vstack([blob_colors, shaded_faces(quads[:, :3], (0.75, 0.1, 0.1))])
    ax.add_collection3d(Poly3DCollection(polys, facecolors=colors, edgecolors="none"))
    if args.wrap == "drape":
        ax.set(xlim=(-0.13, 0.13), ylim=(-0.13, 0.13), zlim=(0.0, 0.21), box_aspect=(1, 1, 0.8))
    else:  # closer
        ax.set(xlim=(-0.1, 0.1), ylim=(-0.1, 0.1), zlim=(0.0, 0.2), box_aspect=(1, 1, 1))
    ax.view_init(elev=20 if args.wrap == "drape" else 30, azim=-35)
    ax.set_axis_off()
    ax.set_title(f"t = {data['time'][f]:.2f} s")
ax = fig.add_subplot(2, 1, 2)
ax.plot(t_f, on_blob, label="load on the blob (mesh reaction, -F_z)")
ax.plot(t_f, on_ground, label="load on the ground plane")
ax.plot(t_f, np.add(on_blob, on_ground), "k", lw=0.8, label="sum")
ax.axhline(weight, color="0.4", ls="--", label=f"scarf weight {weight:.3f} N")
ax.set(xlabel="time (s)", ylabel="vertical contact force (N)", ylim=(0, 2.5 * weight))
ax.legend(loc="upper right", fontsize=9)
ax.grid(alpha=0.3)
how = "dropped on" if args.wrap == "drape" else "looped around"
fig.suptitle(f"Scarf {how} a blob mesh ({len(blob_faces)} triangles), {args.integrator} "
             f"integrator, dt = {dt:g} s")
fig.tight_layout()
fig.savefig(out / f"{name}.png", dpi=90)
plot_snapshots(data["time"], [positions], out / "snapshots.png", labels=["scarf"],
               title="scarf on blob: side and top views")
print(f"wrote {out}/{name}.png, snapshots.png and {name}.npz")
