"""Accent: ease into and out of every motion beat, as an animator times a hit.

Generated dances mark their motion beats less than real dancers do: the dip in joint speed at a
beat is shallower than real's on whole songs, most of all on waltz (docs/results.md, "Whole
songs"). The model's beats are there, only soft. This pass re-times the dance between each two consecutive
motion beats a and b so that it plays at ``1 - depth`` of its speed at the beats and ``1 + depth``
halfway between, a raised cosine whose mean is 1: every motion beat stays on its frame (the
playback is slowest exactly there, so a minimum of the joint speed stays a minimum), and so does
the length of every stretch between beats. It runs before the footsteps and the beat lock, which
then plan the feet and lock the beats of the accented dance. Stretches holding a frame a user
fixed (or a loop's seam) are left as they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..motion.beats import motion_beats
from .beat_lock import retimed_span


@dataclass(frozen=True, kw_only=True)
class AccentConfig:
    depth: float = 0.2  # playback speed 1 - depth at each motion beat, 1 + depth between (docs/results.md, "Whole songs")

    def __post_init__(self):
        if not 0.0 <= self.depth < 1.0:
            raise ParameterError(f"accent: depth must be in [0, 1), got {self.depth}")


def accent_warp(beats: np.ndarray, num_frames: int, depth: float, fixed: np.ndarray) -> np.ndarray:
    """(T,) the source frame each output frame plays: slower at each of ``beats``, faster between,
    the identity outside the first and last beat and across stretches holding a ``fixed`` frame."""
    source = np.arange(num_frames, dtype=np.float64)
    for a, b in zip(beats[:-1], beats[1:]):
        if fixed[a : b + 1].any():
            continue
        phase = (source[a : b + 1] - a) / (b - a)
        source[a : b + 1] -= depth * (b - a) / (2 * np.pi) * np.sin(2 * np.pi * phase)
    return source


def accent(motion: Motion, fixed: np.ndarray | None = None, config: AccentConfig = AccentConfig()) -> Motion:
    """``motion`` eased into and out of its motion beats; ``fixed`` frames stay exactly as they are."""
    fixed = np.zeros(motion.num_frames, bool) if fixed is None else np.asarray(fixed, bool)
    if config.depth == 0 or motion.num_frames < 3 or fixed.all():
        return motion
    beats = motion_beats(motion.joint_positions())
    if len(beats) < 2:
        return motion
    source = accent_warp(beats, motion.num_frames, config.depth, fixed)
    accented = motion.sample_frames(source)
    accented.root_positions[fixed] = motion.root_positions[fixed]  # exactly as given, not re-interpolated
    accented.rotations[fixed] = motion.rotations[fixed]
    if isinstance(motion.metadata.get("clips"), list):  # a backend's timeline follows the re-timing
        accented.metadata["clips"] = [dict(clip, output_frames=retimed_span(clip["output_frames"], source))
                                      for clip in motion.metadata["clips"]]
    return accented
