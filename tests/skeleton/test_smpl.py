"""Tests of choreo.skeleton.smpl.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from choreo.skeleton import (
    PARENTS,
    SMPL24,
    Skeleton,
    axis_angle_to_matrix,
    forward_kinematics,
    global_rotations,
)


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


def chain(parents=(-1, 0, 1), offsets=None) -> Skeleton:
    return Skeleton(("a", "b", "c"), tuple(parents), np.eye(3) if offsets is None else offsets)


@pytest.mark.survivor
def test_a_skeleton_keeps_its_offsets_as_float64_and_checks_its_tree():
    tree = chain(offsets=[[0, 0, 0], [0, 1, 0], [2, 0, 0]])  # lists of ints in
    assert tree.offsets.dtype == np.float64 and tree.offsets.shape == (3, 3)
    with pytest.raises(ValueError, match="^one parent per joint is required$"):
        Skeleton(("a", "b"), (-1,), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="^parents must precede their children$"):
        chain(parents=(-1, 2, 1))
    with pytest.raises(ValueError, match="^parents must precede their children$"):
        chain(parents=(-1, 1, 1))  # a joint that is its own parent


@pytest.mark.survivor
def test_skeleton_helpers():
    tree = chain(parents=(-1, 0, 0), offsets=[[0, 0, 0], [0, 3, 4], [1, 0, 0]])
    assert tree.index("c") == 2 and tree.children(0) == [1, 2] and tree.children(2) == []
    np.testing.assert_allclose(tree.bone_lengths(), [0.0, 5.0, 1.0])
    moved = tree.with_offsets(np.array([[0, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=int))
    assert moved.offsets.dtype == np.float64 and moved.same_topology(tree)
    assert not tree.same_topology(chain(parents=(-1, 0, 1)))  # same names, other parents
    assert not tree.same_topology(Skeleton(("a", "b", "d"), (-1, 0, 0), np.zeros((3, 3))))


@pytest.mark.survivor
def test_global_rotations_compose_down_the_tree_and_agree_with_forward_kinematics():
    rng = np.random.default_rng(0)
    local = Rotation.random(2 * 24, random_state=1).as_matrix().reshape(2, 24, 3, 3)
    world = global_rotations(local, SMPL24.parents)
    for j, p in enumerate(SMPL24.parents):
        expected = local[:, j] if p < 0 else world[:, p] @ local[:, j]
        np.testing.assert_allclose(world[:, j], expected, atol=1e-12)
    np.testing.assert_allclose(world[:, 0], local[:, 0])  # the root's own
    np.testing.assert_allclose(world[:, 6], local[:, 0] @ local[:, 3] @ local[:, 6], atol=1e-12)  # pelvis, spine1, spine2
    root = rng.normal(size=(2, 3))
    positions = forward_kinematics(local, root, SMPL24.offsets, SMPL24.parents)
    for j, p in enumerate(SMPL24.parents):
        if p >= 0:  # a joint sits at its parent plus the parent's world rotation of its offset
            np.testing.assert_allclose(positions[:, j], positions[:, p] + world[:, p] @ SMPL24.offsets[j], atol=1e-12)


@pytest.mark.survivor
def test_forward_kinematics_computes_in_float64():
    local = np.broadcast_to(np.eye(3, dtype=np.float32), (2, 24, 3, 3))
    positions = forward_kinematics(local, np.zeros((2, 3), np.float32), SMPL24.offsets.astype(np.float32), SMPL24.parents)
    assert positions.dtype == np.float64
