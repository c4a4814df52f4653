"""The legs: do the feet step and lift around the body, or ride on it?

Four figures of one dance (joint positions (T, 24, 3), metres, Y up; the evaluation frame rate,
30 fps after resampling), each defined in docs/metrics.md:

- feet speed: mean horizontal speed of the ankles and toes relative to the pelvis (m/s). A
  shuffling dancer's feet stay under it; a stepping dancer's swing out and back.
- ankle lift: each ankle's height above its own 5th percentile, its 90th percentile (m), the mean
  of the two ankles. Percentiles rather than extremes, so one stumble or a capture spike does not
  decide it, and each ankle against its own floor, so the dancer's height and the floor's do not.
- pelvis speed: mean horizontal frame-to-frame speed of the pelvis (m/s): travel and sway together,
  which a dancer that slides instead of stepping overdoes.
- foot jerk: median over frames and the four foot joints of |d3 position / dt3| (m/s^3).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..skeleton.smpl import FOOT_JOINTS, LEFT_ANKLE, RIGHT_ANKLE
from .stepping import UP_AXIS, horizontal_speeds

FLOOR_PERCENTILE, LIFT_PERCENTILE = 5.0, 90.0
PELVIS = 0


@dataclass(frozen=True)
class Legs:
    feet_speed: float  # m/s, ankles and toes around the pelvis, horizontally
    ankle_lift: float  # m, 90th percentile of each ankle's height over its own 5th, mean of the two
    pelvis_speed: float  # m/s, horizontally, frame to frame
    foot_jerk: float  # m/s^3, median over frames and the four foot joints

    def to_dict(self) -> dict:
        return asdict(self)


def feet_speed(positions: np.ndarray, fps: float) -> float:
    """Mean horizontal speed (m/s) of the ankles and toes relative to the pelvis."""
    around = positions[:, list(FOOT_JOINTS)] - positions[:, PELVIS:PELVIS + 1]
    return float(horizontal_speeds(around, fps).mean())


def ankle_lift(positions: np.ndarray) -> float:
    """Mean over the two ankles of the 90th percentile of height above the ankle's own 5th."""
    heights = positions[:, [LEFT_ANKLE, RIGHT_ANKLE], UP_AXIS]
    lift = heights - np.percentile(heights, FLOOR_PERCENTILE, axis=0)
    return float(np.percentile(lift, LIFT_PERCENTILE, axis=0).mean())


def pelvis_speed(positions: np.ndarray, fps: float) -> float:
    """Mean horizontal frame-to-frame speed (m/s) of the pelvis."""
    return float(horizontal_speeds(positions[:, PELVIS:PELVIS + 1], fps).mean())


def foot_jerk(positions: np.ndarray, fps: float) -> float:
    """Median over frames and foot joints of |third derivative of position| (m/s^3)."""
    feet = positions[:, list(FOOT_JOINTS)]
    return float(np.median(np.linalg.norm(np.diff(feet, n=3, axis=0), axis=-1)) * fps**3)


def legs(positions: np.ndarray, fps: float) -> Legs:
    """The four figures of one dance (T, 24, 3); NaN where it is too short for one (4 frames)."""
    positions = np.asarray(positions, dtype=np.float64)
    if len(positions) < 4:
        return Legs(*(float("nan"),) * 4)
    return Legs(feet_speed(positions, fps), ankle_lift(positions), pelvis_speed(positions, fps),
                foot_jerk(positions, fps))


def mean_legs(dances: list[Legs]) -> Legs:
    """Each figure's mean over the dances that have it (NaN when none has)."""
    values = np.array([[getattr(d, name) for name in Legs.__dataclass_fields__] for d in dances], dtype=float)
    if not len(values):
        return Legs(*(float("nan"),) * 4)
    finite = np.isfinite(values)
    sums, counts = np.where(finite, values, 0.0).sum(0), finite.sum(0)
    return Legs(*(float(s / c) if c else float("nan") for s, c in zip(sums, counts)))

