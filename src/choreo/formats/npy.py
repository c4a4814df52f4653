"""Plain joint-position arrays: ``.npy`` of shape (T, 24, 3), metres, Y up, no fps stored.

This is what metric scripts across the field exchange. Positions cannot become a rotation-based
Motion without inverse kinematics, so reading gives the array, not a Motion.
"""

from __future__ import annotations

import numpy as np

from ..errors import MotionFormatError
from ..motion import Motion
from .safe_arrays import load_npy


def write_npy(motion: Motion, handle) -> None:
    np.save(handle, motion.joint_positions(np.float32), allow_pickle=False)


def read_npy_joint_positions(path) -> np.ndarray:
    try:
        positions = load_npy(path)  # the header's size checked against the file before loading
    except (OSError, ValueError, EOFError) as error:
        raise MotionFormatError(f"{path}: not a readable .npy array ({type(error).__name__})") from None
    if positions.dtype.kind not in "fiu":
        raise MotionFormatError(f"{path}: holds {positions.dtype} values, not joint positions")
    if positions.ndim == 2 and positions.shape[1] == 72:
        positions = positions.reshape(-1, 24, 3)
    if positions.ndim != 3 or positions.shape[1:] != (24, 3):
        raise MotionFormatError(f"{path}: expected joint positions of shape (T, 24, 3), got {positions.shape}")
    if len(positions) == 0 or not np.isfinite(positions).all():
        raise MotionFormatError(f"{path}: empty, NaN or infinite joint positions")
    return positions.astype(np.float64)
