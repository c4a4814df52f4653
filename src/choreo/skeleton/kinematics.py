"""Batched forward kinematics, in torch (differentiable, for training losses) and numpy."""

from __future__ import annotations

from typing import Sequence

import numpy as np
import torch


def forward_kinematics_torch(
    local_rotmats: torch.Tensor,
    root_positions: torch.Tensor,
    offsets: torch.Tensor,
    parents: Sequence[int],
) -> torch.Tensor:
    """Joint positions from local rotations.

    Args:
        local_rotmats: (..., J, 3, 3) rotation of each joint relative to its parent.
        root_positions: (..., 3) position of joint 0.
        offsets: (J, 3) or (..., J, 3) rest offset of each joint from its parent.
        parents: parent index per joint, parents before children.

    Returns:
        (..., J, 3) world positions.
    """
    offsets = offsets.to(local_rotmats.dtype).expand(local_rotmats.shape[:-2] + (3,))
    global_rots: list[torch.Tensor] = []
    positions: list[torch.Tensor] = []
    for j, p in enumerate(parents):
        if p < 0:
            global_rots.append(local_rotmats[..., j, :, :])
            positions.append(root_positions)
        else:
            global_rots.append(global_rots[p] @ local_rotmats[..., j, :, :])
            positions.append(positions[p] + (global_rots[p] @ offsets[..., j, :, None])[..., 0])
    return torch.stack(positions, dim=-2)


def forward_kinematics(
    local_rotmats: np.ndarray,
    root_positions: np.ndarray,
    offsets: np.ndarray,
    parents: Sequence[int],
) -> np.ndarray:
    """numpy twin of :func:`forward_kinematics_torch` (same shapes), computed in float64."""
    positions = forward_kinematics_torch(
        torch.from_numpy(np.asarray(local_rotmats, dtype=np.float64)),
        torch.from_numpy(np.asarray(root_positions, dtype=np.float64)),
        torch.from_numpy(np.asarray(offsets, dtype=np.float64)),
        parents,
    )
    return positions.numpy()


def global_rotations(local_rotmats: np.ndarray, parents: Sequence[int]) -> np.ndarray:
    """(..., J, 3, 3) world orientation of each joint from local ones."""
    out = np.empty_like(local_rotmats)
    for j, p in enumerate(parents):
        out[..., j, :, :] = local_rotmats[..., j, :, :] if p < 0 else out[..., p, :, :] @ local_rotmats[..., j, :, :]
    return out
