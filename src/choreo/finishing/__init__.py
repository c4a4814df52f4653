"""Passes every generated dance goes through after its backend: beat lock (re-timing onto the
music's beats), then foot lock (planted feet carry the body instead of sliding)."""

import numpy as np

from ..motion import Motion
from .beat_lock import BeatLockConfig, BeatLockResult, beat_lock, lock_warp
from .foot_lock import FootLockConfig, foot_lock


def finish(motion: Motion, music_beat_frames: np.ndarray, fixed: np.ndarray | None = None, *,
           beat: bool = True, foot: bool = False) -> Motion:
    """The passes as `choreo generate` applies them by default: beat lock (and, when asked, foot
    lock, which halves PFC but doubles FID_g: docs/results.md); ``fixed`` frames stay."""
    if beat:
        motion = beat_lock(motion, music_beat_frames, fixed).motion
    if foot:
        motion = foot_lock(motion, fixed)
    return motion


__all__ = ["BeatLockConfig", "BeatLockResult", "FootLockConfig", "beat_lock", "finish", "foot_lock", "lock_warp"]
