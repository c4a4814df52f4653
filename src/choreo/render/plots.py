"""Diagnostic plots: music beats against motion beats over time, the root path from above, and the
song's form beside the dance's (bar self-similarities)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import OutputError, ParameterError
from ..fileio import atomic_path
from ..metrics.beats import beat_align_score
from ..motion import Motion
from ..motion.beats import smoothed_speed, speed_minima

PLOTS = ("beats", "path", "form")
PLOT_SUFFIXES = {".png", ".svg", ".pdf"}


def _figure(width: float, height: float, columns: int = 1):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt, *plt.subplots(1, columns, figsize=(width, height), dpi=120)


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


def plot_form(motion: Motion, music, path: Path) -> None:
    """The music's bar self-similarity with its sections (the dance's own form when it carries one,
    else the analysed), and the dance's beside it on the same bars, titled with the form score."""
    from ..metrics.form import bar_similarities, form_score
    from ..music.form import analyse_form, beats_per_bar, music_self_similarity

    per_bar = beats_per_bar(motion.metadata.get("genre") or motion.metadata.get("style"))
    bars, music_alike = music_self_similarity(music, per_bar)
    both = bar_similarities(motion.joint_positions(), bars * motion.fps, music_alike)
    if both is None:
        raise ParameterError("a form plot needs a dance and a song of at least four whole bars")
    dance_alike, music_alike = both
    whole = len(music_alike)
    given = motion.metadata.get("form")
    sections = [(s["start"], s["label"]) for s in given] if given else \
        [(s.start, s.label) for s in analyse_form(music, per_bar).sections]
    plt, figure, panels = _figure(11, 5.2, columns=2)
    starts = np.searchsorted(bars[:whole], [start for start, _ in sections], side="left")
    for panel, alike, title in ((panels[0], music_alike, "music"), (panels[1], dance_alike, "dance")):
        panel.imshow(alike, origin="lower", cmap="magma", interpolation="nearest")
        for bar, (_, label) in zip(starts, sections):
            if bar < whole:
                panel.axvline(bar - 0.5, color="#7fd", linewidth=0.8)
                panel.axhline(bar - 0.5, color="#7fd", linewidth=0.8)
                panel.text(bar - 0.3, whole - 0.7, label, color="white", fontsize=10, va="top", weight="bold")
        panel.set(xlabel="bar", ylabel="bar", title=f"{title}: bar self-similarity")
    figure.suptitle(f"form {', '.join(label for _, label in sections)}; form score "
                    f"{form_score(dance_alike, music_alike):.3f} (1: the dance follows the music's returns)")
    _save(plt, figure, path)


def _save(plt, figure, path: Path) -> None:
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lstrip(".").lower())
    plt.close(figure)


def render_plot(kind: str, motion: Motion, path: str | Path, music=None) -> Path:
    """Draw plot ``kind`` of ``motion`` (and ``music``, a choreo.music.Music, if given) to ``path``."""
    path = Path(path)
    if kind not in PLOTS:
        raise ParameterError(f"unknown plot {kind!r} (use {', '.join(PLOTS)})")
    if path.suffix.lower() not in PLOT_SUFFIXES:
        raise OutputError(f"cannot write a plot to {path.name}: use .png, .svg or .pdf")
    if motion.num_frames < 3:
        raise ParameterError("a plot needs a motion of at least 3 frames")
    if kind == "form":
        if music is None:
            raise ParameterError("--plot form needs the song: give --music")
        plot_form(motion, music, path)
    elif kind == "beats":
        beats = None if music is None else (music.beat_times * motion.fps).round().astype(int)
        plot_beats(motion, beats, path)
    else:
        plot_path(motion, path)
    return path
