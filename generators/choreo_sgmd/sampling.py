"""Sampling dances of any length: overlapping 5 s windows denoised together and kept consistent.

Every window overlaps the next by half. After each denoising step but the last, the first half of
window i is overwritten with the second half of window i-1 (EDGE's long-form scheme), so the
windows denoise towards agreement; the final predictions are cross-faded over each overlap. The
network runs over the windows in chunks, and songs longer than a block of windows are sampled
block by block (each block continuing the last), so memory does not grow with the song.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import torch

from choreo.constraints.displacement import displace_to_constraints
from choreo.motion.vector import ROOT_SLICE

from .guidance import GuidedDenoiser, guides_style
from .options import SamplingOptions
from .schedule import NoiseSchedule, make_sampler


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


@dataclass
class Inpainting:
    """Known normalised frame values (T, D) and their mask (T, D): paper eqs. 8-10.

    After every step the known channels are replaced by the known values noised to the step's
    level; after the last step by the known values themselves, so constrained frames come out
    exactly as given (EDGE skips that final re-imposition).
    """

    values: torch.Tensor
    mask: torch.Tensor

    def windows(self, starts: list[int], window: int) -> "Inpainting":
        return Inpainting(windowed(self.values, starts, window), windowed(self.mask.float(), starts, window) > 0.5)

    def align_root(self, x0: torch.Tensor) -> torch.Tensor:
        """Shift each window's predicted root so that it matches the given root on average.

        The model is indifferent to where on the floor it dances (windows are cut anywhere in a
        room), so with a few given frames it would place the dancer metres away and jump there;
        moving its prediction rigidly onto the given frames keeps everything it predicted but the
        location. Normalisation is affine per channel, so the shift is a constant there too.
        """
        mask = self.mask[..., ROOT_SLICE]
        known = mask.sum(-2)
        if not known.any():
            return x0
        offset = ((self.values[..., ROOT_SLICE] - x0[..., ROOT_SLICE]) * mask).sum(-2) / known.clamp(min=1)
        x0 = x0.clone()
        x0[..., ROOT_SLICE] += torch.where(known > 0, offset, torch.zeros_like(offset)).unsqueeze(-2)
        return x0

    def step(self, denoise: Callable[[torch.Tensor], torch.Tensor], sampler, schedule: NoiseSchedule, x: torch.Tensor,
             t: int, generator: torch.Generator, resample: int) -> torch.Tensor:
        """One masked step t -> t_prev, run ``resample`` times: after each but the last, the result
        is noised back to level t (RePaint's resampling), so the unknown part is denoised again
        with the known part already in place, which lets the two agree at their borders."""
        t_prev = sampler.previous(t)
        for attempt in range(resample):
            x_prev = sampler.step(self.align_root(denoise(x)), t, x, generator).prev_sample
            x_prev = self.impose(x_prev, schedule, t_prev, generator)
            if attempt + 1 == resample or t_prev < 0:
                return x_prev
            keep = float(schedule.alphas_cumprod[t] / schedule.alphas_cumprod[t_prev])
            noise = torch.randn(x_prev.shape, generator=generator, dtype=x_prev.dtype)
            x = keep**0.5 * x_prev + (1 - keep) ** 0.5 * noise
        return x_prev

    def impose(self, x: torch.Tensor, schedule: NoiseSchedule, t_prev: int, generator: torch.Generator) -> torch.Tensor:
        if t_prev < 0:  # the end: exact values, reached by a displacement map rather than a step
            moved = displace_to_constraints(x.numpy(), self.values.numpy(), self.mask.numpy())
            return torch.from_numpy(moved).to(x.dtype)
        noise = torch.randn(x.shape, generator=generator, dtype=x.dtype)
        noised = schedule.q_sample(self.values, torch.full((len(x),), t_prev), noise)
        return torch.where(self.mask, noised, x)


def window_styles(style: torch.Tensor, keep_style: torch.Tensor | bool, starts: list[int], window: int,
                  num_frames: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Per-window style vectors: one vector for the song, or the mean over each window of a
    per-frame schedule (T, S), which blends neighbouring styles where a window straddles a border."""
    count = len(starts)
    if style.shape[0] == 1:
        keep = keep_style if isinstance(keep_style, torch.Tensor) else torch.tensor([keep_style])
        return style.expand(count, -1), keep.expand(count)
    per_frame_keep = keep_style.float()[:, None] if isinstance(keep_style, torch.Tensor) else torch.ones(num_frames, 1)
    styles = windowed(style * per_frame_keep, starts, window)
    weights = windowed(per_frame_keep, starts, window)
    total = weights.sum(1)
    return styles.sum(1) / total.clamp(min=1), total[:, 0] > 0


@torch.no_grad()
def sample_long(model, schedule: NoiseSchedule, music: torch.Tensor, style: torch.Tensor, keep_style,
                frame_dim: int, window: int, options: SamplingOptions,
                progress: Callable[[float], None] | None = None,
                inpainting: Inpainting | None = None) -> tuple[torch.Tensor, int]:
    """Normalised x0 (T, frame_dim) for standardised music (T, 35), and the network evaluations per window.

    ``style`` is (1, S) for the whole song or (T, S) per frame (a style schedule); ``keep_style``
    a bool or (T,) bools saying where a style is given at all.

    Up to ``options.block_windows`` windows are denoised together. A longer song goes block by
    block, each block opening with the previous block's last window as known frames (the same
    masked sampling as a seed motion), so memory stays that of one block however long the song.
    """
    options = options.resolved(constrained=inpainting is not None)  # the user's constraints, not the blocks' joins
    num_frames = len(music)
    starts = window_starts(num_frames, window)
    blocks = block_ranges(len(starts), options.block_windows)
    out = torch.full((num_frames, frame_dim), float("nan"))
    evaluations = 0
    for b, (first, last) in enumerate(blocks):
        offset = starts[first]
        stop = min(num_frames, starts[last - 1] + window)
        known = _block_constraints(inpainting, out, offset, stop, window if b > 0 else 0)
        report = None if progress is None else (lambda f, b=b: progress((b + f) / len(blocks)))
        block_style, block_keep = (style, keep_style) if style.shape[0] == 1 else (
            style[offset:stop], keep_style[offset:stop] if isinstance(keep_style, torch.Tensor) else keep_style)
        block_options = options if b == 0 else replace(options, seed=options.seed * 1_000_003 + b)
        out[offset:stop], evaluations = _sample_block(model, schedule, music[offset:stop], block_style, block_keep,
                                                      frame_dim, window, block_options, report, known)
    return out, evaluations


def block_ranges(count: int, size: int) -> list[tuple[int, int]]:
    """[first, last) window ranges of at most ``size`` windows, each sharing its first with the
    previous range's last."""
    if count <= size:
        return [(0, count)]
    ranges, first = [], 0
    while True:
        last = min(count, first + size)
        ranges.append((first, last))
        if last == count:
            return ranges
        first = last - 1


def _block_constraints(inpainting: Inpainting | None, done: torch.Tensor, offset: int, stop: int,
                       carried: int) -> Inpainting | None:
    """The user's constraints on frames [offset, stop) plus the first ``carried`` frames as already sampled."""
    if inpainting is None and carried == 0:
        return None
    if inpainting is None:
        values, mask = torch.zeros(stop - offset, done.shape[1]), torch.zeros(stop - offset, done.shape[1], dtype=torch.bool)
    else:
        values, mask = inpainting.values[offset:stop].clone(), inpainting.mask[offset:stop].clone()
    values[:carried], mask[:carried] = done[offset : offset + carried], True
    return Inpainting(values, mask)


@torch.no_grad()
def _sample_block(model, schedule: NoiseSchedule, music: torch.Tensor, style: torch.Tensor, keep_style,
                  frame_dim: int, window: int, options: SamplingOptions,
                  progress: Callable[[float], None] | None, inpainting: Inpainting | None) -> tuple[torch.Tensor, int]:
    num_frames = len(music)
    starts = window_starts(num_frames, window)
    music_windows = windowed(music, starts, window)
    count, hop = len(starts), window // 2
    generator = torch.Generator().manual_seed(options.seed)
    x = torch.randn((count, window, frame_dim), generator=generator)
    styles, keep = window_styles(style, keep_style, starts, window, num_frames)
    known = inpainting.windows(starts, window) if inpainting is not None else None
    sampler = make_sampler(options.sampler, schedule, options.steps, options.eta)
    denoiser = guided_denoiser(model, music_windows, styles, keep, options, schedule)
    evaluations = 0
    for i, t in enumerate(sampler.timesteps.tolist()):
        if known is None:
            evaluations += denoiser.evaluations_at(t)
            x = sampler.step(denoiser(x, t), t, x, generator).prev_sample
        else:
            evaluations += denoiser.evaluations_at(t) * options.resample
            x = known.step(lambda sample: denoiser(sample, t), sampler, schedule, x, t, generator, options.resample)
        if i + 1 < len(sampler.timesteps):  # the final x0s are cross-faded by stitch() instead
            x[1:, :hop] = x[:-1, window - hop:]
        if progress:
            progress((i + 1) / len(sampler.timesteps))
    return stitch(x, num_frames), evaluations


def guided_denoiser(model, music: torch.Tensor, styles: torch.Tensor, keep_style: torch.Tensor,
                    options: SamplingOptions, schedule: NoiseSchedule) -> GuidedDenoiser:
    """The options' guidance on a set of windows (``options`` resolved: its guidance weights set); the
    music's default interval depends on whether any window has a style to guide. A travel share not
    decided by a genre (``SGMDGenerator.for_genres``) is 1: the travel guided as the body."""
    if options.guidance is None or options.style_guidance is None:
        raise ValueError("resolve the sampling options first (SamplingOptions.resolved)")
    return GuidedDenoiser(model, music, styles, keep_style, options.guidance, options.chunk_windows,
                          interval=options.guided_steps(schedule.timesteps, guides_style(options.style_guidance, keep_style)),
                          style_guidance=options.style_guidance,
                          style_interval=options.style_guided_steps(schedule.timesteps), pace=options.pace,
                          travel_guidance=1.0 if options.travel_guidance is None else options.travel_guidance)


@torch.no_grad()
def sample_independent(model, schedule: NoiseSchedule, music: torch.Tensor, styles: torch.Tensor,
                       keep_style: torch.Tensor, frame_dim: int, options: SamplingOptions,
                       inpainting: Inpainting | None = None) -> torch.Tensor:
    """Normalised x0 (N, W, frame_dim) for N unrelated windows (N, W, 35): how papers score 5 s clips.

    ``inpainting`` holds (N, W, frame_dim) known values and mask, one per window."""
    options = options.resolved(constrained=inpainting is not None)
    generator = torch.Generator().manual_seed(options.seed)
    x = torch.randn((*music.shape[:2], frame_dim), generator=generator)
    sampler = make_sampler(options.sampler, schedule, options.steps, options.eta)
    denoiser = guided_denoiser(model, music, styles, keep_style, options, schedule)
    for t in sampler.timesteps.tolist():
        if inpainting is None:
            x = sampler.step(denoiser(x, t), t, x, generator).prev_sample
        else:
            x = inpainting.step(lambda sample: denoiser(sample, t), sampler, schedule, x, t, generator, options.resample)
    return x
