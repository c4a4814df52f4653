"""Inverse kinematics recovers positions produced by forward kinematics."""

import numpy as np

from choreo.datasets.ik import IKConfig, fit_bone_lengths, fit_rotations
from choreo.motion import Motion
from choreo.skeleton import SMPL24


def smooth_motion(frames=60, seed=0):
    rng = np.random.default_rng(seed)
    axis_angle = np.cumsum(rng.normal(scale=0.04, size=(frames, 24, 3)), axis=0)
    axis_angle = np.clip(axis_angle, -0.8, 0.8)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.9, 0]
    return Motion.from_axis_angle(root, axis_angle)


def test_ik_recovers_all_joint_positions():
    motion = smooth_motion()
    targets = motion.joint_positions()
    result = fit_rotations(targets, list(range(24)), motion.root_positions, SMPL24, IKConfig(iterations=300))
    fitted = Motion(result.root_positions, result.rotations).joint_positions()
    assert np.abs(fitted - targets).max() < 0.005  # 5 mm
    assert result.per_joint_error.mean() < 0.002


def test_ik_from_a_subset_of_joints_with_rescaled_bones():
    motion = smooth_motion(seed=1).with_skeleton(SMPL24.with_offsets(SMPL24.offsets * 1.1))
    observed = [j for j in range(24) if j not in (6, 9, 13, 14)]  # no mid-spine, no collars: as in M2D
    targets = motion.joint_positions()[:, observed]
    skeleton = fit_bone_lengths(targets, [0] + observed[1:] if observed[0] == 0 else observed)
    assert abs(skeleton.bone_lengths()[4] / SMPL24.bone_lengths()[4] - 1.1) < 1e-6  # thigh scaled like the data
    result = fit_rotations(targets, observed, motion.root_positions, skeleton)
    assert result.per_joint_error.mean() < 0.01


def test_rest_pose_gives_identity_rotations():
    motion = Motion.rest(5)
    result = fit_rotations(motion.joint_positions(), list(range(24)), motion.root_positions, SMPL24, IKConfig(iterations=50))
    assert np.abs(np.abs(result.rotations[..., 0]) - 1).max() < 1e-3
