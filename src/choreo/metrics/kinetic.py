"""Kinetic features (72 = 24 joints x 3), as the AIST++ API computes them.

Per joint: mean horizontal kinetic energy |v_xz|^2, mean vertical kinetic energy v_y^2 and mean
"energy expenditure" |a|, with velocities and accelerations averaged over a window of 2 frames on
each side. Reproduced exactly for comparability with published FID_k / Div_k numbers, including:
- frame time fixed at 1/60 s whatever the motion's real frame rate (AIST++ is 60 fps; at 30 fps
  every velocity is half its true value and energies a quarter);
- the acceleration's operator-precedence slip: the earlier velocity is computed as
  ``p[k] - p[k-1] / dt`` instead of ``(p[k] - p[k-1]) / dt``, so energy expenditure grows with
  the joint's distance from the origin. Callers therefore express positions relative to the
  first frame's root (see :func:`choreo.metrics.fid.prepare_positions`).
Vectorised with cumulative sums; equal to the reference's per-frame loops (tests check it).
"""

from __future__ import annotations

import numpy as np

KINETIC_FRAME_TIME = 1.0 / 60.0
WINDOW = 2  # frames on each side


def _window_bounds(num_frames: int, first: int, last: int) -> tuple[np.ndarray, np.ndarray]:
    """For i = 1..T-1, the inclusive range of k in [i - W, i + W] clipped to [first, last]."""
    i = np.arange(1, num_frames)
    return np.maximum(i - WINDOW, first), np.minimum(i + WINDOW, last)


def _window_mean(values: np.ndarray, lower: np.ndarray, upper: np.ndarray, offset: int) -> np.ndarray:
    """Mean of values[k - offset] for k in [lower, upper] per row (values indexed from ``offset``)."""
    cumulative = np.concatenate([np.zeros((1,) + values.shape[1:]), np.cumsum(values, axis=0)])
    total = cumulative[upper - offset + 1] - cumulative[lower - offset]
    count = (upper - lower + 1).reshape((-1,) + (1,) * (values.ndim - 1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return total / count


def windowed_velocity(positions: np.ndarray, frame_time: float = KINETIC_FRAME_TIME) -> np.ndarray:
    """(T-1, J, 3) velocity at frames 1..T-1: mean of p[k] - p[k-1] over the window, over dt."""
    differences = np.diff(positions, axis=0)  # index k-1 holds p[k] - p[k-1], k = 1..T-1
    lower, upper = _window_bounds(len(positions), 1, len(positions) - 1)
    return _window_mean(differences, lower, upper, offset=1) / frame_time


def windowed_acceleration_quirk(positions: np.ndarray, frame_time: float = KINETIC_FRAME_TIME) -> np.ndarray:
    """(T-1, J) |a| at frames 1..T-1 with the reference's precedence slip (module docstring)."""
    later = (positions[2:] - positions[1:-1]) / frame_time  # k = 1..T-2
    earlier = positions[1:-1] - positions[:-2] / frame_time  # sic: p[k] - p[k-1] / dt
    acceleration = (later - earlier) / frame_time
    lower, upper = _window_bounds(len(positions), 1, len(positions) - 2)
    return np.linalg.norm(_window_mean(acceleration, lower, upper, offset=1), axis=-1)


def kinetic_features(positions: np.ndarray, up_axis: int = 1) -> np.ndarray:
    """(72,) per joint [horizontal energy, vertical energy, energy expenditure], joint-major.

    ``positions`` (T, 24, 3), T >= 3, metres, ``up_axis`` 1 for Y up.
    """
    velocity = windowed_velocity(positions)
    horizontal_axes = [a for a in range(3) if a != up_axis]
    horizontal = (np.linalg.norm(velocity[..., horizontal_axes], axis=-1) ** 2).mean(axis=0)
    vertical = (velocity[..., up_axis] ** 2).mean(axis=0)
    expenditure = windowed_acceleration_quirk(positions).mean(axis=0)
    return np.stack([horizontal, vertical, expenditure], axis=-1).reshape(-1).astype(np.float32)
