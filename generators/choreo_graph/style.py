"""Style embedding (paper 3.1): music and motion encoders into one 32-d space, and a beat counter.

The music encoder reads 4 s of log-mel (conv blocks over frequency and time, a GRU over time,
a linear head); the motion encoder reads 4 s of joint positions seen from the excerpt's first
frame (graph-conv blocks over the SMPL tree, a GRU, a linear head). The beat counter predicts how
many motion beats 4 s of this music would carry, from the music's style vector alone.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from choreo.skeleton.smpl import PARENTS

from .config import StyleConfig


def skeleton_adjacency(parents=PARENTS) -> torch.Tensor:
    """Symmetrically normalised adjacency with self-loops, D^-1/2 (A + I) D^-1/2."""
    count = len(parents)
    adjacency = np.eye(count)
    for child, parent in enumerate(parents):
        if parent >= 0:
            adjacency[child, parent] = adjacency[parent, child] = 1.0
    scale = 1.0 / np.sqrt(adjacency.sum(1))
    return torch.tensor(adjacency * scale[:, None] * scale[None, :], dtype=torch.float32)


class ConvBlock(nn.Module):
    """3x3 conv, batch norm, ReLU, then pooling (frequency halves; time halves when asked)."""

    def __init__(self, channels_in: int, channels_out: int, pool_time: bool):
        super().__init__()
        self.body = nn.Sequential(nn.Conv2d(channels_in, channels_out, 3, padding=1), nn.BatchNorm2d(channels_out),
                                  nn.ReLU(), nn.MaxPool2d((2, 2 if pool_time else 1)))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.body(x)


class GraphConvBlock(nn.Module):
    """Spatial graph convolution over the skeleton, then a temporal convolution (ST-GCN style)."""

    def __init__(self, channels_in: int, channels_out: int, stride: int, adjacency: torch.Tensor):
        super().__init__()
        self.register_buffer("adjacency", adjacency, persistent=False)
        self.spatial = nn.Conv2d(channels_in, channels_out, 1)
        self.temporal = nn.Sequential(nn.BatchNorm2d(channels_out), nn.ReLU(),
                                      nn.Conv2d(channels_out, channels_out, (5, 1), (stride, 1), (2, 0)),
                                      nn.BatchNorm2d(channels_out))
        self.skip = nn.Conv2d(channels_in, channels_out, 1, (stride, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:  # (B, C, T, J)
        spatial = torch.einsum("bctj,jk->bctk", self.spatial(x), self.adjacency)
        return torch.relu(self.temporal(spatial) + self.skip(x))


class SequenceHead(nn.Module):
    """GRU over time, then a linear map of its last state to the style vector."""

    def __init__(self, features: int, config: StyleConfig):
        super().__init__()
        self.gru = nn.GRU(features, config.gru_hidden, config.gru_layers, batch_first=True)
        self.out = nn.Linear(config.gru_hidden, config.style_dim)

    def forward(self, sequence: torch.Tensor) -> torch.Tensor:  # (B, T, F)
        _, hidden = self.gru(sequence)
        return self.out(hidden[-1])


class MusicStyleEncoder(nn.Module):
    """(B, T, n_mels) log-mel -> (B, style_dim)."""

    def __init__(self, config: StyleConfig):
        super().__init__()
        channels = (1,) + tuple(config.music_channels)
        self.blocks = nn.Sequential(*(ConvBlock(a, b, pool_time=i < 2) for i, (a, b) in enumerate(zip(channels, channels[1:]))))
        bands = config.n_mels // 2 ** len(config.music_channels)
        self.head = SequenceHead(channels[-1] * bands, config)

    def forward(self, mel: torch.Tensor) -> torch.Tensor:
        x = self.blocks(mel.transpose(1, 2).unsqueeze(1).contiguous())  # (B, C, F', T')
        return self.head(x.flatten(1, 2).transpose(1, 2))


class MotionStyleEncoder(nn.Module):
    """(B, T, J, 3) local joint positions -> (B, style_dim)."""

    def __init__(self, config: StyleConfig):
        super().__init__()
        adjacency = skeleton_adjacency()
        channels = (3,) + tuple(config.motion_channels)
        self.blocks = nn.Sequential(*(GraphConvBlock(a, b, 2 if i < 2 else 1, adjacency)
                                      for i, (a, b) in enumerate(zip(channels, channels[1:]))))
        self.head = SequenceHead(channels[-1], config)

    def forward(self, positions: torch.Tensor) -> torch.Tensor:
        # contiguous: torch 2.13's CPU conv backward corrupts memory on this permuted layout
        x = self.blocks(positions.permute(0, 3, 1, 2).contiguous())  # (B, C, T', J)
        return self.head(x.mean(-1).transpose(1, 2))


class BeatCounter(nn.Module):
    """Four linear layers: a music style vector -> expected motion beats in its 4 s."""

    def __init__(self, config: StyleConfig):
        super().__init__()
        h = config.beat_hidden
        self.net = nn.Sequential(nn.Linear(config.style_dim, h), nn.ReLU(), nn.Linear(h, h), nn.ReLU(),
                                 nn.Linear(h, h // 2), nn.ReLU(), nn.Linear(h // 2, 1))

    def forward(self, style: torch.Tensor) -> torch.Tensor:
        return self.net(style).squeeze(-1)


class StyleModel(nn.Module):
    def __init__(self, config: StyleConfig):
        super().__init__()
        self.config = config
        self.music = MusicStyleEncoder(config)
        self.motion = MotionStyleEncoder(config)
        self.beats = BeatCounter(config)


def style_loss(model: StyleModel, mel: torch.Tensor, positions: torch.Tensor, beat_counts: torch.Tensor) -> dict:
    """Eq. 1 (squared style distance + beat-count error) plus a contrastive term.

    Eq. 1 alone is minimised by encoders that output one constant vector, which would make the
    selector pick at random; the contrastive term (softmax over the batch of negative squared
    distances, the paired clip as the target) keeps unpaired music and motion apart.
    """
    config = model.config
    music_style, motion_style = model.music(mel), model.motion(positions)
    distances = torch.cdist(music_style, motion_style).square()  # (B, B)
    paired = distances.diagonal().mean()
    beats = (model.beats(music_style) - beat_counts).square().mean()
    targets = torch.arange(len(mel))
    contrast = nn.functional.cross_entropy(-distances / config.temperature, targets)
    total = config.style_weight * paired + config.beat_weight * beats + config.contrast_weight * contrast
    with torch.no_grad():
        retrieval = (distances.argmin(1) == targets).float().mean()
    return {"loss": total, "paired": paired.detach(), "beats": beats.detach(), "contrast": contrast.detach(),
            "top1": retrieval}
