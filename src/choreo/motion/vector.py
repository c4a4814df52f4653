"""The 151-d frame vector the diffusion model works in: 4 contacts | 3 root | 24 x 6D."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..skeleton import SMPL24
from ..skeleton import rotations as rot
from .contacts import foot_contacts
from .motion import DEFAULT_FPS, Motion, frame_chunks

CONTACT_SLICE = slice(0, 4)
ROOT_SLICE = slice(4, 7)
ROTATION_SLICE = slice(7, 7 + 24 * 6)
FRAME_DIM = 7 + 24 * 6  # 151


def motion_to_vector(motion: Motion) -> np.ndarray:
    """(T, 151) float32 frame vectors; contacts are computed from the motion itself."""
    if not motion.skeleton.same_topology(SMPL24):
        raise ParameterError("the 151-d frame vector is defined for the SMPL-24 skeleton")
    contacts = foot_contacts(motion.joint_positions(), motion.fps)
    rot6d = rot.matrix_to_rot6d(motion.rotation_matrices()).reshape(motion.num_frames, -1)
    return np.concatenate([contacts, motion.root_positions, rot6d], axis=1).astype(np.float32)


def vector_to_motion(vectors: np.ndarray, fps: float = DEFAULT_FPS, **kwargs) -> tuple[Motion, np.ndarray]:
    """Inverse of :func:`motion_to_vector`: returns the motion and its (T, 4) contact channels.

    Any 6 numbers per joint decode to a valid rotation (Gram-Schmidt), so model output needs no
    clean-up before it becomes a motion.
    """
    vectors = np.asarray(vectors)  # in float64 a chunk at a time: a whole song's copy would be large
    if vectors.ndim != 2 or vectors.shape[1] != FRAME_DIM:
        raise ParameterError(f"frame vectors must have shape (T, {FRAME_DIM}), got {vectors.shape}")
    quaternions = np.zeros((len(vectors), 24, 4))
    for chunk in frame_chunks(len(vectors)):
        rot6d = np.asarray(vectors[chunk, ROTATION_SLICE], dtype=np.float64).reshape(-1, 24, 6)
        quaternions[chunk] = rot.matrix_to_quaternion(rot.rot6d_to_matrix(rot6d))
    root = np.array(vectors[:, ROOT_SLICE], dtype=np.float64)
    motion = Motion(root, quaternions, fps=fps, **kwargs)
    return motion, np.array(vectors[:, CONTACT_SLICE], dtype=np.float64)
