"""AIST++ motion files: ``motions/<sequence>.pkl``, a pickled dict of numpy arrays at 60 fps.

Keys: ``smpl_poses`` (N, 72), ``smpl_trans`` (N, 3) in the scaled body's units, ``smpl_scaling``
(1,) (about 90-100, so trans / scaling is in metres), ``smpl_loss`` (the fit's loss). AIST++'s own
files hold no rate; choreo writes one more key, ``fps``, for a motion at another rate than 60 (its
readers take it, AIST++'s tools ignore it), so such a file reads back at its own pace. Pickles can
run arbitrary code, so they are read by :mod:`choreo.formats.safe_pickle`, which builds numpy
arrays itself and accepts nothing else.
"""

from __future__ import annotations

import pickle

import numpy as np

from ..errors import MotionFormatError
from ..motion import Motion
from ..motion.delivery_options import MAX_DELIVERY_FPS, MIN_DELIVERY_FPS
from .safe_pickle import UnsafePickle, load_numpy_pickle
from .smpl_params import motion_to_smpl_params, smpl_params_to_motion

AISTPP_FPS = 60.0


def read_aistpp_pkl(path, fps: float = AISTPP_FPS) -> Motion:
    """The motion in an AIST++ pickle, at its ``fps`` key's rate when choreo wrote one, else ``fps``."""
    try:
        data = load_numpy_pickle(path)
    except UnsafePickle as error:
        raise MotionFormatError(f"{path}: not a readable AIST++ motion pickle ({error})") from None
    if not isinstance(data, dict) or "smpl_poses" not in data or "smpl_trans" not in data:
        raise MotionFormatError(f"{path}: pickle lacks the smpl_poses and smpl_trans arrays")
    stored = data.get("fps")
    if stored is not None:
        if not (isinstance(stored, (int, float)) and MIN_DELIVERY_FPS <= stored <= MAX_DELIVERY_FPS):
            raise MotionFormatError(f"{path}: its fps must be a number from {MIN_DELIVERY_FPS:g} to {MAX_DELIVERY_FPS:g}")
        fps = float(stored)
    return smpl_params_to_motion(data["smpl_poses"], data["smpl_trans"], data.get("smpl_scaling"), fps, str(path))


def write_aistpp_pkl(motion: Motion, handle, scaling: float = 1.0) -> None:
    """Write the AIST++ dict at the motion's own fps (resample to 60 first for AIST++'s tools); a rate
    other than 60 is kept in an ``fps`` key."""
    arrays = {key: value.astype(np.float64) for key, value in motion_to_smpl_params(motion, scaling).items()}
    arrays["smpl_loss"] = 0.0
    if not np.isclose(motion.fps, AISTPP_FPS):
        arrays["fps"] = float(motion.fps)
    pickle.dump(arrays, handle, protocol=4)
