"""Training and repertoire inputs cut from dataset clips: positions seen from each excerpt's
first frame, the log-mel under them, and their motion-beat counts."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from choreo.datasets import Clip, WindowConfig, window_starts
from choreo.metrics.beats import motion_beats
from choreo.motion.stitch import local_positions

from .config import FPS


def excerpt_starts(num_frames: int, length: int, stride: int) -> list[int]:
    """Start frames of every full ``length``-frame excerpt, ``stride`` frames apart (the datasets' windowing)."""
    return window_starts(num_frames, WindowConfig(seconds=length / FPS, stride_seconds=stride / FPS, fps=FPS))


def beat_count(positions: np.ndarray) -> int:
    return len(motion_beats(positions))


@dataclass
class Excerpts:
    """Paired excerpts of equal length: positions (N, T, J, 3) local to their first frame,
    log-mel (N, T, n_mels), motion-beat counts (N,) and where each came from."""

    positions: np.ndarray
    mel: np.ndarray
    beats: np.ndarray
    sources: list[tuple[str, int]]
    genres: list[str | None]

    def __len__(self) -> int:
        return len(self.positions)


def paired_excerpts(clips: Sequence[Clip], length: int, stride: int, mels: dict[str, np.ndarray]) -> Excerpts:
    positions, mel, beats, sources, genres = [], [], [], [], []
    for clip in clips:
        if clip.name not in mels:
            continue
        world = clip.motion.joint_positions().astype(np.float32)
        for start in excerpt_starts(clip.motion.num_frames, length, stride):
            piece = world[start : start + length]
            positions.append(local_positions(piece).astype(np.float32))
            mel.append(mels[clip.name][start : start + length])
            beats.append(beat_count(piece))
            sources.append((clip.name, start))
            genres.append(clip.genre)
    if not positions:
        raise ValueError(f"no clip with audio is {length} frames long")
    return Excerpts(np.stack(positions), np.stack(mel), np.array(beats, np.float32), sources, genres)
