"""Beat lock: re-time a dance so that its motion beats land on the music's beats.

After Davis and Agrawala's "Visual Rhythm and Beat" (SIGGRAPH 2018), which re-times video so
that its visual beats fall on musical beats. Here the visual beats are the motion beats the
metrics use (local minima of the smoothed mean joint speed, choreo.metrics.motion_beats), and
the re-timing is a monotone warp of the dance's own frames:

1. pairs (motion beat -> music beat) are chosen by dynamic programming: as many motion beats as
   possible land on some music beat (any beat: every 2nd or 4th is fine too), no motion beat
   moves further than ``max_shift_seconds``, and between consecutive pairs the dance plays at a
   speed within [min_speed, max_speed] of the original, with a cost on straying from 1 and a
   bonus when consecutive pairs are one or two music beats apart (so the motion beats recur at
   the song's pulse, not merely somewhere on its grid: measured, docs/results.md);
2. the warp runs piecewise-linearly through the pairs, then its per-frame speed is smoothed (a
   Gaussian, which keeps every speed inside the bounds) and rescaled so each free stretch still
   ends where it started;
3. frames a user fixed (keys, seed motion, the kept parts of an inpainting) are anchors: the warp
   is the identity on them, so they stay exactly where they were given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from ..errors import ParameterError
from ..motion.beats import motion_beats
from ..motion import Motion


@dataclass(frozen=True)
class BeatLockConfig:
    min_speed: float = 0.75  # the slowest local playback speed of the dance
    max_speed: float = 1.33  # the fastest
    max_shift_seconds: float = 0.5  # how far a motion beat may move to reach a music beat
    speed_cost: float = 0.5  # per pair, times |log speed|: prefer small changes of pace
    smoothing_frames: float = 2.0  # sigma of the speed smoothing (no kinks at the pairs)
    max_skip: int = 6  # a pair may follow one up to this many motion beats earlier
    pulse_bonus: float = 1.0  # extra reward when consecutive pairs are one or two music beats apart (the pulse)

    def __post_init__(self):
        if not 0 < self.min_speed <= 1 <= self.max_speed:
            raise ParameterError(f"beat lock speeds must satisfy 0 < min <= 1 <= max, got {self.min_speed}, {self.max_speed}")
        if self.max_shift_seconds < 0 or self.smoothing_frames < 0 or self.max_skip < 1:
            raise ParameterError("beat lock: shift and smoothing must be >= 0 and max_skip >= 1")


@dataclass(frozen=True)
class BeatLockResult:
    motion: Motion
    source_frames: np.ndarray  # (T,) the original frame (fractional) each output frame plays
    pairs: list[tuple[int, int]]  # (motion beat frame, music beat frame) pairs that were locked
    motion_beats: int  # how many motion beats the dance had


def beat_lock(motion: Motion, music_beat_frames: np.ndarray, fixed: np.ndarray | None = None,
              config: BeatLockConfig = BeatLockConfig()) -> BeatLockResult:
    """The dance re-timed onto ``music_beat_frames`` (frames at the motion's fps); same length."""
    dance_beats = motion_beats(motion.joint_positions())
    fixed = np.zeros(motion.num_frames, bool) if fixed is None else np.asarray(fixed, bool)
    if fixed.shape != (motion.num_frames,):
        raise ParameterError(f"fixed frames must be a ({motion.num_frames},) mask, got {fixed.shape}")
    source, pairs = lock_warp(dance_beats, np.asarray(music_beat_frames), motion.num_frames, fixed, motion.fps, config)
    warped = motion.sample_frames(source)
    warped.root_positions[fixed] = motion.root_positions[fixed]  # exactly as given, not re-interpolated
    warped.rotations[fixed] = motion.rotations[fixed]
    warped.metadata = dict(motion.metadata, beat_lock=f"{len(pairs)} of {len(dance_beats)} motion beats on music beats")
    if isinstance(motion.metadata.get("clips"), list):  # a backend's timeline follows the re-timing
        warped.metadata["clips"] = [dict(clip, output_frames=retimed_span(clip["output_frames"], source))
                                    for clip in motion.metadata["clips"]]
    return BeatLockResult(warped, source, pairs, len(dance_beats))


def retimed_span(frames: list[int], source: np.ndarray) -> list[int]:
    """Where the frames [first, last] of a dance play after re-timing (``source[i]``: the frame
    that output frame i shows; non-decreasing)."""
    end = len(source) - 1
    first = min(int(np.searchsorted(source, frames[0] - 0.5)), end)
    last = min(int(np.searchsorted(source, frames[1] + 0.5)) - 1, end)
    return [first, max(last, first)]


def free_spans(fixed: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop] frame pairs of the stretches the warp may move: between fixed frames, with
    each stretch's ends pinned (the fixed frame itself, or the dance's first / last frame)."""
    num_frames = len(fixed)
    spans, start = [], 0
    for frame in np.flatnonzero(fixed):
        if frame - start >= 2:
            spans.append((start, int(frame)))
        start = int(frame)
    if num_frames - 1 - start >= 2:
        spans.append((start, num_frames - 1))
    return spans


def lock_warp(dance_beats: np.ndarray, music_beats: np.ndarray, num_frames: int, fixed: np.ndarray, fps: float,
              config: BeatLockConfig = BeatLockConfig()) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """(source frame per output frame, locked pairs): identity on fixed frames, locked elsewhere."""
    source = np.arange(num_frames, dtype=np.float64)
    all_pairs: list[tuple[int, int]] = []
    for start, stop in free_spans(fixed):
        inside = lambda beats: beats[(beats > start) & (beats < stop)]  # noqa: E731
        pairs = choose_pairs(inside(np.asarray(dance_beats)), inside(np.asarray(music_beats)), start, stop, fps, config)
        if pairs:
            source[start: stop + 1] = span_warp(pairs, start, stop, config)
            all_pairs.extend(pairs)
    source[fixed] = np.flatnonzero(fixed)
    return source, all_pairs


def choose_pairs(dance_beats: np.ndarray, music_beats: np.ndarray, start: int, stop: int, fps: float,
                 config: BeatLockConfig) -> list[tuple[int, int]]:
    """The best monotone (motion beat, music beat) pairs in [start, stop] by dynamic programming."""
    reach = config.max_shift_seconds * fps
    music_beats = np.sort(np.asarray(music_beats))
    nodes = [(start, start)]
    for d in np.sort(np.asarray(dance_beats)):  # the music beats within reach of each motion beat
        lo = np.searchsorted(music_beats, d - reach, side="left")
        hi = np.searchsorted(music_beats, d + reach, side="right")
        nodes.extend((int(d), int(m)) for m in music_beats[lo:hi])
    order = {d: i for i, d in enumerate(sorted(set(int(d) for d in dance_beats)))}
    beat_number = {int(m): k for k, m in enumerate(sorted(set(int(m) for m in music_beats)))}
    score = np.full(len(nodes), -np.inf)
    back = np.full(len(nodes), -1)
    score[0] = 0.0

    def step_cost(a: tuple[int, int], b: tuple[int, int]) -> float | None:
        source, target = b[0] - a[0], b[1] - a[1]
        if source <= 0 or target <= 0:
            return None
        speed = source / target
        if not config.min_speed <= speed <= config.max_speed:
            return None
        return config.speed_cost * abs(np.log(speed))

    rank = np.array([-1] + [order[d] for d, _ in nodes[1:]])  # motion-beat number of each node, ascending
    for j in range(1, len(nodes)):
        first = max(1, int(np.searchsorted(rank, rank[j] - config.max_skip)))  # pairs up to max_skip beats back
        for i in (0, *range(first, j)):
            if score[i] == -np.inf:
                continue
            cost = step_cost(nodes[i], nodes[j])
            if cost is None:
                continue
            gain = 1.0 - cost
            if i > 0 and beat_number[nodes[j][1]] - beat_number[nodes[i][1]] in (1, 2):
                gain += config.pulse_bonus
            if score[i] + gain > score[j]:
                score[j], back[j] = score[i] + gain, i
    best, best_total = 0, 0.0  # the identity (no pair) scores 0
    for j in range(1, len(nodes)):
        cost = step_cost(nodes[j], (stop, stop))
        if score[j] > -np.inf and cost is not None and score[j] - cost > best_total:
            best, best_total = j, score[j] - cost
    pairs = []
    while best > 0:
        pairs.append(nodes[best])
        best = back[best]
    return pairs[::-1]


def span_warp(pairs: list[tuple[int, int]], start: int, stop: int, config: BeatLockConfig) -> np.ndarray:
    """Source frames for output frames start..stop through the pairs, with a smoothed speed."""
    targets = np.array([start] + [m for _, m in pairs] + [stop], dtype=np.float64)
    sources = np.array([start] + [d for d, _ in pairs] + [stop], dtype=np.float64)
    frames = np.arange(start, stop + 1, dtype=np.float64)
    linear = np.interp(frames, targets, sources)
    speed = np.diff(linear)
    if config.smoothing_frames > 0 and len(speed) > 1:
        speed = gaussian_filter1d(speed, config.smoothing_frames, mode="nearest")
        speed *= (stop - start) / speed.sum()  # the span still ends where it started
    return start + np.concatenate([[0.0], np.cumsum(speed)])
