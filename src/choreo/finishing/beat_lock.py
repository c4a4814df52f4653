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
   the song's pulse, not merely somewhere on its grid: measured, docs/history/results-2026-12-01-to-2026-12-04.md,
   "Finishing passes: speed limit, beat lock and foot lock");
2. the warp runs through the pairs with a constant playback speed for ``hold_frames`` either
   side of each locked beat, and changes speed only between beats, along raised-cosine ramps.
   Why hold: a motion beat is a minimum of the smoothed joint speed, and a playback speed that
   changes across it tilts that minimum by a few frames, and far fewer locked beats stay within
   a frame of their music beat (docs/results.md, "Beat lock"). Every speed stays within the bounds; a
   stretch too short for a hold and ramps plays at one constant speed;
3. frames a user fixed (keys, seed motion, the kept parts of an inpainting) are anchors: the warp
   is the identity on them, so they stay exactly where they were given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..motion.beats import motion_beats
from ..motion import Motion, positions_at


ON_TARGET_FRAMES = 1  # a locked beat counts as landed within this many frames of its music beat


@dataclass(frozen=True, kw_only=True)
class BeatLockConfig:
    min_speed: float = 0.75  # the slowest local playback speed of the dance
    max_speed: float = 1.33  # the fastest
    max_shift_seconds: float = 0.5  # how far a motion beat may move to reach a music beat
    speed_cost: float = 0.5  # per pair, times |log speed|: prefer small changes of pace
    hold_frames: float = 10.0  # constant playback speed this far either side of a locked beat
    ramp_frames: float = 5.0  # length of each raised-cosine change of speed between beats
    max_skip: int = 6  # a pair may follow one up to this many motion beats earlier
    pulse_bonus: float = 1.0  # extra reward when consecutive pairs are one or two music beats apart (the pulse)
    refinements: int = 3  # rounds of re-aiming each locked beat by where the re-timed dance put it

    def __post_init__(self):
        if not 0 < self.min_speed <= 1 <= self.max_speed:
            raise ParameterError(f"beat lock speeds must satisfy 0 < min <= 1 <= max, got {self.min_speed}, {self.max_speed}")
        if self.max_shift_seconds < 0 or self.hold_frames < 0 or self.ramp_frames < 0 or self.max_skip < 1:
            raise ParameterError("beat lock: shift, hold and ramp must be >= 0 and max_skip >= 1")


@dataclass(frozen=True)
class BeatLockResult:
    motion: Motion
    source_frames: np.ndarray  # (T,) the original frame (fractional) each output frame plays
    pairs: list[tuple[int, int]]  # (motion beat frame, music beat frame) pairs that were locked
    motion_beats: int  # how many motion beats the dance had


def beat_lock(motion: Motion, music_beat_frames: np.ndarray, fixed: np.ndarray | None = None,
              config: BeatLockConfig = BeatLockConfig()) -> BeatLockResult:
    """The dance re-timed onto ``music_beat_frames`` (frames at the motion's fps); same length."""
    positions = motion.joint_positions()
    dance_beats = motion_beats(positions)
    fixed = np.zeros(motion.num_frames, bool) if fixed is None else np.asarray(fixed, bool)
    if fixed.shape != (motion.num_frames,):
        raise ParameterError(f"fixed frames must be a ({motion.num_frames},) mask, got {fixed.shape}")
    source, pairs = lock_warp(dance_beats, np.asarray(music_beat_frames), motion.num_frames, fixed, motion.fps, config)
    if pairs and config.refinements:
        source = refined_warp(positions, pairs, fixed, source, config)
    on_target = beats_on_target(positions_at(positions, source), pairs) if pairs else 0
    del positions  # before the re-timed rotations are built
    warped = motion.sample_frames(source)
    warped.root_positions[fixed] = motion.root_positions[fixed]  # exactly as given, not re-interpolated
    warped.rotations[fixed] = motion.rotations[fixed]
    warped.metadata = dict(motion.metadata, beat_lock=f"{on_target} of {len(dance_beats)} motion beats locked within a frame of a music beat "
                                                          f"({len(pairs)} aimed)")
    if isinstance(motion.metadata.get("clips"), list):  # a backend's timeline follows the re-timing
        warped.metadata["clips"] = [dict(clip, output_frames=retimed_span(clip["output_frames"], source))
                                    for clip in motion.metadata["clips"]]
    return BeatLockResult(warped, source, pairs, len(dance_beats))


