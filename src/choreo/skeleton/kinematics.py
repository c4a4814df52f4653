"""Batched forward kinematics, written once for torch tensors (differentiable, for training
losses) and numpy arrays (without importing torch)."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .rotations import array_namespace


def forward_kinematics_torch(local_rotmats, root_positions, offsets, parents: Sequence[int]):
    """Joint positions from local rotations (tensors or arrays: the kind given is returned).

    Args:
        local_rotmats: (..., J, 3, 3) rotation of each joint relative to its parent.
        root_positions: (..., 3) position of joint 0.
        offsets: (J, 3) or (..., J, 3) rest offset of each joint from its parent.
        parents: parent index per joint, parents before children.

    Returns:
        (..., J, 3) world positions.
    """
    xp = array_namespace(local_rotmats, root_positions, offsets)
    offsets = xp.broadcast_to(xp.astype(offsets, local_rotmats.dtype), tuple(local_rotmats.shape[:-2]) + (3,))
    global_rots: list = []
    positions: list = []
    for j, p in enumerate(parents):
        if p < 0:
            global_rots.append(local_rotmats[..., j, :, :])
            positions.append(root_positions)
        else:
            global_rots.append(global_rots[p] @ local_rotmats[..., j, :, :])
            positions.append(positions[p] + (global_rots[p] @ offsets[..., j, :, None])[..., 0])
    return xp.stack(positions, axis=-2)


def forward_kinematics(
    local_rotmats: np.ndarray,
    root_positions: np.ndarray,
    offsets: np.ndarray,
    parents: Sequence[int],
) -> np.ndarray:
    """numpy twin of :func:`forward_kinematics_torch` (same shapes), computed in float64."""
    as64 = lambda a: np.asarray(a, dtype=np.float64)  # noqa: E731
    return forward_kinematics_torch(as64(local_rotmats), as64(root_positions), as64(offsets), parents)


def global_rotations(local_rotmats: np.ndarray, parents: Sequence[int]) -> np.ndarray:
    """(..., J, 3, 3) world orientation of each joint from local ones."""
    out = np.empty_like(local_rotmats)
    for j, p in enumerate(parents):
        out[..., j, :, :] = local_rotmats[..., j, :, :] if p < 0 else out[..., p, :, :] @ local_rotmats[..., j, :, :]
    return out
