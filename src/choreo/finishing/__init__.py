"""Passes every generated dance goes through after its backend: beat lock (re-timing onto the
music's beats)."""

from .beat_lock import BeatLockConfig, BeatLockResult, beat_lock, lock_warp

__all__ = ["BeatLockConfig", "BeatLockResult", "beat_lock", "lock_warp"]
