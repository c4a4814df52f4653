"""Sampling dances of any length: overlapping 5 s windows denoised together and kept consistent.

Every window overlaps the next by half. After each denoising step but the last, the first half of
window i is overwritten with the second half of window i-1 (EDGE's long-form scheme), so the
windows denoise towards agreement; the final predictions are cross-faded over each overlap. The
network runs over the windows in chunks, so its activations do not grow with the song.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import torch

from .schedule import NoiseSchedule, guided_x0, make_sampler


@dataclass(frozen=True)
class SamplingOptions:
    steps: int = 50  # network evaluations per window (DDIM); 1000 for DDPM
    guidance: float = 2.0  # classifier-free guidance weight w on music (paper eq. 6)
    sampler: str = "ddim"
    eta: float = 1.0  # DDIM stochasticity: 1 as EDGE samples, 0 deterministic
    seed: int = 0
    chunk_windows: int = 32  # windows per network call


def window_starts(num_frames: int, window: int) -> list[int]:
    hop = window // 2
    starts = [0]
    while starts[-1] + window < num_frames:
        starts.append(starts[-1] + hop)
    return starts


def windowed(features: torch.Tensor, starts: list[int], window: int) -> torch.Tensor:
    """(T, C) -> (N, window, C), zero-padded past the end."""
    padded_length = starts[-1] + window
    padded = torch.zeros(padded_length, features.shape[-1], dtype=features.dtype)
    padded[: len(features)] = features
    return torch.stack([padded[s: s + window] for s in starts])


def stitch(windows: torch.Tensor, num_frames: int) -> torch.Tensor:
    """(N, W, D) half-overlapping windows -> (num_frames, D), cross-faded linearly over each overlap.

    In the 6D rotation channels a linear blend of two nearby rotations followed by Gram-Schmidt
    (when the vector becomes a Motion) is a normalised lerp: the slerp of close rotations.
    """
    window = windows.shape[1]
    hop = window // 2
    ramp = ((torch.arange(hop, dtype=windows.dtype) + 0.5) / hop)[:, None]
    out = [windows[0][: window - hop]]
    for previous, current in zip(windows[:-1], windows[1:]):
        out.append((1 - ramp) * previous[window - hop:] + ramp * current[:hop])
        out.append(current[hop: window - hop])
    out.append(windows[-1][hop:])
    return torch.cat(out)[:num_frames]


@torch.no_grad()
def sample_long(model, schedule: NoiseSchedule, music: torch.Tensor, style: torch.Tensor, keep_style: bool,
                frame_dim: int, window: int, options: SamplingOptions,
                progress: Callable[[float], None] | None = None) -> tuple[torch.Tensor, int]:
    """Normalised x0 (T, frame_dim) for standardised music (T, 35); returns it and the network evaluations."""
    num_frames = len(music)
    starts = window_starts(num_frames, window)
    music_windows = windowed(music, starts, window)
    count, hop = len(starts), window // 2
    generator = torch.Generator().manual_seed(options.seed)
    x = torch.randn((count, window, frame_dim), generator=generator)
    styles = style.expand(count, -1)
    keep = torch.full((count,), keep_style, dtype=torch.bool)
    sampler = make_sampler(options.sampler, schedule, options.steps, options.eta)
    evaluations = 0
    for i, t in enumerate(sampler.timesteps.tolist()):
        predictions = []
        for first in range(0, count, options.chunk_windows):
            part = slice(first, first + options.chunk_windows)
            predictions.append(guided_x0(_StyleMask(model, keep[part]), x[part], t, music_windows[part], styles[part],
                                         options.guidance))
            evaluations += 1 if options.guidance == 1.0 else 2
        x = sampler.step(torch.cat(predictions), t, x, generator).prev_sample
        if i + 1 < len(sampler.timesteps):  # the final x0s are cross-faded by stitch() instead
            x[1:, :hop] = x[:-1, window - hop:]
        if progress:
            progress((i + 1) / len(sampler.timesteps))
    return stitch(x, num_frames), evaluations


class _StyleMask:
    """The model with keep_style fixed (guidance only drops music; style stays as given)."""

    def __init__(self, model, keep_style: torch.Tensor):
        self.model, self.keep_style = model, keep_style

    def __call__(self, x_t, t, music, style, keep_music=None):
        keep_style = self.keep_style.repeat(len(x_t) // len(self.keep_style))
        return self.model(x_t, t, music, style, keep_music=keep_music, keep_style=keep_style)


@torch.no_grad()
def sample_independent(model, schedule: NoiseSchedule, music: torch.Tensor, styles: torch.Tensor,
                       keep_style: torch.Tensor, frame_dim: int, options: SamplingOptions) -> torch.Tensor:
    """Normalised x0 (N, W, frame_dim) for N unrelated windows (N, W, 35): how papers score 5 s clips."""
    generator = torch.Generator().manual_seed(options.seed)
    x = torch.randn((*music.shape[:2], frame_dim), generator=generator)
    sampler = make_sampler(options.sampler, schedule, options.steps, options.eta)
    for t in sampler.timesteps.tolist():
        predictions = [guided_x0(_StyleMask(model, keep_style[part]), x[part], t, music[part], styles[part], options.guidance)
                       for part in (slice(i, i + options.chunk_windows) for i in range(0, len(x), options.chunk_windows))]
        x = sampler.step(torch.cat(predictions), t, x, generator).prev_sample
    return x
