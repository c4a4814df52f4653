"""NPZ with the AIST++ keys, plus what a reader needs to be self-sufficient.

Keys written: ``smpl_poses`` (T, 72) axis-angle, ``smpl_trans`` (T, 3) metres, ``smpl_scaling``
(1,) = 1, ``fps``, ``joint_positions`` (T, 24, 3) metres Y-up (for metrics without FK),
``offsets`` (24, 3) the skeleton's bone offsets, and ``metadata`` (a JSON string). Any NPZ with
``smpl_poses`` and ``smpl_trans`` reads back; fps defaults to 30 when absent.
"""

from __future__ import annotations

import json

import numpy as np

from ..errors import MotionFormatError
from ..fileio import json_safe
from ..motion import Motion, source_name
from ..motion.motion import file_metadata
from ..skeleton import SMPL24
from .safe_arrays import load_npz
from .smpl_params import first_number, motion_to_smpl_params, smpl_params_to_motion

DEFAULT_FPS = 30.0


def write_npz(motion: Motion, handle) -> None:
    arrays = motion_to_smpl_params(motion)
    arrays["fps"] = np.array(motion.fps, dtype=np.float64)
    arrays["joint_positions"] = motion.joint_positions(np.float32)
    arrays["offsets"] = motion.skeleton.offsets.astype(np.float64)
    arrays["metadata"] = np.array(json.dumps(json_safe(motion.metadata), default=str))
    np.savez(handle, **arrays)


def _load(path) -> dict[str, np.ndarray]:
    return load_npz(path)  # sizes checked before anything is decompressed


def read_npz(path) -> Motion:
    data = _load(path)
    if "smpl_poses" not in data or "smpl_trans" not in data:
        raise MotionFormatError(f"{path}: NPZ lacks the smpl_poses and smpl_trans arrays")
    fps = first_number(data["fps"], "fps", str(path)) if "fps" in data else DEFAULT_FPS
    motion = smpl_params_to_motion(data["smpl_poses"], data["smpl_trans"], data.get("smpl_scaling"), fps, str(path))
    offsets = _numeric(data.get("offsets"), (24, 3))
    if offsets is not None:
        motion = motion.with_skeleton(SMPL24.with_offsets(offsets))
    if "metadata" in data:
        try:
            metadata = json.loads(str(data["metadata"]))
            if isinstance(metadata, dict):
                motion.metadata = {**file_metadata(metadata), "source": source_name(path)}
        except (ValueError, RecursionError):  # metadata is optional: unreadable JSON is ignored
            pass
    return motion


def read_npz_joint_positions(path) -> np.ndarray | None:
    """The stored (T, 24, 3) joint positions, if the file has them."""
    data = _load(path)
    return _numeric(data.get("joint_positions"), None)


def _numeric(value, shape: tuple | None) -> np.ndarray | None:
    """An optional array as finite float64 of ``shape`` (any shape if None), else None: a damaged
    optional entry is ignored (offsets from the template, positions from the rotations)."""
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "fiub":
        return None
    if shape is not None and value.shape != shape:
        return None
    value = value.astype(np.float64)
    return value if np.isfinite(value).all() else None
