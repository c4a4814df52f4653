"""PFC, the Physical Foot Contact score (EDGE ``eval/eval_pfc.py``).

Feet that slide while the body accelerates are physically implausible. Per frame: the smaller
horizontal displacement of each foot's two joints (ankle, toe), left times right, times the
root's acceleration normalised by its maximum in the sequence (upward acceleration clamped at 0,
since pushing up needs a planted foot anyway); mean over frames, mean over sequences, x 10,000.
The reference runs on Z-up data at 30 fps with displacements per frame (not divided by dt), so
the score scales roughly with 1/fps^2: always state the frame rate. We rotate Y-up input to Z-up
(+90 deg about X, as EDGE does with AIST++) and apply the reference formula unchanged.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..skeleton import LEFT_ANKLE_FOOT, RIGHT_ANKLE_FOOT
from .beats import MetricWarning

PFC_FRAME_TIME = 1.0 / 30.0
PFC_SCALE = 10_000.0
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # +90 deg about X


def to_z_up(positions: np.ndarray, up_axis: str = "y") -> np.ndarray:
    if up_axis == "z":
        return positions
    if up_axis != "y":
        raise ValueError(f"up axis must be 'y' or 'z', got {up_axis!r}")
    return positions @ Y_UP_TO_Z_UP.T


def from_z_up(positions: np.ndarray) -> np.ndarray:
    """Inverse of :func:`to_z_up`: Z-up positions (EDGE's convention) back to our Y up."""
    return positions @ Y_UP_TO_Z_UP


def foot_contact_score(positions: np.ndarray, up_axis: str = "y") -> float:
    """PFC term of one sequence (T, 24, 3), before the x 10,000 and the mean over sequences."""
    joints = to_z_up(np.asarray(positions, dtype=np.float64), up_axis)
    if len(joints) < 3:
        warnings.warn("PFC needs at least 3 frames; returning NaN", MetricWarning, stacklevel=2)
        return float("nan")
    root_velocity = np.diff(joints[:, 0], axis=0) / PFC_FRAME_TIME
    root_acceleration = np.diff(root_velocity, axis=0) / PFC_FRAME_TIME
    root_acceleration[:, 2] = np.maximum(root_acceleration[:, 2], 0.0)
    acceleration = np.linalg.norm(root_acceleration, axis=-1)
    peak = acceleration.max()
    if peak <= 0:
        return 0.0  # a root that never accelerates cannot be propelled by sliding feet
    acceleration = acceleration / peak
    horizontal = joints[..., :2]
    slide = np.linalg.norm(horizontal[2:] - horizontal[1:-1], axis=-1)  # (T-2, 24) per-frame displacement
    left = slide[:, list(LEFT_ANKLE_FOOT)].min(axis=1)
    right = slide[:, list(RIGHT_ANKLE_FOOT)].min(axis=1)
    return float((left * right * acceleration).mean())


def physical_foot_contact(sequences: list[np.ndarray], up_axis: str = "y") -> float:
    """PFC of a set: mean of the per-sequence scores, x 10,000 (lower is better)."""
    scores = [foot_contact_score(s, up_axis) for s in sequences]
    return float(np.nanmean(scores) * PFC_SCALE) if scores else float("nan")
