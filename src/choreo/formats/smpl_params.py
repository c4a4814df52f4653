"""SMPL parameters (AIST++ keys) <-> Motion, shared by the NPZ and AIST++ pkl formats.

AIST++ stores ``smpl_poses`` (T, 72) axis-angle (global orientation then 23 body joints),
``smpl_trans`` (T, 3) and ``smpl_scaling`` (1,); the translation is in the scaled body's units, so
metres = trans / scaling. Like EDGE, we take trans / scaling as the pelvis position: SMPL's own
pelvis sits a few centimetres from the model origin for a given body shape, a shape we do not have.
"""

from __future__ import annotations

import numpy as np

from ..errors import MotionFormatError
from ..motion import Motion, source_name
from ..skeleton import SMPL24


def as_float_array(value, key: str, name: str) -> np.ndarray:
    """``value`` as float64, or a one-line refusal: a file may hold text, ragged lists or None
    where numbers belong, and numpy's complaints about them are not the user's language."""
    if isinstance(value, np.ndarray) and value.dtype.kind not in "fiub":
        raise MotionFormatError(f"{name}: {key} holds {value.dtype} values, not numbers")
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError, RecursionError):
        raise MotionFormatError(f"{name}: {key} is not an array of numbers") from None


def first_number(value, key: str, name: str) -> float:
    """The first number of a scalar or array entry (fps, smpl_scaling); refused when there is none."""
    array = as_float_array(value, key, name).reshape(-1)
    if array.size == 0:
        raise MotionFormatError(f"{name}: {key} is empty")
    return float(array[0])


def smpl_params_to_motion(poses, trans, scaling, fps: float, name: str) -> Motion:
    poses = as_float_array(poses, "smpl_poses", name)
    trans = as_float_array(trans, "smpl_trans", name)
    scaling = first_number(scaling, "smpl_scaling", name) if scaling is not None else 1.0
    if poses.ndim != 2 or poses.shape[1] != 72:
        raise MotionFormatError(f"{name}: smpl_poses must have shape (T, 72), got {poses.shape}")
    if trans.shape != (len(poses), 3):
        raise MotionFormatError(f"{name}: smpl_trans must have shape ({len(poses)}, 3), got {trans.shape}")
    if len(poses) == 0:
        raise MotionFormatError(f"{name}: no frames")
    if not (np.isfinite(poses).all() and np.isfinite(trans).all()) or not np.isfinite(scaling) or scaling <= 0:
        raise MotionFormatError(f"{name}: NaN, infinite or non-positive values in SMPL parameters")
    if not (np.isfinite(fps) and fps > 0):
        raise MotionFormatError(f"{name}: bad frame rate {fps}")
    return Motion.from_axis_angle(trans / scaling, poses.reshape(-1, 24, 3), fps=float(fps), skeleton=SMPL24,
                                  metadata={"source": source_name(name)})


def motion_to_smpl_params(motion: Motion, scaling: float = 1.0) -> dict[str, np.ndarray]:
    if not motion.skeleton.same_topology(SMPL24):
        raise MotionFormatError("SMPL parameters need the SMPL-24 skeleton")
    return {
        "smpl_poses": motion.axis_angle().reshape(motion.num_frames, 72).astype(np.float32),
        "smpl_trans": (motion.root_positions * scaling).astype(np.float32),
        "smpl_scaling": np.array([scaling], dtype=np.float32),
    }
