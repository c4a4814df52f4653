"""The speed limit: a one-frame spin or dash is spread over its neighbours until no joint moves
faster than real dancers do, ends and given frames untouched, movements within the limits left
bit for bit."""

import numpy as np
import pytest

from choreo.finishing import finish
from choreo.finishing.speed_limit import (REAL_FLOOR_STEP, REAL_JOINT_SPEED, SpeedLimitConfig, frames_around, smoothed,
                                          speed_limit)
from choreo.motion import Motion
from choreo.motion.stitch import facing_yaw


def joint_speeds(motion: Motion) -> np.ndarray:
    """(T-1,) the fastest joint's speed (m/s) between consecutive frames, by a literal loop."""
    positions = motion.joint_positions()
    return np.array([max(np.linalg.norm(positions[t + 1, j] - positions[t, j]) for j in range(24)) * motion.fps
                     for t in range(len(positions) - 1)])


def spinning(frames=60, at=30, turn=np.radians(120), fps=30.0) -> Motion:
    """Arms out, facing +z, then turned by ``turn`` about +y between frames ``at`` and ``at + 1``."""
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 16, 2], axis_angle[:, 17, 2] = -1.3, 1.3  # shoulders: arms raised sideways
    axis_angle[at + 1:, 0, 1] = turn
    root = np.tile([0.0, 0.95, 0.0], (frames, 1))
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def test_a_one_frame_spin_is_spread_until_no_joint_is_faster_than_real_dancers():
    motion = spinning()
    assert joint_speeds(motion).max() > 1.5 * REAL_JOINT_SPEED  # the hands fly round in one frame
    limited = speed_limit(motion)
    assert joint_speeds(limited).max() <= REAL_JOINT_SPEED
    headings = np.unwrap(facing_yaw(limited.joint_positions()))
    assert headings[-1] - headings[0] == pytest.approx(np.radians(120), abs=1e-9)  # the whole turn still happens
    assert (np.diff(headings) >= -1e-12).all()  # and only one way
    untouched = np.r_[0:20, 41:60]  # far from the spin: bit for bit
    np.testing.assert_array_equal(limited.rotations[untouched], motion.rotations[untouched])
    np.testing.assert_array_equal(limited.root_positions, motion.root_positions)


def test_movement_within_the_limits_is_left_bit_for_bit():
    motion = spinning(turn=np.radians(10))
    assert joint_speeds(motion).max() < REAL_JOINT_SPEED
    limited = speed_limit(motion)
    np.testing.assert_array_equal(limited.rotations, motion.rotations)
    np.testing.assert_array_equal(limited.root_positions, motion.root_positions)


def test_a_root_dash_is_spread_and_ends_where_it_ended():
    frames = 40
    root = np.tile([0.0, 0.95, 0.0], (frames, 1))
    root[21:, 0] = 0.6  # 60 cm sideways in one frame
    motion = Motion.from_axis_angle(root, np.zeros((frames, 24, 3)), fps=30.0)
    limited = speed_limit(motion, config=SpeedLimitConfig(joint_speed=1e9))  # the floor limit alone
    steps = np.linalg.norm(np.diff(limited.root_positions[:, [0, 2]], axis=0), axis=-1)
    assert steps.max() <= REAL_FLOOR_STEP and steps.sum() == pytest.approx(0.6, abs=1e-9)
    np.testing.assert_array_equal(limited.root_positions[[0, -1]], motion.root_positions[[0, -1]])
    np.testing.assert_array_equal(limited.root_positions[:, 1], motion.root_positions[:, 1])  # height untouched
    at_60 = Motion.from_axis_angle(root, np.zeros((frames, 24, 3)), fps=60.0)  # a step per frame at 60 fps is half
    steps = np.linalg.norm(np.diff(speed_limit(at_60, config=SpeedLimitConfig(joint_speed=1e9)).root_positions, axis=0), axis=-1)
    assert REAL_FLOOR_STEP / 2 - 0.02 < steps.max() <= REAL_FLOOR_STEP / 2


def test_given_frames_keep_their_values():
    motion = spinning()
    fixed = np.zeros(motion.num_frames, bool)
    fixed[[30, 31]] = True  # the spin itself is given: it stays, the rest cannot absorb it
    limited = speed_limit(motion, fixed)
    np.testing.assert_array_equal(limited.rotations[[30, 31]], motion.rotations[[30, 31]])
    fixed[[30, 31]], fixed[28] = False, True
    limited = speed_limit(motion, fixed)
    np.testing.assert_array_equal(limited.rotations[28], motion.rotations[28])
    assert joint_speeds(limited).max() <= REAL_JOINT_SPEED


def test_smoothing_by_hand_and_quaternions_on_one_hemisphere():
    values = np.array([[0.0], [0.0], [4.0], [8.0], [8.0]])
    np.testing.assert_allclose(smoothed(values, np.array([1, 2, 3])), [[1.0], [4.0], [7.0]])
    half_turn = np.array([np.cos(np.pi / 8), 0.0, np.sin(np.pi / 8), 0.0])  # 45 degrees about +y
    quaternions = np.array([[1.0, 0, 0, 0], -half_turn, [np.cos(np.pi / 4), 0, np.sin(np.pi / 4), 0]])
    middle = smoothed(quaternions, np.array([1]), quaternions=True)[0]  # its neighbours taken onto its side
    expected = -(np.array([1.0, 0, 0, 0]) + 2 * half_turn + np.array([np.cos(np.pi / 4), 0, np.sin(np.pi / 4), 0]))
    np.testing.assert_allclose(middle, expected / np.linalg.norm(expected))
    assert frames_around(np.array([False, False, True, False, False, False]), np.ones(7, bool), 1).tolist() == [1, 2, 3, 4]


def test_finish_applies_it_by_default_and_not_when_told():
    motion = spinning()
    no_beats = np.zeros(0, int)
    assert joint_speeds(finish(motion, no_beats)).max() <= REAL_JOINT_SPEED
    np.testing.assert_array_equal(finish(motion, no_beats, speed=False, beat=False, footsteps=False).rotations,
                                  motion.rotations)
