"""A clamped cable sagging under its own weight, compared with linear beam theory.

    python examples/cantilever_sag.py        # writes cantilever_sag.png

Shows: building a rod with physical parameters, clamping an end, damping to equilibrium,
reading positions and energies.
"""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import deformx as dx

L, r, rho, E = 1.0, 0.1, 1000.0, 2e6  # m, m, kg/m^3, Pa (a soft, thick rubber rod)
for n in (10, 25, 100):
    rod = dx.Rod.straight(n_elements=n, start=(0, 0, 0), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=L, radius=r, density=rho, youngs_modulus=E, damping=14.0)
    world = dx.World(gravity=(0, 0, -9.81), dt=rod.stable_dt())
    world.add_rod(rod)
    rod.fix_start()
    world.run(3.0, progress=True)  # damped to rest
    plt.plot(rod.positions[:, 0], rod.positions[:, 2], "o-", ms=3, label=f"DeformX, n = {n}")
    print(f"n = {n:3d}: tip at x = {rod.positions[-1, 0]:.4f} m, z = {rod.positions[-1, 2]:.4f} m, "
          f"bending energy {rod.elastic_energy()['bend']:.4f} J")

# Linear Euler-Bernoulli cantilever under a uniform load w: z = -w x^2 (6L^2 - 4Lx + x^2) / (24 EI).
w = rho * np.pi * r**2 * 9.81
EI = E * np.pi * r**4 / 4
x = np.linspace(0, L, 100)
plt.plot(x, -w * x**2 * (6 * L**2 - 4 * L * x + x**2) / (24 * EI), "k--", label="linear beam theory")
plt.axis("equal")
plt.xlabel("x (m)")
plt.ylabel("z (m)")
plt.legend()
plt.title("Cantilever under its own weight (large deflection: the tip also pulls back)")
plt.savefig("cantilever_sag.png", dpi=120)
print("wrote cantilever_sag.png")
