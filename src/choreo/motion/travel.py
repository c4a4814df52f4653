"""Where a dancer travels: the ground track, the root's floor path without its sway and wobble.

Shared by the pace pass (choreo.finishing.pace), the whole-song figures (choreo.metrics.whole_song)
and anything that separates travel from the motion around it. Y is up.
"""

from __future__ import annotations

import numpy as np

from .filters import low_pass

TRACK_CUTOFF_HZ = 1.0  # slower than a step: what remains is where the dancer goes
FLOOR_AXES = (0, 2)


def ground_track(root_positions: np.ndarray, fps: float, cutoff_hz: float = TRACK_CUTOFF_HZ) -> np.ndarray:
    """(T, 2) the root's floor path (x, z), low-passed at ``cutoff_hz`` (zero-phase)."""
    return low_pass(np.asarray(root_positions, dtype=np.float64)[:, list(FLOOR_AXES)], fps, cutoff_hz)


def track_pace(track: np.ndarray, fps: float) -> float:
    """Metres per second along a (T, 2) track."""
    seconds = (len(track) - 1) / fps
    return float(np.linalg.norm(np.diff(track, axis=0), axis=-1).sum() / seconds) if seconds > 0 else 0.0


def track_reach(track: np.ndarray) -> float:
    """A (T, 2) track's farthest distance from where it started (metres)."""
    return float(np.linalg.norm(track - track[:1], axis=-1).max()) if len(track) else 0.0


def pace(root_positions: np.ndarray, fps: float) -> float:
    """Metres per second along the ground track of (T, 3) root positions."""
    return track_pace(ground_track(root_positions, fps), fps)
