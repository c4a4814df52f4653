"""Figures of a whole dance, as a user sees it: pace, wandering, smoothness and how clear the motion
beats are. The 5 s scoring windows cannot show a dancer that rushes over a minute, wanders off the
floor or wobbles along its path; these can (joint positions in metres, Y up).

- ground track: the root's horizontal path low-passed at 1 Hz (choreo.motion.travel), so that
  sway and wobble do not count as travel. Pace is its length over the dance's duration; reach is
  its farthest point from where it started.
- jerk: median over frames and joints of |d3 position / dt3|, for the whole body, the root's path
  alone and the body relative to the pelvis (where the jitter lives).
- beat dip: 1 - (mean joint speed at the motion beats) / (the peak speed between two beats), the
  median over beats: 1 is a dancer who stops dead on every beat, 0 one whose beats do not show.
- the legs: feet speed around the pelvis, ankle lift, pelvis speed and foot jerk (legs.py).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..motion.beats import smoothed_speed, speed_minima
from ..motion.travel import ground_track, track_pace, track_reach
from .legs import legs
from .stepping import stepping


@dataclass(frozen=True)
class WholeSong:
    seconds: float
    pace: float  # m/s along the ground track
    reach: float  # metres: the ground track's farthest point from its start
    planted: float
    foot_root: float
    slide: float
    jerk: float  # m/s^3, every joint
    root_jerk: float  # the root joint alone
    body_jerk: float  # every joint but the root, relative to the root
    beat_dip: float
    feet_speed: float  # m/s, ankles and toes around the pelvis (legs.py)
    ankle_lift: float  # m
    pelvis_speed: float  # m/s
    foot_jerk: float  # m/s^3

    def to_dict(self) -> dict:
        return asdict(self)


def median_jerk(positions: np.ndarray, fps: float) -> float:
    """Median over frames and joints of |third derivative| (m/s^3); positions (T, J, 3)."""
    positions = np.asarray(positions, dtype=np.float64)
    if len(positions) < 4:
        return float("nan")
    return float(np.median(np.linalg.norm(np.diff(positions, n=3, axis=0), axis=-1)) * fps**3)


def jerks(positions: np.ndarray, fps: float) -> tuple[float, float, float]:
    """(whole body, root's path, body relative to the root) median jerks."""
    positions = np.asarray(positions, dtype=np.float64)
    return (median_jerk(positions, fps), median_jerk(positions[:, :1], fps),
            median_jerk(positions[:, 1:] - positions[:, :1], fps))


def beat_dip(positions: np.ndarray) -> float:
    """Median over motion beats of 1 - speed at the beat / peak speed up to the next beat."""
    if len(positions) < 3:
        return float("nan")
    speed = smoothed_speed(np.asarray(positions, dtype=np.float64))
    beats = speed_minima(speed)
    dips = [1.0 - speed[a] / speed[a:b + 1].max() for a, b in zip(beats[:-1], beats[1:]) if speed[a:b + 1].max() > 0]
    return float(np.median(dips)) if dips else float("nan")


def whole_song(positions: np.ndarray, fps: float) -> WholeSong:
    """Every figure of one whole dance (T, 24, 3)."""
    steps = stepping(positions, fps)
    jerk, root_jerk, body_jerk = jerks(positions, fps)
    track = ground_track(np.asarray(positions)[:, 0], fps)
    return WholeSong(len(positions) / fps, track_pace(track, fps), track_reach(track), steps.planted_share,
                     steps.foot_root_correlation, steps.support_slide, jerk, root_jerk, body_jerk,
                     beat_dip(positions), *legs(positions, fps).to_dict().values())
