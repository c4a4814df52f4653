"""Passes every generated dance goes through after its backend: beat lock (re-timing onto the
music's beats), then foot lock (planted feet carry the body instead of sliding)."""

from .beat_lock import BeatLockConfig, BeatLockResult, beat_lock, lock_warp
from .foot_lock import FootLockConfig, foot_lock

__all__ = ["BeatLockConfig", "BeatLockResult", "FootLockConfig", "beat_lock", "foot_lock", "lock_warp"]
