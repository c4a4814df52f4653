"""Rotation conversions and forward kinematics: against each other, scipy and hand-computed poses."""

import math

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from choreo.skeleton import (
    PARENTS,
    SMPL24,
    axis_angle_to_matrix,
    axis_angle_to_quaternion,
    euler_to_matrix,
    forward_kinematics,
    forward_kinematics_torch,
    matrix_to_axis_angle,
    matrix_to_euler,
    matrix_to_quaternion,
    matrix_to_rot6d,
    quaternion_multiply,
    quaternion_slerp,
    quaternion_to_axis_angle,
    quaternion_to_matrix,
    rot6d_to_matrix,
)


@pytest.fixture
def random_axis_angle():
    rng = np.random.default_rng(7)
    directions = rng.normal(size=(500, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    angles = rng.uniform(0, math.pi, size=(500, 1))
    angles[:5] = [[0.0], [1e-9], [math.pi], [math.pi - 1e-7], [1e-4]]  # edge cases
    return directions * angles


def test_axis_angle_matrix_agrees_with_scipy(random_axis_angle):
    ours = axis_angle_to_matrix(random_axis_angle)
    np.testing.assert_allclose(ours, Rotation.from_rotvec(random_axis_angle).as_matrix(), atol=1e-12)


def test_round_trips_through_every_representation(random_axis_angle):
    matrix = axis_angle_to_matrix(random_axis_angle)
    np.testing.assert_allclose(quaternion_to_matrix(matrix_to_quaternion(matrix)), matrix, atol=1e-12)
    np.testing.assert_allclose(rot6d_to_matrix(matrix_to_rot6d(matrix)), matrix, atol=1e-12)
    np.testing.assert_allclose(axis_angle_to_matrix(matrix_to_axis_angle(matrix)), matrix, atol=1e-7)
    quat = axis_angle_to_quaternion(random_axis_angle)
    np.testing.assert_allclose(quaternion_to_matrix(quat), matrix, atol=1e-12)
    np.testing.assert_allclose(axis_angle_to_matrix(quaternion_to_axis_angle(quat)), matrix, atol=1e-7)


@pytest.mark.parametrize("order", ["ZXY", "XYZ", "ZYX", "YXZ", "XZY", "YZX"])
def test_euler_matches_scipy_intrinsic_and_inverts(order, random_axis_angle):
    matrix = axis_angle_to_matrix(random_axis_angle)
    angles = matrix_to_euler(matrix, order)
    np.testing.assert_allclose(euler_to_matrix(angles, order), matrix, atol=1e-10)
    np.testing.assert_allclose(Rotation.from_euler(order, angles).as_matrix(), matrix, atol=1e-10)


def test_euler_gimbal_lock_still_reconstructs():
    angles = np.array([[0.3, math.pi / 2, -0.2], [0.1, -math.pi / 2, 0.5]])
    matrix = euler_to_matrix(angles, "ZXY")
    np.testing.assert_allclose(euler_to_matrix(matrix_to_euler(matrix, "ZXY"), "ZXY"), matrix, atol=1e-9)


def test_known_rotations():
    quarter_turn_z = axis_angle_to_matrix(np.array([0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(quarter_turn_z @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-12)
    half_turn_y = axis_angle_to_quaternion(np.array([0.0, math.pi, 0.0]))
    np.testing.assert_allclose(np.abs(half_turn_y), [0.0, 0.0, 1.0, 0.0], atol=1e-12)
    # Two quarter turns about X compose to a half turn.
    q = axis_angle_to_quaternion(np.array([math.pi / 2, 0.0, 0.0]))
    np.testing.assert_allclose(quaternion_to_matrix(quaternion_multiply(q, q)), np.diag([1.0, -1.0, -1.0]), atol=1e-12)


def test_rot6d_accepts_any_six_numbers():
    raw = np.random.default_rng(0).normal(size=(100, 6))
    matrix = rot6d_to_matrix(raw)
    np.testing.assert_allclose(matrix @ np.swapaxes(matrix, -1, -2), np.broadcast_to(np.eye(3), matrix.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(matrix), 1.0, atol=1e-12)


def test_slerp_halfway_is_half_the_angle():
    a = axis_angle_to_quaternion(np.zeros(3))
    b = axis_angle_to_quaternion(np.array([0.0, 1.2, 0.0]))
    mid = quaternion_slerp(a, b, np.array(0.5))
    np.testing.assert_allclose(quaternion_to_axis_angle(mid), [0.0, 0.6, 0.0], atol=1e-12)


def test_torch_and_numpy_agree_and_torch_has_gradients(random_axis_angle):
    tensor = torch.tensor(random_axis_angle[:50], requires_grad=True)
    matrix = axis_angle_to_matrix(tensor)
    assert isinstance(matrix, torch.Tensor)
    np.testing.assert_allclose(matrix.detach().numpy(), axis_angle_to_matrix(random_axis_angle[:50]), atol=1e-12)
    matrix_to_rot6d(matrix).sum().backward()
    assert torch.isfinite(tensor.grad).all()


def test_skeleton_tree_is_smpl24():
    assert SMPL24.num_joints == 24
    assert SMPL24.names[7] == "l_ankle" and SMPL24.names[11] == "r_foot"
    assert SMPL24.parents == tuple(PARENTS)
    rest = SMPL24.rest_positions()
    assert rest[15, 1] > 0.5 and rest[10, 1] < -0.9  # head up, feet down: Y is up, metres
    assert rest[16, 0] > 0 > rest[17, 0]  # +X is the body's left


def _identity(frames=1):
    return np.broadcast_to(np.eye(3), (frames, 24, 3, 3)).copy()


def test_fk_rest_pose_is_template_plus_root():
    root = np.array([[1.0, 2.0, 3.0]])
    positions = forward_kinematics(_identity(), root, SMPL24.offsets, SMPL24.parents)
    np.testing.assert_allclose(positions[0], SMPL24.rest_positions() + root[0], atol=1e-12)


def test_fk_hand_computed_shoulder_raise():
    """l_shoulder (16) turned +90 deg about Z swings the elbow from +X to +Y: (x, y, z) -> (-y, x, z)."""
    rotmats = _identity()
    rotmats[0, 16] = axis_angle_to_matrix(np.array([0.0, 0.0, math.pi / 2]))
    positions = forward_kinematics(rotmats, np.zeros((1, 3)), SMPL24.offsets, SMPL24.parents)
    shoulder = SMPL24.rest_positions()[16]
    x, y, z = SMPL24.offsets[18]
    np.testing.assert_allclose(positions[0, 18], shoulder + [-y, x, z], atol=1e-12)
    np.testing.assert_allclose(positions[0, 16], shoulder, atol=1e-12)  # a joint's own rotation moves its children only


def test_fk_hand_computed_root_half_turn():
    rotmats = _identity()
    rotmats[0, 0] = np.diag([-1.0, 1.0, -1.0])  # 180 deg about Y
    positions = forward_kinematics(rotmats, np.zeros((1, 3)), SMPL24.offsets, SMPL24.parents)
    x, y, z = SMPL24.offsets[1]
    np.testing.assert_allclose(positions[0, 1], [-x, y, -z], atol=1e-12)
    np.testing.assert_allclose(positions[0, 15], SMPL24.rest_positions()[15] * [-1, 1, -1], atol=1e-12)


def test_fk_torch_batched_matches_numpy_and_preserves_bone_lengths():
    rng = np.random.default_rng(1)
    rotmats = axis_angle_to_matrix(rng.normal(size=(2, 10, 24, 3)))
    root = rng.normal(size=(2, 10, 3))
    ours = forward_kinematics_torch(torch.tensor(rotmats), torch.tensor(root), torch.tensor(SMPL24.offsets), PARENTS)
    np.testing.assert_allclose(ours.numpy(), forward_kinematics(rotmats, root, SMPL24.offsets, PARENTS), atol=1e-12)
    positions = ours.numpy()
    bones = np.linalg.norm(positions[..., 1:, :] - positions[..., list(PARENTS[1:]), :], axis=-1)
    np.testing.assert_allclose(bones, np.broadcast_to(SMPL24.bone_lengths()[1:], bones.shape), atol=1e-12)
