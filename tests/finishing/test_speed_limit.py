"""The speed limit: a one-frame spin or dash is spread over its neighbours until no joint moves
faster than real dancers do, ends and given frames untouched, movements within the limits left
bit for bit."""

import numpy as np
import pytest

from choreo.finishing import finish
from choreo.finishing.speed_limit import (
    REAL_FLOOR_STEP,
    REAL_JOINT_SPEED,
    SpeedLimitConfig,
    frames_around,
    smoothed,
    speed_limit,
    step_lengths,
)
from choreo.motion import Motion
from choreo.motion.stitch import facing_yaw
from choreo.pipeline import Finishing


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
    np.testing.assert_array_equal(finish(motion, no_beats, Finishing(speed_limit=False, beat_lock=False, footsteps=False)).rotations,
                                  motion.rotations)


def literal_frames_around(over, movable, reach):
    frames = {f for step, flagged in enumerate(over) if flagged for f in range(step - reach, step + reach + 2)}
    return np.array(sorted(f for f in frames if 0 <= f < len(movable) and movable[f]), dtype=int)


def literal_average(before, centre, after, quaternions):
    """One frame's [1, 2, 1] / 4 average of (..., D) values, a row at a time."""
    out = np.empty_like(centre)
    for index in np.ndindex(centre.shape[:-1]):
        b, c, a = before[index], centre[index], after[index]
        if quaternions:
            b = -b if np.dot(b, c) < 0 else b
            a = -a if np.dot(a, c) < 0 else a
        mean = (b + 2 * c + a) / 4
        out[index] = mean / np.sqrt(np.sum(mean**2)) if quaternions else mean
    return out


def literal_speed_limit(motion: Motion, fixed, config: SpeedLimitConfig) -> Motion:
    """The pass written plainly: every speed recomputed from the whole motion after every pass."""
    T = motion.num_frames
    movable = [not f for f in fixed] if fixed is not None else [True] * T
    movable[0] = movable[-1] = False
    root, rotations = motion.root_positions.copy(), motion.rotations.copy()
    floor_limit = config.floor_step * 30.0 / motion.fps
    for _ in range(config.max_passes):
        over = [np.hypot(*(root[t + 1, [0, 2]] - root[t, [0, 2]])) > floor_limit for t in range(T - 1)]
        chosen = literal_frames_around(over, movable, config.reach)
        if not len(chosen):
            break
        old = root.copy()
        for f in chosen:
            root[f, [0, 2]] = literal_average(old[f - 1, [0, 2]], old[f, [0, 2]], old[f + 1, [0, 2]], False)
    for _ in range(config.max_passes):
        positions = motion.replace(root_positions=root, rotations=rotations).joint_positions()
        speed = [max(np.linalg.norm(positions[t + 1, j] - positions[t, j]) for j in range(24)) * motion.fps
                 for t in range(T - 1)]
        chosen = literal_frames_around([s > config.joint_speed for s in speed], movable, config.reach)
        if not len(chosen):
            break
        old_rotations, old_root = rotations.copy(), root.copy()
        for f in chosen:
            rotations[f] = literal_average(old_rotations[f - 1], old_rotations[f], old_rotations[f + 1], True)
            root[f] = literal_average(old_root[f - 1], old_root[f], old_root[f + 1], False)
    return motion.replace(root_positions=root, rotations=rotations)


def random_quaternions(rng, shape):
    q = rng.normal(size=shape + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def jerky_dance(seed=0, frames=40) -> Motion:
    """A dance with two one-frame spins of the whole body, a limb flip and a floor dash; some
    quaternions stored with the opposite sign (the same rotation)."""
    rng = np.random.default_rng(seed)
    axis_angle = np.cumsum(rng.normal(scale=0.02, size=(frames, 24, 3)), axis=0)
    axis_angle[12:, 0, 1] += 1.6  # whole-body turn in one frame
    axis_angle[25:, 18, 2] += 2.0  # an elbow flips
    root = np.tile([0.0, 0.95, 0.0], (frames, 1)) + np.cumsum(rng.normal(scale=0.005, size=(frames, 3)), axis=0)
    root[30:, 0] += 0.4  # a 40 cm dash in one frame
    motion = Motion.from_axis_angle(root, axis_angle, fps=30.0)
    signs = np.where(rng.random((frames, 24, 1)) < 0.3, -1.0, 1.0)
    return motion.replace(rotations=motion.rotations * signs)


@pytest.mark.survivor
def test_step_lengths_are_per_joint_distances_between_consecutive_frames():
    values = np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3) ** 2
    expected = [[np.linalg.norm(values[1, j] - values[0, j]) for j in range(3)]]
    np.testing.assert_allclose(step_lengths(values), expected, rtol=1e-15)
    np.testing.assert_allclose(step_lengths(np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 4.0]])), [5.0, 0.0])


