"""Foot-contact labels: which of the four foot joints is planted in each frame."""

from __future__ import annotations

import numpy as np

from ..skeleton import FOOT_JOINTS

# EDGE's rule: a foot joint is in contact when it moves less than 1 cm between frames at 30 fps,
# i.e. slower than 0.3 m/s; expressed as a speed so it means the same at any frame rate.
CONTACT_SPEED_THRESHOLD = 0.01 * 30.0  # metres per second


def foot_contacts(joint_positions: np.ndarray, fps: float,
                  speed_threshold: float = CONTACT_SPEED_THRESHOLD) -> np.ndarray:
    """(T, 4) float labels (1 = contact) for l_ankle, r_ankle, l_foot, r_foot.

    Speed at frame t is |p[t+1] - p[t]| * fps; the last frame repeats the one before it.
    """
    feet = joint_positions[:, list(FOOT_JOINTS)]
    if len(feet) < 2:
        return np.ones((len(feet), len(FOOT_JOINTS)))
    speed = np.linalg.norm(np.diff(feet, axis=0), axis=-1) * fps
    speed = np.concatenate([speed, speed[-1:]], axis=0)
    return (speed < speed_threshold).astype(np.float64)
