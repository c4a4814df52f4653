"""Diagnostic plots: music beats against motion beats over time, and the root path from above."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import OutputError, ParameterError
from ..fileio import atomic_path
from ..metrics.beats import beat_align_score
from ..motion import Motion
from ..motion.beats import smoothed_speed, speed_minima

PLOTS = ("beats", "path")
PLOT_SUFFIXES = {".png", ".svg", ".pdf"}


def _figure(width: float, height: float):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt, *plt.subplots(figsize=(width, height), dpi=120)


def plot_beats(motion: Motion, music_beat_frames: np.ndarray | None, path: Path) -> None:
    """Smoothed joint speed with its minima (motion beats) and the music's beats as lines."""
    plt, figure, axes = _figure(10, 3.2)
    positions = motion.joint_positions()
    per_frame = smoothed_speed(positions)
    speed, time = per_frame * motion.fps, np.arange(len(per_frame)) / motion.fps
    dance_beats = speed_minima(per_frame)
    axes.plot(time, speed, color="#3a6fd8", linewidth=1.4, label="mean joint speed (m/s)")
    axes.plot(dance_beats / motion.fps, speed[dance_beats], "o", color="#eb802a", markersize=4, label="motion beats")
    title = "motion beats"
    if music_beat_frames is not None and len(music_beat_frames):
        for i, frame in enumerate(music_beat_frames):
            axes.axvline(frame / motion.fps, color="#888", linewidth=0.8, alpha=0.6, label="music beats" if i == 0 else None)
        title = f"BeatAlign {beat_align_score(music_beat_frames, dance_beats):.3f}"
    axes.set(xlabel="time (s)", ylabel="speed (m/s)", title=title, xlim=(0, time[-1] if len(time) else 1))
    axes.legend(loc="upper right", fontsize=8)
    _save(plt, figure, path)


def plot_path(motion: Motion, path: Path) -> None:
    """The root's floor path seen from above, coloured by time."""
    plt, figure, axes = _figure(5.5, 5.5)
    x, z = motion.root_positions[:, 0], motion.root_positions[:, 2]
    time = np.arange(motion.num_frames) / motion.fps
    travel = np.linalg.norm(np.diff(motion.root_positions[:, [0, 2]], axis=0), axis=1).sum()
    points = axes.scatter(x, z, c=time, s=4, cmap="viridis")
    axes.plot(x[0], z[0], "o", color="#2a2", label="start")
    axes.plot(x[-1], z[-1], "s", color="#c22", label="end")
    axes.set(xlabel="x (m)", ylabel="z (m)", title=f"root path from above, {travel:.1f} m travelled")
    axes.set_aspect("equal", adjustable="datalim")
    axes.grid(alpha=0.3)
    axes.legend(loc="best", fontsize=8)
    figure.colorbar(points, ax=axes, label="time (s)", shrink=0.8)
    _save(plt, figure, path)


def _save(plt, figure, path: Path) -> None:
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lstrip(".").lower())
    plt.close(figure)


def render_plot(kind: str, motion: Motion, path: str | Path, music_beat_frames: np.ndarray | None = None) -> Path:
    path = Path(path)
    if kind not in PLOTS:
        raise ParameterError(f"unknown plot {kind!r} (use {' or '.join(PLOTS)})")
    if path.suffix.lower() not in PLOT_SUFFIXES:
        raise OutputError(f"cannot write a plot to {path.name}: use .png, .svg or .pdf")
    if motion.num_frames < 3:
        raise ParameterError("a plot needs a motion of at least 3 frames")
    (plot_beats(motion, music_beat_frames, path) if kind == "beats" else plot_path(motion, path))
    return path