@pytest.mark.survivor
@pytest.mark.parametrize("flagged", [[0], [8], [3, 4], [0, 8], [5]])
@pytest.mark.parametrize("reach", [0, 1, 2])
def test_frames_around_a_step_are_its_two_frames_and_reach_more_each_side_within_the_motion(flagged, reach):
    over = np.zeros(9, bool)  # steps of a 10-frame motion
    over[flagged] = True
    movable = np.ones(10, bool)
    np.testing.assert_array_equal(frames_around(over, movable, reach), literal_frames_around(over, movable, reach))
    movable[[1, 6]] = False
    np.testing.assert_array_equal(frames_around(over, movable, reach), literal_frames_around(over, movable, reach))


@pytest.mark.survivor
def test_frames_around_step_zero_do_not_wrap_to_the_end():
    over = np.zeros(19, bool)
    over[0] = True
    np.testing.assert_array_equal(frames_around(over, np.ones(20, bool), 2), [0, 1, 2, 3])
    over[:] = False
    over[-1] = True  # the last step joins frames 18 and 19
    np.testing.assert_array_equal(frames_around(over, np.ones(20, bool), 2), [16, 17, 18, 19])


@pytest.mark.survivor
def test_smoothed_values_are_a_one_two_one_average_of_the_old_neighbours():
    values = np.random.default_rng(1).normal(size=(8, 3))
    chosen = np.array([2, 3, 6])
    expected = [(values[f - 1] + 2 * values[f] + values[f + 1]) / 4 for f in chosen]  # all from the old values
    np.testing.assert_allclose(smoothed(values, chosen), expected, rtol=1e-14)


@pytest.mark.survivor
def test_smoothed_quaternions_take_each_joints_neighbours_onto_the_centres_hemisphere():
    rng = np.random.default_rng(2)
    q = random_quaternions(rng, (6, 5))
    q[1, 0] *= -1  # both signs next to one frame, per joint
    q[3, 2] *= -1
    chosen = np.array([2, 4])
    expected = [literal_average(q[f - 1], q[f], q[f + 1], True) for f in chosen]
    np.testing.assert_allclose(smoothed(q, chosen, quaternions=True), expected, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(smoothed(q, chosen, quaternions=True), axis=-1), 1.0, rtol=1e-14)


@pytest.mark.survivor
def test_a_neighbour_at_right_angles_keeps_its_sign():
    """A dot product of exactly 0 is not 'the other hemisphere': the neighbour is not negated."""
    q = np.array([[[0.0, 1.0, 0.0, 0.0]], [[1.0, 0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0, 0.0]]])
    mean = np.array([3.0, 1.0, 0.0, 0.0])
    np.testing.assert_allclose(smoothed(q, np.array([1]), quaternions=True)[0, 0], mean / np.linalg.norm(mean))
    np.testing.assert_allclose(smoothed(q[::-1], np.array([1]), quaternions=True)[0, 0], mean / np.linalg.norm(mean))


@pytest.mark.survivor
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("reach", [1, 2])
def test_the_whole_pass_equals_a_literal_one_that_recomputes_every_speed(seed, reach):
    motion = jerky_dance(seed)
    config = SpeedLimitConfig(reach=reach)
    fixed = np.zeros(motion.num_frames, bool)
    fixed[[13, 27]] = True
    for given in (None, fixed):
        got, want = speed_limit(motion, given, config), literal_speed_limit(motion, given, config)
        assert not np.allclose(got.rotations, motion.rotations)  # there was something to do
        np.testing.assert_allclose(got.root_positions, want.root_positions, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.rotations, want.rotations, rtol=0, atol=1e-12)


