"""Motion beats: the moments a dancer nearly stops (local minima of the mean joint speed
after Gaussian smoothing). Motion analysis, used by the metrics (BeatAlign), by the dataset
readers (M2D's music offsets) and by the beat lock; times are in frames of the motion's rate."""

from __future__ import annotations

import numpy as np

from .motion import frame_chunks

SPEED_SMOOTHING_SIGMA = 5.0  # frames, as in the reference code


def mean_joint_speed(joint_positions: np.ndarray) -> np.ndarray:
    """(T-1,) mean over joints of |p[t+1] - p[t]| (metres per frame)."""
    return np.concatenate([np.linalg.norm(np.diff(joint_positions[steps.start: steps.stop + 1], axis=0), axis=-1).mean(axis=-1)
                           for steps in frame_chunks(max(len(joint_positions) - 1, 1))])


def smoothed_speed(joint_positions: np.ndarray, sigma: float = SPEED_SMOOTHING_SIGMA) -> np.ndarray:
    """(T-1,) mean joint speed (metres per frame) after Gaussian smoothing: the curve whose minima
    are the motion beats (metrics, the beat plot and the whole-song beat dip all read it)."""
    from scipy.ndimage import gaussian_filter1d  # here: every motion reader imports this module

    return gaussian_filter1d(mean_joint_speed(joint_positions), sigma)


def speed_minima(speed: np.ndarray) -> np.ndarray:
    """Frame indices of the local minima (order 1) of a smoothed ``speed`` curve: see motion_beats."""
    inner = (speed[1:-1] < speed[:-2]) & (speed[1:-1] <= speed[2:])
    return np.flatnonzero(inner) + 1


def motion_beats(joint_positions: np.ndarray, sigma: float = SPEED_SMOOTHING_SIGMA) -> np.ndarray:
    """Frame indices of motion beats: local minima (order 1) of the smoothed speed.

    Strict on the left, not on the right: a minimum shared by two equal frames (a dancer who
    stops exactly between two frames: the speed is symmetric about the stop) counts once, at its
    first frame. The reference's strict test (scipy's argrelextrema with np.less) finds no beat
    there at all, or one, depending on the last bit of rounding; on any other speed curve the
    two agree."""
    if len(joint_positions) < 3:
        return np.zeros(0, dtype=int)
    return speed_minima(smoothed_speed(joint_positions, sigma))
