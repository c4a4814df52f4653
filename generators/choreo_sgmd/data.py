"""Training tensors from dataset clips: frame vectors, standardised music, style vectors."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Iterator, Sequence

import numpy as np
import torch

from choreo.datasets import Clip, WindowConfig, window_starts
from choreo.errors import ParameterError
from choreo.motion import Motion, mirrored, motion_to_vector, stretched, turned
from choreo.motion.travel import ground_track, track_pace
from choreo.music import FEATURE_DIM, RHYTHM_DIM, rhythm_channels, stretch_features

from .frame_rate import music_at_model_rate
from .style import GENRES, canonical_genre, genre_vector


@dataclass
class WindowTensors:
    motion: torch.Tensor  # (N, T, 151) raw frame vectors
    music: torch.Tensor  # (N, T, 35) raw features
    style: torch.Tensor  # (N, S) style vectors (zeros where the genre is unknown)
    has_style: torch.Tensor  # (N,) bool
    genres: tuple[str | None, ...] = ()  # (N,) each window's genre, for genre-balanced sampling
    pace: torch.Tensor | None = None  # (N,) each window's pace along its ground track, m/s (a pace condition)

    def __len__(self) -> int:
        return len(self.motion)

    def sampling_weights(self, balance: float) -> torch.Tensor | None:
        """Per-window draw weights proportional to (windows of its genre)^-balance; None for 0.

        balance 1 draws every genre equally often; 0.5 halves the gap in log share. M2D's waltz
        (60 % of the windows, captured at 5.9 fps and interpolated) is the case it is for.
        """
        if not balance or len(self.genres) != len(self):
            return None  # uniform draws (windows made without genres, e.g. synthetic ones)
        counts = Counter(self.genres)
        return torch.tensor([counts[g] ** -balance for g in self.genres], dtype=torch.float64)


@dataclass(frozen=True)
class Augmentation:
    """Copies of each training clip a real dancer could have danced: faster, slower, facing
    another way and, for styles without a handedness, mirrored (not ballroom: docs/sgmd.md)."""

    mirror: bool = False
    stretch: tuple[float, ...] = (1.0,)  # pace factors; music features are stretched along
    turns: tuple[float, ...] = (0.0,)  # facings in degrees about the vertical; 0 is the dance as captured

    def __post_init__(self):
        if not self.stretch or any(not 0.5 <= f <= 2.0 for f in self.stretch):
            raise ParameterError(f"stretch factors must be within [0.5, 2], got {self.stretch}")
        if not self.turns or any(not -360.0 <= t <= 360.0 for t in self.turns):
            raise ParameterError(f"turns must be angles within [-360, 360] degrees, got {self.turns}")

    def variants(self, motion: Motion, features: np.ndarray) -> Iterator[tuple[Motion, np.ndarray]]:
        for factor in self.stretch:
            paced = (motion, features) if factor == 1.0 else (stretched(motion, factor), stretch_features(features, factor))
            for copy in (paced[0], mirrored(paced[0])) if self.mirror else (paced[0],):
                for degrees in self.turns:
                    yield (copy if degrees == 0.0 else turned(copy, degrees)), paced[1]


def music_input(features: np.ndarray, music_dim: int) -> np.ndarray:
    """What a model with ``music_dim`` inputs reads: the 35-d features, plus the rhythm channels
    (beat phase, tempo) for models trained with them (music_dim 38)."""
    if music_dim == FEATURE_DIM:
        return features
    if music_dim == FEATURE_DIM + RHYTHM_DIM:
        return np.concatenate([features, rhythm_channels(features)], axis=1)
    raise ParameterError(f"a model reading {music_dim}-d music is not one choreo knows how to feed")


def windows_to_tensors(clips: Sequence[Clip], config: WindowConfig, prompt_kind: str,
                       music_dim: int = FEATURE_DIM, augmentation: Augmentation = Augmentation(),
                       frame_stride: int = 1) -> WindowTensors:
    """Every window of ``clips`` (and of their augmented copies) as stacked tensors; motion
    vectors are computed once per clip and copy; rhythm channels per window, as scoring sees them.
    ``frame_stride``: windows at the model's frame rate (every stride-th frame; frame_rate.py).
    Each window's pace is measured on the whole clip's ground track, so its ends are not filter edges."""
    motions, musics, styles, has_style, genres, paces = [], [], [], [], [], []
    dim = len(GENRES) if prompt_kind == "onehot" else 384
    for clip in clips:
        if clip.features is None:
            continue
        genre = canonical_genre(clip.genre) if clip.genre else None
        vector = genre_vector(genre, prompt_kind) if genre else np.zeros(dim, np.float32)
        for motion, features in augmentation.variants(clip.motion, clip.features):
            vectors = motion_to_vector(motion)
            track = ground_track(motion.root_positions, motion.fps)
            for start in window_starts(len(vectors), config):
                stop = start + config.length
                motions.append(vectors[start:stop:frame_stride])
                musics.append(music_at_model_rate(music_input(features[start:stop], music_dim), frame_stride))
                styles.append(vector)
                has_style.append(genre is not None)
                genres.append(genre)
                paces.append(track_pace(track[start:stop], motion.fps))
    if not motions:
        raise ValueError("no training windows: clips are shorter than a window or have no music")
    return WindowTensors(torch.from_numpy(np.stack(motions)).float(), torch.from_numpy(np.stack(musics)).float(),
                         torch.from_numpy(np.stack(styles)).float(), torch.tensor(has_style), tuple(genres),
                         torch.tensor(paces, dtype=torch.float32))


@dataclass
class MusicScaler:
    """Standardises music features (MFCCs reach the hundreds, one-hots are 0/1)."""

    mean: torch.Tensor
    std: torch.Tensor

    @classmethod
    def fit(cls, music: torch.Tensor) -> "MusicScaler":
        flat = music.reshape(-1, music.shape[-1])
        return cls(flat.mean(0), flat.std(0).clamp(min=1e-3))

    def __call__(self, music: torch.Tensor) -> torch.Tensor:
        return (music - self.mean) / self.std

    def to(self, device) -> "MusicScaler":
        return MusicScaler(self.mean.to(device), self.std.to(device))

    def state_dict(self) -> dict:
        return {"mean": self.mean, "std": self.std}

    @classmethod
    def from_state_dict(cls, state: dict) -> "MusicScaler":
        return cls(state["mean"], state["std"])
