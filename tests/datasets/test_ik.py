"""Inverse kinematics recovers poses that forward kinematics produced."""

import numpy as np
import pytest

from choreo.datasets.ik import IKConfig, fit_rotations, initial_pose, kabsch, performer_skeleton, swing
from choreo.errors import ParameterError
from choreo.motion import Motion
from choreo.skeleton import SMPL24, axis_angle_to_matrix, quaternion_to_axis_angle

# What M2D observes: no pelvis, mid-spine, neck, collars or hands (see choreo.datasets.m2d).
M2D_LIKE = [j for j in range(24) if j not in (0, 6, 9, 12, 13, 14, 22, 23)]


def smooth_motion(frames: int = 60, seed: int = 0, skeleton=SMPL24) -> Motion:
    """Random but smooth rotations of every joint (up to ~45 degrees) and a wandering root."""
    rng = np.random.default_rng(seed)
    axis_angle = np.clip(np.cumsum(rng.normal(scale=0.04, size=(frames, 24, 3)), axis=0), -0.8, 0.8)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0.0, 0.9, 0.0]
    return Motion.from_axis_angle(root, axis_angle, skeleton=skeleton)


def test_every_joint_observed_recovers_positions_within_5mm():
    motion = smooth_motion()
    targets = motion.joint_positions()
    result = fit_rotations(targets, list(range(24)), SMPL24)
    fitted = Motion(result.root_positions, result.rotations).joint_positions()
    assert np.abs(fitted - targets).max() < 0.005
    assert result.errors.shape == (60, 24) and result.mean_error < 0.002


def test_m2d_like_subset_on_the_true_bones():
    motion = smooth_motion(seed=1)
    targets = motion.joint_positions()[:, M2D_LIKE]
    result = fit_rotations(targets, M2D_LIKE, SMPL24)
    assert result.mean_error < 0.005
    assert result.errors.max() < 0.02


def test_performer_skeleton_takes_the_data_proportions():
    longer = SMPL24.with_offsets(SMPL24.offsets * 1.1)
    motion = smooth_motion(seed=2, skeleton=longer)
    targets = motion.joint_positions()[:, M2D_LIKE]
    skeleton = performer_skeleton(targets, M2D_LIKE)
    # a bone between two observed joints is measured exactly (thigh: hip -> knee)
    assert skeleton.bone_lengths()[4] == pytest.approx(longer.bone_lengths()[4], rel=1e-6)
    # the unobserved pelvis: hips and lower back keep their mutual distances
    fitted, truth = skeleton.rest_positions(), longer.rest_positions()
    for a, b in ((1, 2), (1, 3), (2, 3)):
        expected = np.linalg.norm(truth[a] - truth[b])
        assert np.linalg.norm(fitted[a] - fitted[b]) == pytest.approx(expected, rel=1e-3)
    result = fit_rotations(targets, M2D_LIKE, skeleton)
    assert result.mean_error < 0.01  # chains through unobserved joints bend, so not exact


def test_rest_pose_gives_identity_rotations():
    motion = Motion.rest(5)
    result = fit_rotations(motion.joint_positions(), list(range(24)), SMPL24, IKConfig(iterations=20))
    assert np.abs(quaternion_to_axis_angle(result.rotations)).max() < 1e-3
    assert np.allclose(result.root_positions, motion.root_positions, atol=1e-4)


def test_rest_pose_from_a_subset_starts_at_identity():
    motion = Motion.rest(3)
    targets = motion.joint_positions()[:, M2D_LIKE]
    local, root = initial_pose(targets, M2D_LIKE, SMPL24)
    assert np.allclose(local, np.eye(3), atol=1e-6)
    assert np.allclose(root, motion.root_positions, atol=1e-6)


def test_swing_and_kabsch():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    b[0] = -a[0]  # opposite directions need the half-turn branch
    turned = np.einsum("tij,tj->ti", swing(a, b), a)
    assert np.allclose(turned / np.linalg.norm(turned, axis=-1, keepdims=True),
                       b / np.linalg.norm(b, axis=-1, keepdims=True), atol=1e-9)
    rotations = axis_angle_to_matrix(rng.normal(size=(10, 3)))
    points = rng.normal(size=(10, 4, 3))
    moved = np.einsum("tij,tnj->tni", rotations, points)
    assert np.allclose(kabsch(points, moved), rotations, atol=1e-9)


def test_bad_targets_are_refused():
    with pytest.raises(ParameterError):
        fit_rotations(np.zeros((4, 3, 3)), [1, 2], SMPL24)
    with pytest.raises(ParameterError):
        fit_rotations(np.full((4, 2, 3), np.nan), [1, 2], SMPL24)
