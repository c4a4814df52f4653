"""Passes every generated dance goes through after its backend: speed limit (no joint faster
than real dancers move), beat lock (re-timing onto the music's beats), footsteps (feet that stand
and step instead of gliding), and, when asked, foot lock (planted feet carry the body)."""

import numpy as np

from ..motion import Motion
from .beat_lock import BeatLockConfig, BeatLockResult, beat_lock, lock_warp
from .foot_lock import FootLockConfig, foot_lock
from .pace import PaceConfig, paced
from .root_path import RootPathConfig, smooth_root_path
from .speed_limit import SpeedLimitConfig, speed_limit
from .steps import StepConfig, steps as planted_steps


def finish(motion: Motion, music_beat_frames: np.ndarray, fixed: np.ndarray | None = None, *,
           beat: bool = True, foot: bool = False, speed: bool = True, footsteps: bool = True,
           legs_fixed: np.ndarray | None = None, step_config: StepConfig = StepConfig(),
           root_path: RootPathConfig | None = RootPathConfig(), pace: PaceConfig | None = PaceConfig()) -> Motion:
    """The passes as `choreo generate` applies them by default: speed limit, footsteps, beat lock (and,
    when asked, foot lock, which halves PFC but doubles FID_g: docs/results.md); ``fixed`` frames stay.
    The speed limit goes first, so that a glitch is not taken for a motion beat, and last, since
    re-timing speeds stretches up by as much as 1.33 x. Footsteps come before the beat lock: they
    move the motion beats (a leg's swing is part of the body's speed), and a re-timing keeps a
    standing foot standing; after it they cost the beat-rate lock 5-9 points (docs/results.md, "Feet").
    Footsteps turn only the legs, so they keep the frames in ``legs_fixed`` (where a leg rotation
    was given; default ``fixed``), not every given frame. ``step_config``: the step planner's
    settings (scripts/experiments/footsteps_settings.py compares them)."""
    if speed:
        motion = speed_limit(motion, fixed)
    if root_path is not None:
        motion = smooth_root_path(motion, fixed, root_path)
    if pace is not None:
        motion = paced(motion, fixed, pace)
    if footsteps:
        motion = planted_steps(motion, fixed if legs_fixed is None else legs_fixed, step_config)
    if beat:
        motion = beat_lock(motion, music_beat_frames, fixed).motion
    if foot:
        motion = foot_lock(motion, fixed)
    if speed and (beat or foot or footsteps):
        motion = speed_limit(motion, fixed)
    return motion


__all__ = ["BeatLockConfig", "BeatLockResult", "FootLockConfig", "PaceConfig", "RootPathConfig", "SpeedLimitConfig", "StepConfig", "beat_lock", "finish",
           "foot_lock", "lock_warp", "paced", "planted_steps", "smooth_root_path", "speed_limit"]