@pytest.mark.survivor
@pytest.mark.parametrize("fixed_frames", [[], [11, 14], [24, 26]])
def test_single_frame_runs_between_given_frames_and_a_spin_into_the_last_frame_match_the_literal_pass(fixed_frames):
    """With reach 0 and given frames on both sides, a moved run can be one frame long; every step
    into and out of it must be measured again."""
    motion = jerky_dance(6, frames=30)
    axis_angle = np.zeros((30, 24, 3))
    axis_angle[-1, 0, 1] = 1.5  # the whole body turns into the last frame
    turned = Motion.from_axis_angle(np.zeros((30, 3)), axis_angle, fps=30.0).rotations[:, :1]
    rotations = motion.rotations.copy()
    w1, v1, w2, v2 = rotations[:, 0, :1], rotations[:, 0, 1:], turned[:, 0, :1], turned[:, 0, 1:]
    rotations[:, 0] = np.concatenate([w2 * w1 - (v2 * v1).sum(-1, keepdims=True), w2 * v1 + w1 * v2 + np.cross(v2, v1)], -1)
    motion = motion.replace(rotations=rotations)
    fixed = np.zeros(30, bool)
    fixed[fixed_frames] = True
    config = SpeedLimitConfig(reach=0)
    got, want = speed_limit(motion, fixed, config), literal_speed_limit(motion, fixed, config)
    assert not np.allclose(got.rotations[-2], motion.rotations[-2])
    np.testing.assert_allclose(got.rotations, want.rotations, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.root_positions, want.root_positions, rtol=0, atol=1e-12)


@pytest.mark.survivor
def test_first_and_last_frames_stay_even_when_the_fast_step_touches_them():
    motion = jerky_dance(3, frames=12)
    root = motion.root_positions.copy()
    root[0, 0] -= 0.5  # dashes out of the first frame and into the last
    root[-1, 0] += 0.5
    motion = motion.replace(root_positions=root)
    limited = speed_limit(motion)
    for frame in (0, -1):
        np.testing.assert_array_equal(limited.root_positions[frame], motion.root_positions[frame])
        np.testing.assert_array_equal(limited.rotations[frame], motion.rotations[frame])
    assert not np.array_equal(limited.root_positions[1], motion.root_positions[1])
    assert not np.array_equal(limited.root_positions[-2], motion.root_positions[-2])


@pytest.mark.survivor
def test_three_frames_are_enough_to_spread_a_dash():
    root = np.array([[0.0, 0.9, 0.0], [0.0, 0.9, 0.0], [0.6, 0.9, 0.0]])
    motion = Motion.from_axis_angle(root, np.zeros((3, 24, 3)), fps=30.0)
    limited = speed_limit(motion)  # x <- (0 + 2 x + 0.6) / 4 until the passes run out: halfway
    assert limited.root_positions[1, 0] == pytest.approx(0.3, abs=1e-9)


@pytest.mark.survivor
def test_a_step_exactly_at_a_limit_is_left_alone():
    root = np.tile([0.0, 0.9, 0.0], (6, 1))
    root[3:, 0] = 0.5  # one floor step of exactly 0.5 m
    motion = Motion.from_axis_angle(root, np.zeros((6, 24, 3)), fps=30.0)
    at_limit = SpeedLimitConfig(floor_step=0.5, joint_speed=1e9)
    np.testing.assert_array_equal(speed_limit(motion, config=at_limit).root_positions, root)
    below = SpeedLimitConfig(floor_step=0.49, joint_speed=1e9)
    assert not np.array_equal(speed_limit(motion, config=below).root_positions, root)
    dance = jerky_dance(4)
    fastest = step_lengths(dance.joint_positions()).max(-1).max() * dance.fps  # the pass's own arithmetic
    untouched = speed_limit(dance, config=SpeedLimitConfig(floor_step=1e9, joint_speed=fastest))
    np.testing.assert_allclose(untouched.rotations, dance.rotations, rtol=0, atol=1e-15)  # (renormalised on the way)


@pytest.mark.survivor
def test_the_output_has_its_own_copy_of_the_metadata():
    motion = jerky_dance(5).replace(metadata={"generator": "sgmd"})
    limited = speed_limit(motion)
    assert limited.metadata == {"generator": "sgmd"}
    limited.metadata["finished"] = True
    assert motion.metadata == {"generator": "sgmd"}
