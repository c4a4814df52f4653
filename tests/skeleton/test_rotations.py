"""Tests of choreo.skeleton.rotations.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import math
import subprocess
import sys

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from choreo.skeleton import (
    axis_angle_to_matrix,
    axis_angle_to_quaternion,
    euler_to_matrix,
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
from choreo.skeleton.rotations import elementary_rotation


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


@pytest.mark.survivor
def test_elementary_and_euler_rotations_of_two_dimensional_batches():
    angles = np.random.default_rng(2).uniform(-3, 3, size=(4, 5))
    for axis in "XYZ":
        matrices = elementary_rotation(angles, axis)
        assert matrices.shape == (4, 5, 3, 3)
        expected = Rotation.from_euler(axis.lower(), angles.reshape(-1, 1)).as_matrix().reshape(4, 5, 3, 3)
        np.testing.assert_allclose(matrices, expected, atol=1e-12)
    triples = np.random.default_rng(3).uniform(-3, 3, size=(4, 5, 3))
    expected = Rotation.from_euler("ZXY", triples.reshape(-1, 3)).as_matrix().reshape(4, 5, 3, 3)
    np.testing.assert_allclose(euler_to_matrix(triples, "ZXY"), expected, atol=1e-12)


@pytest.mark.survivor
def test_a_half_turn_and_the_identity_convert_exactly():
    half_turn = np.diag([1.0, -1.0, -1.0])  # w = 0: the square root of exactly zero
    q = matrix_to_quaternion(half_turn)
    np.testing.assert_allclose(np.abs(q), [0.0, 1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(matrix_to_quaternion(np.eye(3)), [1.0, 0.0, 0.0, 0.0], atol=1e-15)
    small = Rotation.from_rotvec([0.3, 0.0, 0.0]).as_matrix()  # a trace-derived term between 0 and 1
    np.testing.assert_allclose(np.abs(matrix_to_quaternion(small)), np.abs(Rotation.from_matrix(small).as_quat()[[3, 0, 1, 2]]),
                               atol=1e-12)


@pytest.mark.survivor
def test_numpy_rotations_never_import_torch():
    code = ("import sys, numpy as np; from choreo.skeleton.rotations import quaternion_to_matrix, matrix_to_quaternion; "
            "matrix_to_quaternion(quaternion_to_matrix(np.array([1.0, 0, 0, 0]))); "
            "print('torch' in sys.modules, 'array_api_compat.numpy' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "False"]  # numpy itself, not the compat wrapper (0.2 s of imports)


@pytest.mark.survivor
def test_the_gradient_through_a_half_turn_is_finite():
    torch = pytest.importorskip("torch")
    matrix = torch.tensor(np.diag([1.0, -1.0, -1.0]), requires_grad=True)  # w = sqrt(0)
    matrix_to_quaternion(matrix).sum().backward()
    assert torch.isfinite(matrix.grad).all()
