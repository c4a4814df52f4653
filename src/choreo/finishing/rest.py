"""Rest: where the song has not begun the dancer waits, and where it has ended the dancer stops.

The backends dance every frame they are given, so a song that ends on ten seconds of silence
got ten seconds of dancing to nothing (15 of the 25 LMMS demo songs end on a second or more of
it: docs/results.md, "Finishing passes"). Here the dance is re-timed at its quiet ends
(choreo.music.loudness.audible_span): over ``ease_seconds`` its playback slows smoothly to a stop
on the stillest pose with both feet down near the music's end, and holds that pose; before the
music it holds such a pose near the music's start and sets off from it, reaching the dance's own
timing as the music comes in. Between the two the timing is untouched, so every beat the beat lock placed stays where it is. An end
with a frame a user fixed is left as it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..motion.beats import smoothed_speed
from ..skeleton import SMPL24
from ..skeleton.legs import LEGS

FOOT_DOWN = 0.03  # metres: an ankle this close to its standing height has its foot on the floor


@dataclass(frozen=True, kw_only=True)
class RestConfig:
    min_silence_seconds: float = 1.0  # a quiet end shorter than this is danced through (a breath, a reverb)
    ease_seconds: float = 1.0  # how long the dancer takes to slow to a stop, or to set off
    search_seconds: float = 0.5  # the pose held: the stillest with both feet down this close to the music's end (or start)

    def __post_init__(self):
        if self.min_silence_seconds <= 0 or self.ease_seconds <= 0 or self.search_seconds < 0:
            raise ParameterError("rest: silence and ease must be positive, search >= 0")


def rest(motion: Motion, audible: tuple[int, int] | None, fixed: np.ndarray | None = None,
         config: RestConfig = RestConfig()) -> Motion:
    """The dance waiting before frame ``audible[0]`` and at rest from ``audible[1]`` on (frames
    [start, stop) have music); same length. Frames in ``fixed`` (a (T,) mask) keep their timing:
    an end that holds one is not re-timed."""
    frames = motion.num_frames
    fixed = np.zeros(frames, bool) if fixed is None else np.asarray(fixed, bool)
    if fixed.shape != (frames,):
        raise ParameterError(f"fixed frames must be a ({frames},) mask, got {fixed.shape}")
    if audible is None or frames < 3:
        return motion
    start, stop = audible
    ease, search = config.ease_seconds * motion.fps, config.search_seconds * motion.fps
    silence = config.min_silence_seconds * motion.fps
    quiet_opening, quiet_ending = start >= silence, frames - stop >= silence
    room = 2 * (ease + search)  # music enough to set off, dance and stop without the two eases overlapping
    if stop - start < room:  # a short burst of music: quicker eases, poses nearer its ends
        ease, search = ease * (stop - start) / room, search * (stop - start) / room
    if not (quiet_opening or quiet_ending) or ease < 2:
        return motion
    positions = motion.joint_positions()
    speed, grounded = smoothed_speed(positions), _both_feet_down(motion, positions)
    source = np.arange(frames, dtype=np.float64)
    waits = quiet_opening and _retime_opening(source, _stillest(speed, grounded, start, search), ease, fixed)
    rests = quiet_ending and _retime_ending(source, _stillest(speed, grounded, stop, search), ease, fixed)
    if not (waits or rests):
        return motion
    rested = motion.sample_frames(source)
    own = source == np.arange(frames)  # played at their own time: exactly as they were, not re-interpolated
    rested.rotations[own], rested.root_positions[own] = motion.rotations[own], motion.root_positions[own]
    rested.metadata["rest"] = {"waits_until": round(start / motion.fps, 3) if waits else 0.0,
                               "rests_from": round(stop / motion.fps, 3) if rests else round(frames / motion.fps, 3)}
    return rested


def _both_feet_down(motion: Motion, positions: np.ndarray) -> np.ndarray:
    """(T,) frames where both ankles are within FOOT_DOWN of the dance's usual standing height (the
    lower ankle's median height); every frame for a skeleton whose legs are not SMPL-24's."""
    if tuple(motion.skeleton.parents) != tuple(SMPL24.parents):
        return np.ones(motion.num_frames, bool)
    ankles = positions[:, [leg[2] for leg in LEGS], 1]
    return ankles.max(axis=1) - np.median(ankles.min(axis=1)) < FOOT_DOWN


def _stillest(speed: np.ndarray, grounded: np.ndarray, frame: int, search: float) -> int:
    """The frame within ``search`` of ``frame`` where the smoothed joint speed is lowest, among
    those with both feet down when there are any: a pose to hold, not a step frozen mid-air."""
    low, high = max(0, int(frame - search)), min(len(speed), int(frame + search) + 1)
    if high <= low:
        return min(frame, len(speed))
    cost = np.where(grounded[low:high], speed[low:high], speed[low:high] + speed.max() + 1.0)
    return low + int(np.argmin(cost))


def _retime_ending(source: np.ndarray, pose: int, ease: float, fixed: np.ndarray) -> bool:
    """Slow the playback from 1 to 0 along a half cosine so that it stops on ``pose``, then hold
    it; False (and ``source`` untouched) when a fixed frame would move."""
    begin = pose - ease / 2  # at speed 1 to 0 over ``ease`` frames the dance covers half of them
    out = np.arange(len(source))
    if begin < 0 or fixed[int(np.floor(begin)):].any():
        return False
    u = np.clip((out - begin) / ease, 0.0, 1.0)
    covered = ease * (u / 2 + np.sin(np.pi * u) / (2 * np.pi))
    source[:] = np.where(out < begin, source, begin + covered)
    return True


def _retime_opening(source: np.ndarray, pose: int, ease: float, fixed: np.ndarray) -> bool:
    """Hold ``pose`` until the dance sets off from it, its playback rising from 0 to 1 along a
    half cosine and meeting the dance's own timing ``ease / 2`` frames after ``pose``; False when
    a fixed frame would move."""
    meet = pose + ease / 2
    out = np.arange(len(source))
    if meet >= len(source) or fixed[: int(np.ceil(meet)) + 1].any():
        return False
    u = np.clip((out - (meet - ease)) / ease, 0.0, 1.0)
    covered = ease * (u / 2 - np.sin(np.pi * u) / (2 * np.pi))
    source[:] = np.where(out >= meet, source, pose + covered)
    return True