def refined_warp(joint_positions: np.ndarray, pairs: list[tuple[int, int]], fixed: np.ndarray, source: np.ndarray,
                 config: BeatLockConfig) -> np.ndarray:
    """The warp with each locked beat re-aimed until the re-timed dance's own motion beat is on
    its music beat. Why: a motion beat is a minimum of the smoothed joint speed, and the speed
    changes of a warp within the smoothing's reach of the beat move that minimum by a few
    frames. Each round aims a pair short by as far as its beat landed past it; an aim that would
    break the speed bounds is not taken. The round with the most beats on target is kept. (The
    rounds read the re-timed joints by linear interpolation of ``joint_positions``: no forward
    kinematics per round.)"""
    targets = np.array([m for _, m in pairs], dtype=np.float64)
    aims = targets.copy()
    best, best_hits = source, -1
    for round_ in range(config.refinements + 1):
        miss = landed_beats(positions_at(joint_positions, source), targets) - targets
        hits = int(np.sum(np.abs(miss) <= ON_TARGET_FRAMES))
        if hits > best_hits:
            best, best_hits = source, hits
        if round_ == config.refinements or hits == len(targets):
            break
        aims = feasible_aims(pairs, aims, aims - np.where(np.abs(miss) <= 3, miss, 0.0), config)
        source = warp_through([(d, a) for (d, _), a in zip(pairs, aims)], len(joint_positions), fixed, config)
        speed = np.diff(source)[~(fixed[1:] & fixed[:-1])]
        if speed.min() < config.min_speed - 1e-6 or speed.max() > config.max_speed + 1e-6:
            break  # an aim pushed a stretch at a span's end out of bounds: keep the best so far
    return best


def beats_on_target(joint_positions: np.ndarray, pairs: list[tuple[int, int]]) -> int:
    """How many locked pairs' music beats have a motion beat of the re-timed joints within a frame."""
    targets = np.array([m for _, m in pairs], dtype=np.float64)
    return int(np.sum(np.abs(landed_beats(joint_positions, targets) - targets) <= ON_TARGET_FRAMES))


