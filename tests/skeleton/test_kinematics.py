"""Tests of choreo.skeleton.kinematics."""

import numpy as np
import torch

from choreo.skeleton import (
    PARENTS,
    SMPL24,
    axis_angle_to_matrix,
    forward_kinematics,
    forward_kinematics_torch,
)


def test_fk_torch_batched_matches_numpy_and_preserves_bone_lengths():
    rng = np.random.default_rng(1)
    rotmats = axis_angle_to_matrix(rng.normal(size=(2, 10, 24, 3)))
    root = rng.normal(size=(2, 10, 3))
    ours = forward_kinematics_torch(torch.tensor(rotmats), torch.tensor(root), torch.tensor(SMPL24.offsets), PARENTS)
    np.testing.assert_allclose(ours.numpy(), forward_kinematics(rotmats, root, SMPL24.offsets, PARENTS), atol=1e-12)
    positions = ours.numpy()
    bones = np.linalg.norm(positions[..., 1:, :] - positions[..., list(PARENTS[1:]), :], axis=-1)
    np.testing.assert_allclose(bones, np.broadcast_to(SMPL24.bone_lengths()[1:], bones.shape), atol=1e-12)
