"""Rope calibration: fit a rope model's parameters to recorded markers by replaying the
recorded tool motion (the paper's calibration, its error = mean marker distance over time).

With the rope's ends driven kinematically the motion depends on E / rho, not on each: the
density is an input (measured mass per length), and the fit finds Young's modulus and the
damping (``rope="cosserat"``: the rod's damping, 1/s; ``rope="capsule"``: the ball joints'
spring E I / l through ``youngs_modulus`` and their damping ``capsule_damping``, N m s/rad).
CMA-ES (``cma``) searches the logarithms of the parameters within bounds.

Files: markers CSV as :func:`deformx.apps.calibration.write_csv` writes them (time, marker,
x, y, z); motion CSV (time, x, y, z) of the tool tip, as :func:`write_motion` writes them.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..errors import SimulationDiverged
from . import calibration as cal

FITTED = {"cosserat": ("youngs_modulus", "damping"),
          "capsule": ("youngs_modulus", "capsule_damping")}
BOUNDS = {"youngs_modulus": (1e3, 1e9), "damping": (1e-4, 10.0),
          "capsule_damping": (1e-5, 1.0)}


@dataclass
class FitResult:
    """Fitted ``parameters``, the mean marker error ``error`` (m) and its course over
    ``times`` (``errors``), and every evaluation (parameters, error)."""

    parameters: dict
    error: float
    times: np.ndarray
    errors: np.ndarray
    evaluations: list = field(default_factory=list)


def read_markers(path: str | Path) -> np.ndarray:
    """Rows (time, marker, x, y, z) of a markers CSV."""
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if table.shape[1] != 5:
        raise ValueError(f"{path}: expected columns time, marker, x, y, z; got "
                         f"{table.shape[1]} columns")
    return table


def write_motion(path: str | Path, times: np.ndarray, positions: np.ndarray) -> Path:
    """The tool tip's path: rows (time s, x, y, z m)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time", "x", "y", "z"])
        for t, p in zip(times, positions):
            w.writerow([f"{t:.6f}", *(f"{v:.6f}" for v in p)])
    return path


def read_motion(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if data.shape[1] != 4:
        raise ValueError(f"{path}: expected columns time, x, y, z; got {data.shape[1]} columns")
    return data[:, 0], data[:, 1:]


def tool_motion(setup: cal.Setup, duration: float, every: float = 0.01
                ) -> tuple[np.ndarray, np.ndarray]:
    """The setup's sinusoidal tool path sampled every ``every`` s (a robot log stands in)."""
    exp_t = np.arange(0.0, duration + 0.5 * every, every)
    w = 2.0 * math.pi * setup.frequency
    pos = np.tile(np.asarray(setup.start, dtype=float), (len(exp_t), 1))
    pos[:, 2] += setup.amplitude * np.sin(w * exp_t)
    return exp_t, pos


def simulate(rope: str, setup: cal.Setup, motion: tuple, times: np.ndarray) -> np.ndarray:
    """Marker table of the model replaying ``motion``, recorded at ``times``."""
    every = float(np.median(np.diff(times))) if len(times) > 1 else setup.dt
    return cal.run(rope, duration=float(times[-1]), setup=setup, every=every, motion=motion)


def calibrate(markers: np.ndarray, motion: tuple, rope: str = "cosserat",
              setup: cal.Setup | None = None, start: dict | None = None,
              max_evals: int = 60, sigma: float = 0.5, seed: int = 0,
              progress: bool = False) -> FitResult:
    """Fit ``FITTED[rope]`` so that the model's markers follow ``markers`` (rows time,
    marker, x, y, z) when the tool replays ``motion`` (times, positions). ``setup`` gives
    everything else (density, geometry, the rope's initial shape); ``start``: initial
    parameters (default the setup's)."""
    try:
        import cma
    except ImportError as err:  # pragma: no cover - the [learn] extra
        raise ImportError("calibration needs cma: python -m pip install 'deformx[learn]'"
                          ) from err

    from ..engine.running import progress_bar

    if rope not in FITTED:
        raise ValueError(f"rope must be one of {tuple(FITTED)}, got {rope!r}")
    setup = setup or cal.Setup()
    names = FITTED[rope]
    n_markers = int(markers[:, 1].max()) + 1
    if n_markers != setup.markers:
        setup = replace(setup, markers=n_markers)
    times = markers[::n_markers, 0]
    x0 = np.array([math.log((start or {}).get(k, getattr(setup, k))) for k in names])
    lo = np.array([math.log(BOUNDS[k][0]) for k in names])
    hi = np.array([math.log(BOUNDS[k][1]) for k in names])
    evaluations: list = []

    def error(x: np.ndarray) -> float:
        params = {k: float(math.exp(v)) for k, v in zip(names, x)}
        try:
            sim = simulate(rope, replace(setup, **params), motion, times)
            e = float(cal.marker_error(sim, markers[: len(sim)]).mean()) if len(sim) == len(
                markers) else float("inf")
        except SimulationDiverged:  # a diverged trial is a bad trial, not the end of the fit
            e = float("inf")
        evaluations.append((params, e))
        return e if math.isfinite(e) else 1e3

    es = cma.CMAEvolutionStrategy(x0, sigma, {"bounds": [lo.tolist(), hi.tolist()],
                                              "maxfevals": max_evals, "seed": seed + 1,
                                              "verbose": -9, "popsize": 6})
    with progress_bar(f"calibrating the {rope} rope", max_evals, progress) as update:
        while not es.stop():
            xs = es.ask()
            es.tell(xs, [error(x) for x in xs])
            update(len(evaluations))
    best = min(evaluations, key=lambda pe: pe[1])[0]
    sim = simulate(rope, replace(setup, **best), motion, times)
    errors = cal.marker_error(sim, markers)
    return FitResult(best, float(errors.mean()), times, errors, evaluations)


def plot_fit(result: FitResult, png: str | Path, initial: np.ndarray | None = None) -> Path:
    """Marker error over time of the fitted model (and of the initial one), as in the
    paper's calibration figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3))
    if initial is not None:
        ax.plot(result.times, 100 * initial, label="before the fit", color="0.6")
    label = ", ".join(f"{k} {v:.3g}" for k, v in result.parameters.items())
    ax.plot(result.times, 100 * result.errors, label=f"fitted ({label})")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("mean marker error (cm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return Path(png)
