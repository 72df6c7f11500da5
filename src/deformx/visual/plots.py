"""Plots and videos of recorded rod trajectories.

Plain functions over the arrays a :class:`deformx.Recorder` writes (``time`` of shape
``(T,)`` and ``rod{i}_positions`` of shape ``(T, n_i + 1, 3)``); nothing here imports the
engine. Everything renders with matplotlib's non-interactive Agg backend, so it works on
machines without a display.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

__all__ = [
    "rods_from_record",
    "load_record",
    "plot_snapshots",
    "write_video",
]

_ROD_KEY = re.compile(r"^rod(\d+)_positions$")

# One (x, y) axis pair per panel: side view x-z and top view x-y.
_VIEWS = (("side view (x-z)", 0, 2, "z [m]"), ("top view (x-y)", 0, 1, "y [m]"))


def _figure(figsize, dpi):
    # Build a figure on the Agg canvas directly: no pyplot, so no global backend state is
    # touched and nothing tries to open a window.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def rods_from_record(record: Mapping[str, np.ndarray]) -> list[np.ndarray]:
    """Return the per-rod position arrays ``(T, n_i + 1, 3)`` of a record, ordered by rod index."""
    found = []
    for key in record.keys():
        m = _ROD_KEY.match(key)
        if m:
            found.append((int(m.group(1)), key))
    found.sort()
    return [np.asarray(record[key], dtype=float) for _, key in found]


def load_record(path: str | Path) -> tuple[np.ndarray, list[np.ndarray]]:
    """Load ``(time, [positions per rod])`` from a recorder ``.npz`` file."""
    with np.load(Path(path)) as data:
        time = np.asarray(data["time"], dtype=float)
        rods = rods_from_record(data)
    return time, rods


def _checked_record(time, rods, caller: str) -> tuple[np.ndarray, list[np.ndarray], int]:
    """Arrays of a record and its usable frame count; ValueError if it has no rods or frames."""
    time = np.asarray(time, dtype=float)
    rods = [np.asarray(r, dtype=float) for r in rods]
    if not rods:
        raise ValueError(f"{caller}: no rods to plot (expected at least one rod{{i}}_positions array)")
    n_frames = min(len(time), *(len(r) for r in rods))
    if n_frames == 0:
        raise ValueError(f"{caller}: the record has no frames")
    return time, rods, n_frames


def _snapshot_indices(n_frames: int, n_snapshots: int) -> np.ndarray:
    if n_frames <= 0:
        return np.zeros(0, dtype=int)
    n = max(1, min(n_snapshots, n_frames))
    return np.unique(np.linspace(0, n_frames - 1, n).round().astype(int))


def _bounds(rods: Sequence[np.ndarray], planes_z: Sequence[float] = ()) -> np.ndarray:
    """Axis-aligned bounds ``(2, 3)`` of all rods over all frames, padded a little."""
    pts = np.concatenate([r.reshape(-1, 3) for r in rods], axis=0)
    finite = pts[np.all(np.isfinite(pts), axis=1)]
    if finite.size == 0:
        finite = np.zeros((1, 3))
    lo, hi = finite.min(axis=0), finite.max(axis=0)
    for z in planes_z:
        lo[2] = min(lo[2], z)
        hi[2] = max(hi[2], z)
    span = np.maximum(hi - lo, 1e-3)
    pad = 0.05 * span.max()
    return np.stack([lo - pad, hi + pad])


def _style_view(ax, name, ylabel, bounds, i, j, ground_z) -> None:
    """Title, labels, limits, grid and (in side views) the ground line of one view."""
    if ground_z is not None and j == 2:
        ax.axhline(ground_z, color="0.4", lw=1.0, ls="--")
    _set_limits(ax, bounds, i, j)
    ax.set_title(name)
    ax.set_xlabel("x [m]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)


def _set_limits(ax, bounds, i, j):
    """Cover ``bounds`` in axes (i, j) with equal aspect, growing the shorter axis."""
    lo, hi = bounds
    # Invisible corner points give autoscaling the extent; adjustable="datalim" then widens
    # whichever axis needs it so shapes are not distorted.
    ax.plot([lo[i], hi[i]], [lo[j], hi[j]], alpha=0.0)
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()


def _freeze_limits(axes):
    """Fix the current (aspect-adjusted) limits so that changing line data moves nothing."""
    for ax in axes:
        ax.apply_aspect()
        xlim, ylim = ax.get_xlim(), ax.get_ylim()
        ax.set_autoscale_on(False)
        ax.set_aspect("auto")
        ax.set_xlim(xlim)
        ax.set_ylim(ylim)


def plot_snapshots(
    time: np.ndarray,
    rods: Sequence[np.ndarray],
    path: str | Path,
    *,
    n_snapshots: int = 6,
    title: str | None = None,
    ground_z: float | None = 0.0,
    labels: Sequence[str] | None = None,
    dpi: int = 120,
) -> Path:
    """Write a PNG with a side view (x-z) and a top view (x-y) of the rods.

    A few snapshots are drawn thin and colored by time (viridis); the final shape is drawn
    thick on top. ``ground_z`` draws a ground line in the side view (``None`` for none).
    Returns the path written.
    """
    import matplotlib
    from matplotlib import cm, colors

    time, rods, n_frames = _checked_record(time, rods, "plot_snapshots")
    idx = _snapshot_indices(n_frames, n_snapshots)
    t0, t1 = float(time[0]), float(time[n_frames - 1])
    norm = colors.Normalize(vmin=t0, vmax=t1 if t1 > t0 else t0 + 1e-12)
    cmap = matplotlib.colormaps["viridis"]

    bounds = _bounds([r[:n_frames] for r in rods], () if ground_z is None else (ground_z,))
    fig = _figure((11, 4.8), dpi)
    axes = fig.subplots(1, 2)
    rod_colors = [f"C{k % 10}" for k in range(len(rods))]
    for ax, (name, i, j, ylabel) in zip(axes, _VIEWS):
        for k, r in enumerate(rods):
            for f in idx[:-1]:
                ax.plot(r[f, :, i], r[f, :, j], color=cmap(norm(time[f])), lw=0.9, alpha=0.75)
            last = r[n_frames - 1]
            label = labels[k] if labels is not None and k < len(labels) else f"rod {k}"
            ax.plot(last[:, i], last[:, j], color=rod_colors[k], lw=2.4, label=label if i == 0 and j == 2 else None)
            ax.plot(last[0, i], last[0, j], "o", color=rod_colors[k], ms=3)
        _style_view(ax, name, ylabel, bounds, i, j, ground_z)
    if len(rods) <= 10:
        axes[0].legend(loc="best", fontsize=8)
    sm = cm.ScalarMappable(norm=norm, cmap=cmap)
    sm.set_array([])
    cbar = fig.colorbar(sm, ax=list(axes), fraction=0.03, pad=0.02)
    cbar.set_label("snapshot time [s] (thick: final)")
    if title:
        fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def write_video(
    time: np.ndarray,
    rods: Sequence[np.ndarray],
    path: str | Path,
    *,
    fps: float | None = None,
    title: str | None = None,
    ground_z: float | None = 0.0,
    labels: Sequence[str] | None = None,
    size: tuple[int, int] = (960, 480),
    max_frames: int | None = None,
) -> Path:
    """Write an MP4 (H.264 via imageio-ffmpeg) with side and top views of every frame.

    ``fps`` defaults to real time (one video second per simulated second, at most 60 fps).
    ``size`` is the frame size in pixels; both must be multiples of 16 for the codec.
    Returns the path written.
    """
    import imageio.v2 as imageio

    time, rods, n_frames = _checked_record(time, rods, "write_video")
    frames = np.arange(n_frames)
    if max_frames is not None and n_frames > max_frames:
        frames = np.unique(np.linspace(0, n_frames - 1, max_frames).round().astype(int))
    if fps is None:
        if len(frames) > 1 and time[frames[-1]] > time[frames[0]]:
            fps = (len(frames) - 1) / (time[frames[-1]] - time[frames[0]])
        else:
            fps = 30.0
    fps = float(min(max(fps, 1.0), 60.0))
    width, height = size
    if width % 16 or height % 16:
        raise ValueError(f"write_video: size must be multiples of 16 pixels, got {size}")

    dpi = 80
    fig = _figure((width / dpi, height / dpi), dpi)
    axes = fig.subplots(1, 2)
    bounds = _bounds([r[:n_frames] for r in rods], () if ground_z is None else (ground_z,))
    lines = []
    for ax, (name, i, j, ylabel) in zip(axes, _VIEWS):
        row = []
        for k, r in enumerate(rods):
            (ln,) = ax.plot(r[0, :, i], r[0, :, j], color=f"C{k % 10}", lw=2.0, animated=True)
            row.append(ln)
        lines.append(row)
        if j == 2 and labels is not None and len(rods) <= 10:
            # proxy handles: the animated lines themselves are not drawn in the background
            from matplotlib.lines import Line2D

            handles = [Line2D([], [], color=f"C{k % 10}", lw=2.0) for k in range(len(rods))]
            ax.legend(handles, [str(x) for x in labels][: len(rods)], loc="upper right", fontsize=8)
        _style_view(ax, name, ylabel, bounds, i, j, ground_z)
    stamp = fig.text(0.01, 0.97, "", ha="left", va="top", family="monospace", animated=True)
    if title:
        fig.suptitle(title)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    _freeze_limits(axes)
    # Blitting: draw the static parts (axes, ticks, grid, titles) once, then per frame
    # restore that background and draw only the animated lines and the time stamp.
    canvas = fig.canvas
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = imageio.get_writer(
        str(path), fps=fps, codec="libx264", quality=7, macro_block_size=16,
        pixelformat="yuv420p", ffmpeg_log_level="error",
    )
    try:
        for f in frames:
            canvas.restore_region(background)
            for ax, (name, i, j, _), row in zip(axes, _VIEWS, lines):
                for ln, r in zip(row, rods):
                    ln.set_data(r[f, :, i], r[f, :, j])
                    ax.draw_artist(ln)
            stamp.set_text(f"t = {time[f]:7.3f} s")
            fig.draw_artist(stamp)
            rgba = np.asarray(canvas.buffer_rgba())
            writer.append_data(np.ascontiguousarray(rgba[:height, :width, :3]))
    finally:
        writer.close()
    return path
