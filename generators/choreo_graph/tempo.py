"""Tempo-density (paper 3.2): a 1-d curve per frame that says how fast the dance moves through
its material, learnt without labels, and predicted from music.

The motion estimator is an autoencoder whose code is split in two: a per-frame tempo-density and
a time-invariant content vector. It is trained on a clip and a randomly time-warped copy of it
(same content, other timing): any pairing of one's content with either's tempo-density must
rebuild the clip whose timing it took (eq. 2), so timing is forced into the curve and out of the
content. The music estimator then learns to predict the curve from 4 s of log-mel (eq. 3).
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from choreo.metrics.beats import motion_beats
from choreo.motion.motion import frames_between

from .config import TempoConfig

DEPTH = 5  # conv and deconv blocks (the paper's five each); time shrinks 32x at the bottleneck


def down_blocks(channels_in: int, width: int) -> nn.Sequential:
    layers, c = [], channels_in
    for _ in range(DEPTH):
        layers += [nn.Conv1d(c, width, 4, stride=2, padding=1), nn.GroupNorm(8, width), nn.GELU()]
        c = width
    return nn.Sequential(*layers)


def up_blocks(width: int, channels_out: int) -> nn.Sequential:
    layers = []
    for _ in range(DEPTH):
        layers += [nn.ConvTranspose1d(width, width, 4, stride=2, padding=1), nn.GroupNorm(8, width), nn.GELU()]
    layers += [nn.Conv1d(width, channels_out, 3, padding=1)]
    return nn.Sequential(*layers)


def padded_length(frames: int) -> int:
    """Sequences are padded to a multiple of 2^DEPTH so down- and up-sampling meet exactly."""
    step = 2**DEPTH
    return -(-frames // step) * step


def pad_time(x: torch.Tensor, length: int) -> torch.Tensor:  # (B, C, T) -> (B, C, length), edge-padded
    return F.pad(x, (0, length - x.shape[-1]), mode="replicate") if x.shape[-1] < length else x


class MotionTempoEstimator(nn.Module):
    """Encoder (transformer layer, conv blocks; deconv blocks -> tempo-density, linears -> content)
    and a decoder that rebuilds the motion from a tempo-density and a content vector."""

    def __init__(self, config: TempoConfig, frames: int, features: int):
        super().__init__()
        w, self.frames, self.length = config.width, frames, padded_length(frames)
        bottleneck = w * self.length // 2**DEPTH
        self.embed = nn.Linear(features, w)
        self.attend = nn.TransformerEncoderLayer(w, config.heads, 2 * w, dropout=0.0, batch_first=True, norm_first=True)
        self.encode = down_blocks(w, w)
        self.tempo_head = up_blocks(w, 1)
        self.content_head = nn.Sequential(nn.Linear(bottleneck, 2 * config.content_dim), nn.GELU(),
                                          nn.Linear(2 * config.content_dim, config.content_dim))
        self.decode_tempo = down_blocks(1, w)
        self.decode_content = nn.Sequential(nn.Linear(config.content_dim, 2 * config.content_dim), nn.GELU(),
                                            nn.Linear(2 * config.content_dim, bottleneck))
        self.decode_up = up_blocks(w, w)
        self.decode_attend = nn.TransformerEncoderLayer(w, config.heads, 2 * w, dropout=0.0, batch_first=True, norm_first=True)
        self.out = nn.Linear(w, features)

    def encode_motion(self, motion: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(B, T, F) -> tempo-density (B, T) and content (B, content_dim)."""
        hidden = self.attend(self.embed(motion)).transpose(1, 2).contiguous()
        hidden = self.encode(pad_time(hidden, self.length))
        tempo = self.tempo_head(hidden)[:, 0, : motion.shape[1]]
        return tempo, self.content_head(hidden.flatten(1))

    def decode(self, tempo: torch.Tensor, content: torch.Tensor) -> torch.Tensor:
        """Tempo-density (B, T) and content (B, D) -> motion (B, T, F)."""
        hidden = self.decode_tempo(pad_time(tempo.unsqueeze(1), self.length))
        hidden = hidden + self.decode_content(content).view_as(hidden)
        hidden = self.decode_up(hidden)[:, :, : tempo.shape[1]].transpose(1, 2).contiguous()
        return self.out(self.decode_attend(hidden))


class MusicTempoEstimator(nn.Module):
    """4 s of log-mel (B, T, n_mels) -> the motion tempo-density a dance to it would have (B, T)."""

    def __init__(self, config: TempoConfig, frames: int, n_mels: int):
        super().__init__()
        w, self.length = config.width, padded_length(frames)
        self.embed = nn.Linear(n_mels, w)
        layer = nn.TransformerEncoderLayer(w, config.heads, 2 * w, dropout=0.0, batch_first=True, norm_first=True)
        self.attend = nn.TransformerEncoder(layer, config.music_layers, enable_nested_tensor=False)
        self.encode = down_blocks(w, w)
        self.decode = up_blocks(w, 1)

    def forward(self, mel: torch.Tensor) -> torch.Tensor:
        hidden = self.attend(self.embed(mel)).transpose(1, 2).contiguous()
        return self.decode(self.encode(pad_time(hidden, self.length)))[:, 0, : mel.shape[1]]


def tempo_autoencoder_loss(model: MotionTempoEstimator, motion: torch.Tensor, warped: torch.Tensor,
                           content_weight: float) -> dict:
    """Eq. 2: rebuild each clip from its own and the other's content, always with its own timing."""
    tempo, content = model.encode_motion(motion)
    tempo_w, content_w = model.encode_motion(warped)
    rebuild = (F.mse_loss(model.decode(tempo, content), motion) + F.mse_loss(model.decode(tempo_w, content_w), warped)
               + F.mse_loss(model.decode(tempo, content_w), motion) + F.mse_loss(model.decode(tempo_w, content), warped))
    same_content = F.mse_loss(content, content_w)
    return {"loss": rebuild + content_weight * same_content, "rebuild": rebuild.detach(), "content": same_content.detach()}


def random_time_warp(positions: np.ndarray, max_shift: int, rng: np.random.Generator) -> np.ndarray:
    """The paper's random time-warper: move some motion beats by a few frames, keep the ends,
    and re-time the frames in between linearly (the content stays, the timing changes)."""
    frames = len(positions)
    beats = motion_beats(positions)
    beats = beats[(beats > max_shift) & (beats < frames - 1 - max_shift)]
    chosen = beats[rng.random(len(beats)) < 0.5]
    moved = chosen + rng.integers(-max_shift, max_shift + 1, len(chosen))
    order = np.argsort(moved)
    source = np.concatenate([[0], chosen[order], [frames - 1]]).astype(np.float64)
    target = np.concatenate([[0], moved[order], [frames - 1]]).astype(np.float64)
    keep = np.concatenate([[True], np.diff(target) > 0]) & np.concatenate([[True], np.diff(source) > 0])
    source_time = np.interp(np.arange(frames), target[keep], source[keep])
    lower, upper, weight = frames_between(source_time, frames)
    weight = weight[:, None, None]
    return (1 - weight) * positions[lower] + weight * positions[upper]
