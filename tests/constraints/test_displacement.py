"""Tests of choreo.constraints.displacement.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.constraints import (
    Constraints,
)
from choreo.constraints.displacement import displace_motion, displace_to_constraints, offset_anchors
from choreo.motion import Motion


def one_channel(length, keys, reach, base=None):
    """Frames ``base`` (zeros) moved to {frame: value} ``keys`` on a single channel."""
    frames = np.zeros((length, 1)) if base is None else np.asarray(base, dtype=np.float64)[:, None]
    values = np.zeros((length, 1))
    mask = np.zeros((length, 1), bool)
    for frame, value in keys.items():
        values[frame, 0] = value
        mask[frame, 0] = True
    return displace_to_constraints(frames, values, mask, reach=reach)[:, 0]


@pytest.mark.survivor
def test_one_keyframe_makes_a_tent_reach_frames_wide():
    moved = one_channel(20, {10: 8.0}, reach=4)
    assert moved.tolist() == [0] * 6 + [0, 2, 4, 6, 8, 6, 4, 2, 0] + [0] * 5


@pytest.mark.survivor
def test_default_reach_is_fifteen_frames():
    frames = np.zeros((60, 1))
    values = np.full((60, 1), 15.0)
    mask = np.zeros((60, 1), bool)
    mask[30] = True
    moved = displace_to_constraints(frames, values, mask)[:, 0]
    expected = [max(0.0, 15.0 - abs(t - 30)) for t in range(60)]
    assert moved.tolist() == expected


@pytest.mark.survivor
def test_close_keyframes_are_bridged_and_far_ones_fade_alone():
    bridged = one_channel(20, {5: 4.0, 11: -2.0}, reach=4)  # 6 frames apart, up to 8 bridged
    expected = [0, 0, 1, 2, 3, 4, 3, 2, 1, 0, -1, -2, -1.5, -1, -0.5, 0, 0, 0, 0, 0]
    np.testing.assert_allclose(bridged, expected)
    edge = one_channel(16, {2: 6.0, 8: 0.0}, reach=3)  # exactly 2 x reach apart: still bridged
    np.testing.assert_allclose(edge, [2, 4, 6, 5, 4, 3, 2, 1, 0, 0, 0, 0, 0, 0, 0, 0])
    apart = one_channel(16, {2: 6.0, 9: 3.0}, reach=3)  # one frame more: each fades on its own
    np.testing.assert_allclose(apart, [2, 4, 6, 4, 2, 0, 0, 1, 2, 3, 2, 1, 0, 0, 0, 0])


@pytest.mark.survivor
def test_three_runs_of_keyframes():
    moved = one_channel(30, {3: 3.0, 4: 3.0, 14: 6.0, 25: 3.0}, reach=3)
    expected = np.zeros(30)
    expected[0:8] = [0, 1, 2, 3, 3, 2, 1, 0]
    expected[11:18] = [0, 2, 4, 6, 4, 2, 0]
    expected[22:29] = [0, 1, 2, 3, 2, 1, 0]
    np.testing.assert_allclose(moved, expected)


@pytest.mark.survivor
def test_displacement_adds_to_the_frames_and_lands_exactly_on_the_values():
    base = np.array([10.0, 11, 12, 13, 14, 15, 16, 17, 18, 19])
    moved = one_channel(10, {4: 20.0}, reach=2)  # from zeros first, then from the ramp
    assert moved.tolist() == [0, 0, 0, 10, 20, 10, 0, 0, 0, 0]
    moved = one_channel(10, {4: 20.0}, reach=2, base=base)  # offset 20 - 14 = 6
    assert moved.tolist() == [10, 11, 12, 13 + 3, 20, 15 + 3, 16, 17, 18, 19]
    moved = one_channel(10, {0: 0.0, 9: 29.0}, reach=20, base=base)  # offsets -10 and +10, bridged
    np.testing.assert_allclose(moved, [(10 + t) + (-10 + 20 * t / 9) for t in range(10)])  # 29 t / 9


@pytest.mark.survivor
def test_displacement_per_sequence_and_channel_with_broadcast_values():
    frames = np.zeros((2, 8, 3), dtype=np.float32)
    frames[1] = 1.0
    original = frames.copy()
    values = np.full((8, 3), 5.0)  # broadcast over both sequences
    mask = np.zeros((2, 8, 3), bool)
    mask[0, 3, 0] = True
    mask[1, 6, 2] = True
    moved = displace_to_constraints(frames, values, mask, reach=2)
    assert moved.dtype == np.float64 and moved.shape == (2, 8, 3)
    np.testing.assert_array_equal(frames, original)  # the input is left alone
    np.testing.assert_allclose(moved[0, :, 0], [0, 0, 2.5, 5, 2.5, 0, 0, 0])
    np.testing.assert_allclose(moved[0, :, 1:], 0)
    np.testing.assert_allclose(moved[1, :, 2], [1, 1, 1, 1, 1, 3, 5, 3])
    np.testing.assert_allclose(moved[1, :, :2], 1)
    shared_mask = np.zeros((8, 1), bool)  # one mask for every sequence and channel
    shared_mask[0] = True
    moved = displace_to_constraints(frames, values, shared_mask, reach=2)
    np.testing.assert_allclose(moved[0, :, 1], [5, 2.5, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(moved[1, :, 2], [5, 3, 1, 1, 1, 1, 1, 1])


@pytest.mark.survivor
def test_displace_motion_meets_the_constraints_and_bends_the_root_across_whole_gaps():
    from choreo.skeleton.rotations import quaternion_multiply

    frames = 100
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 18, 2] = np.linspace(0, 1, frames)  # the left elbow bends over time
    root = np.stack([np.zeros(frames), np.full(frames, 0.9), np.linspace(0, 1, frames)], -1)
    motion = Motion.from_axis_angle(root, axis_angle, fps=30.0)
    given = Constraints.none(frames, 30.0)
    given.root[[0, 99], 0] = [0.5, -0.5]  # x given on the first and last frames only
    given.root_known[[0, 99], 0] = True
    turned = motion.rotations[50].copy()
    turned[18] = quaternion_multiply(np.array([np.cos(0.3), np.sin(0.3), 0, 0]), turned[18])
    given.rotations[50], given.joints_known[50] = turned, True
    bent = displace_motion(motion, given, root_reach=frames)
    # root x: offsets +0.5 and -0.5 interpolated over the whole gap (x was 0 throughout)
    np.testing.assert_allclose(bent.root_positions[:, 0], 0.5 - np.arange(frames) / 99, atol=1e-9)
    np.testing.assert_allclose(bent.root_positions[:, 1:], motion.root_positions[:, 1:], atol=1e-12)
    # the given rotation exactly; 15 frames away and beyond, the motion's own
    np.testing.assert_allclose(np.abs((bent.rotations[50] * turned).sum(-1)), 1.0, atol=1e-9)
    far = np.r_[0:35, 66:frames]
    np.testing.assert_allclose(np.abs((bent.rotations[far] * motion.rotations[far]).sum(-1)), 1.0, atol=1e-9)
    assert not np.allclose(np.abs((bent.rotations[45, 18] * motion.rotations[45, 18]).sum()), 1.0, atol=1e-6)
    short = displace_motion(motion, given)  # the default reach: the root's offsets fade in 15 frames
    np.testing.assert_allclose(short.root_positions[[0, 15, 50, 84, 99], 0], [0.5, 0, 0, 0, -0.5], atol=1e-9)
    with pytest.raises(ValueError, match="constraints cover 100 frames, the motion 99"):
        displace_motion(motion.slice_frames(0, 99), given)


@pytest.mark.survivor
def test_offset_anchors_by_hand():
    anchors, values = offset_anchors(np.array([10]), np.array([5.0]), 4)
    assert anchors.tolist() == [6, 10, 14] and values.tolist() == [0, 5, 0] and anchors.dtype == np.float64
    anchors, values = offset_anchors(np.array([2, 3, 20]), np.array([1.0, 2.0, 3.0]), 4)
    assert anchors.tolist() == [-2, 2, 3, 7, 16, 20, 24]
    assert values.tolist() == [0, 1, 2, 0, 0, 3, 0]
    anchors, values = offset_anchors(np.array([0, 8, 17, 40]), np.array([1.0, 2.0, 3.0, 4.0]), 4)
    assert anchors.tolist() == [-4, 0, 8, 12, 13, 17, 21, 36, 40, 44]
    assert values.tolist() == [0, 1, 2, 0, 0, 3, 0, 0, 4, 0]


@pytest.mark.survivor
def test_reach_zero_moves_only_the_given_frames():
    moved = one_channel(10, {2: 5.0, 7: 10.0}, reach=0)
    assert moved.tolist() == [0, 0, 5, 0, 0, 0, 0, 10, 0, 0]