def landed_beats(joint_positions: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """The motion beat of the joints nearest to each target frame (inf without any)."""
    beats = motion_beats(joint_positions)
    if len(beats) == 0:
        return np.full(len(targets), np.inf)
    # The beats ascend, so the nearest is the first at or after the target or the one before it (the
    # earlier on a tie); a (targets x beats) table of distances would take gigabytes on an hour's song.
    after = np.minimum(np.searchsorted(beats, targets), len(beats) - 1)
    before = np.maximum(after - 1, 0)
    earlier = np.abs(beats[before] - targets) <= np.abs(beats[after] - targets)
    return np.where(earlier, beats[before], beats[after]).astype(np.float64)


def feasible_aims(pairs: list[tuple[int, int]], aims: np.ndarray, wanted: np.ndarray,
                  config: BeatLockConfig) -> np.ndarray:
    """``wanted`` aims, except where one would make a stretch between pairs play outside the
    speed bounds (or out of order): there the previous aim stays."""
    sources = np.array([d for d, _ in pairs], dtype=np.float64)
    result = aims.copy()
    for i, aim in enumerate(wanted):
        trial = result.copy()
        trial[i] = aim
        if all(_speed_ok(sources[j + 1] - sources[j], trial[j + 1] - trial[j], config)
               for j in (i - 1, i) if 0 <= j < len(trial) - 1):
            result = trial
    return result


def _speed_ok(source_frames: float, output_frames: float, config: BeatLockConfig) -> bool:
    return output_frames > 0 and config.min_speed <= source_frames / output_frames <= config.max_speed


def warp_through(knots: list[tuple[float, float]], num_frames: int, fixed: np.ndarray,
                 config: BeatLockConfig) -> np.ndarray:
    """(source frame per output frame) through (source, output) knots; identity on fixed frames."""
    source = np.arange(num_frames, dtype=np.float64)
    for start, stop in free_spans(fixed):
        inside = [(d, a) for d, a in knots if start < a < stop]
        if inside:
            source[start: stop + 1] = span_warp(inside, start, stop, config)
    source[fixed] = np.flatnonzero(fixed)
    return source


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
    all_pairs: list[tuple[int, int]] = []
    for start, stop in free_spans(fixed):
        inside = lambda beats: beats[(beats > start) & (beats < stop)]  # noqa: E731
        all_pairs += choose_pairs(inside(np.asarray(dance_beats)), inside(np.asarray(music_beats)), start, stop, fps, config)
    return warp_through(all_pairs, num_frames, fixed, config), all_pairs


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
    """Source frames for output frames start..stop through the pairs (exactly), each locked beat
    inside a stretch of constant speed, every speed within the bounds."""
    targets = np.array([start] + [m for _, m in pairs] + [stop], dtype=np.float64)
    sources = np.array([start] + [d for d, _ in pairs] + [stop], dtype=np.float64)
    slopes = knot_speeds(sources, targets, config)
    frames = np.arange(start, stop + 1, dtype=np.float64)
    warp = np.empty_like(frames)
    for k in range(len(targets) - 1):
        inside = (frames >= targets[k]) & (frames <= targets[k + 1])
        holds = (0.0 if k == 0 else config.hold_frames, 0.0 if k == len(targets) - 2 else config.hold_frames)
        warp[inside] = sources[k] + stretch_progress(frames[inside] - targets[k], targets[k + 1] - targets[k],
                                                     sources[k + 1] - sources[k], slopes[k], slopes[k + 1], holds, config)
    return warp


def knot_speeds(sources: np.ndarray, targets: np.ndarray, config: BeatLockConfig) -> np.ndarray:
    """Playback speed held around each pair: the geometric mean of the stretches either side
    (the span's ends take their one stretch's speed), within the bounds."""
    stretch = np.diff(sources) / np.diff(targets)
    speeds = np.concatenate([[stretch[0]], np.sqrt(stretch[:-1] * stretch[1:]), [stretch[-1]]])
    return np.clip(speeds, config.min_speed, config.max_speed)


def stretch_progress(u: np.ndarray, length: float, source_length: float, first: float, last: float,
                     holds: tuple[float, float], config: BeatLockConfig) -> np.ndarray:
    """Source frames advanced ``u`` output frames into a stretch between two pairs: speed ``first``
    held, a ramp to a plateau, a ramp to ``last``, held; the plateau is what makes the stretch
    end exactly on its pair. Holds shrink until the plateau is within the bounds; if none fits,
    one constant speed (the pairs' own, within the bounds by construction)."""
    ramp = min(config.ramp_frames, length / 4)
    room = max(0.0, min(1.0, (length - 2 * ramp) / max(sum(holds), 1e-9)))  # holds that fit beside the ramps
    for fraction in (1.0, 0.75, 0.5, 0.25):
        hold_in, hold_out = holds[0] * room * fraction, holds[1] * room * fraction
        plateau_length = max(length - hold_in - hold_out - 2 * ramp, 0.0)
        plateau = (source_length - hold_in * first - hold_out * last - ramp * (first + last) / 2) / (plateau_length + ramp)
        if config.min_speed - 1e-9 <= plateau <= config.max_speed + 1e-9:
            pieces = ((hold_in, first, first), (ramp, first, plateau), (plateau_length, plateau, plateau),
                      (ramp, plateau, last), (hold_out, last, last))
            return _speed_profile_integral(u, pieces)
    return u * (source_length / length)


def _speed_profile_integral(u: np.ndarray, pieces: tuple[tuple[float, float, float], ...]) -> np.ndarray:
    """Integral from 0 to u of a speed made of consecutive ``pieces`` (length, speed at its start,
    speed at its end), each constant or a raised-cosine ramp."""
    result, start = np.zeros_like(u), 0.0
    for width, v0, v1 in pieces:
        x = np.clip(u - start, 0.0, width)  # how far into this piece
        result += v0 * x
        if width > 0 and v1 != v0:
            result += (v1 - v0) / 2 * (x - width / np.pi * np.sin(np.pi * x / width))
        start += width
    return result
