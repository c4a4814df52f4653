"""Training tensors from dataset clips: frame vectors, standardised music, style vectors."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import torch

from choreo.datasets import Clip, WindowConfig, WindowedDataset
from choreo.motion import motion_to_vector

from .style import GENRES, canonical_genre, genre_vector


@dataclass
class WindowTensors:
    motion: torch.Tensor  # (N, T, 151) raw frame vectors
    music: torch.Tensor  # (N, T, 35) raw features
    style: torch.Tensor  # (N, S) style vectors (zeros where the genre is unknown)
    has_style: torch.Tensor  # (N,) bool

    def __len__(self) -> int:
        return len(self.motion)


def windows_to_tensors(clips: Sequence[Clip], config: WindowConfig, prompt_kind: str) -> WindowTensors:
    """Every window of ``clips`` as stacked tensors; motion vectors are computed once per clip."""
    motions, musics, styles, has_style = [], [], [], []
    dim = len(GENRES) if prompt_kind == "onehot" else 384
    for clip in clips:
        if clip.features is None:
            continue
        vectors = motion_to_vector(clip.motion)
        genre = canonical_genre(clip.genre) if clip.genre else None
        vector = genre_vector(genre, prompt_kind) if genre else np.zeros(dim, np.float32)
        single = WindowedDataset([clip], config)
        for _, start in single.index:
            stop = start + config.length
            motions.append(vectors[start:stop])
            musics.append(clip.features[start:stop])
            styles.append(vector)
            has_style.append(genre is not None)
    if not motions:
        raise ValueError("no training windows: clips are shorter than a window or have no music")
    return WindowTensors(torch.from_numpy(np.stack(motions)).float(), torch.from_numpy(np.stack(musics)).float(),
                         torch.from_numpy(np.stack(styles)).float(), torch.tensor(has_style))


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
