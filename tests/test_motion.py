"""Motion: FK, slicing, concatenation, resampling, contacts and the 151-d frame vector."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.motion import FRAME_DIM, Motion, foot_contacts, motion_to_vector, vector_to_motion
from choreo.skeleton import SMPL24


def random_motion(frames=60, fps=30.0, seed=0, scale=0.4):
    rng = np.random.default_rng(seed)
    # Smooth random rotations: cumulative small steps keep consecutive frames close, like real motion.
    axis_angle = np.cumsum(rng.normal(scale=scale / 10, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.9, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def test_rest_motion_stands_on_the_floor():
    motion = Motion.rest(10)
    positions = motion.joint_positions()
    assert positions.shape == (10, 24, 3)
    assert positions[..., 1].min() == pytest.approx(0.0, abs=1e-9)
    assert motion.duration == pytest.approx(10 / 30)


def test_slicing_and_concatenation_round_trip():
    motion = random_motion(90)
    parts = [motion[0:30], motion[30:45], motion.slice_frames(45)]
    assert [p.num_frames for p in parts] == [30, 15, 45]
    joined = Motion.concatenate(parts)
    np.testing.assert_allclose(joined.joint_positions(), motion.joint_positions(), atol=1e-12)
    assert motion.slice_seconds(1.0, 2.0).num_frames == 30


def test_concatenate_rejects_mixed_fps():
    with pytest.raises(ParameterError):
        Motion.concatenate([random_motion(10), random_motion(10, fps=60)])


def test_resample_keeps_duration_and_reproduces_original_frames():
    motion = random_motion(60)
    double = motion.resample(60)
    assert double.num_frames == 120 and double.fps == 60
    np.testing.assert_allclose(double.joint_positions()[::2], motion.joint_positions(), atol=1e-9)
    np.testing.assert_allclose(double.resample(30).joint_positions(), motion.joint_positions(), atol=1e-9)
    down = random_motion(50, fps=25).resample(30)
    assert down.num_frames == 60


def test_resample_interpolates_between_frames():
    motion = random_motion(2, seed=3)
    mid = motion.resample(60).joint_positions()[1]
    # Halfway in time lies between the endpoints (small rotation steps: close to the linear mean).
    np.testing.assert_allclose(mid, motion.joint_positions().mean(0), atol=5e-3)


def test_invalid_motion_is_rejected():
    with pytest.raises(ParameterError):
        Motion(np.zeros((5, 3)), np.zeros((4, 24, 4)))
    bad = random_motion(5)
    with pytest.raises(ParameterError, match="NaN"):
        Motion(bad.root_positions * np.nan, bad.rotations)


def test_foot_contacts_follow_foot_speed():
    positions = np.zeros((4, 24, 3))
    positions[:, 7, 0] = [0.0, 0.005, 0.5, 1.0]  # left ankle: planted, then sliding fast
    contacts = foot_contacts(positions, fps=30)
    assert contacts.shape == (4, 4)
    np.testing.assert_array_equal(contacts[:, 0], [1, 0, 0, 0])
    np.testing.assert_array_equal(contacts[:, 1:], 1)
    # The same displacement at 60 fps is twice the speed.
    np.testing.assert_array_equal(foot_contacts(positions, fps=2 * 30 * 1.5)[:, 0], [0, 0, 0, 0])


def test_frame_vector_round_trip():
    motion = random_motion(40)
    vectors = motion_to_vector(motion)
    assert vectors.shape == (40, FRAME_DIM) == (40, 151)
    decoded, contacts = vector_to_motion(vectors)
    np.testing.assert_allclose(decoded.joint_positions(), motion.joint_positions(), atol=1e-5)
    np.testing.assert_array_equal(contacts, foot_contacts(motion.joint_positions(), 30))
    np.testing.assert_allclose(vectors[:, 4:7], motion.root_positions, atol=1e-6)


def test_frame_vector_requires_smpl24():
    small = SMPL24.__class__(("a", "b"), (-1, 0), np.array([[0, 0, 0], [0, 1, 0]]))
    motion = Motion(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 2, 1)), skeleton=small)
    with pytest.raises(ParameterError):
        motion_to_vector(motion)


def test_rest_is_the_identity_pose_over_the_origin_at_the_asked_rate():
    from choreo.skeleton import SMPL24

    rest = Motion.rest(5, fps=24.0, root_height=0.9)
    np.testing.assert_array_equal(rest.rotations, np.tile([1.0, 0.0, 0.0, 0.0], (5, 24, 1)))
    np.testing.assert_array_equal(rest.root_positions, np.tile([0.0, 0.9, 0.0], (5, 1)))
    assert rest.fps == 24.0 and rest.skeleton is SMPL24
    np.testing.assert_allclose(rest.joint_positions()[0], SMPL24.rest_positions() + [0.0, 0.9, 0.0], atol=1e-12)


def test_rest_of_another_skeleton_stands_on_the_floor():
    from choreo.skeleton import Skeleton

    small = Skeleton(("hips", "foot"), (-1, 0), np.array([[0.0, 0.0, 0.0], [0.0, -0.8, 0.0]]))
    rest = Motion.rest(3, skeleton=small)
    assert rest.skeleton is small and rest.rotations.shape == (3, 2, 4)
    np.testing.assert_allclose(rest.joint_positions()[:, :, 1], [[0.8, 0.0]] * 3)


def test_motion_beats_are_scipys_strict_local_minima_of_the_smoothed_speed():
    # motion_beats no longer imports scipy.signal (1 s of start-up for every motion reader); its
    # minima must stay argrelextrema(np.less, order=1)'s, plateaus and edges included.
    from scipy.ndimage import gaussian_filter1d
    from scipy.signal import argrelextrema

    from choreo.motion.beats import mean_joint_speed, motion_beats

    rng = np.random.default_rng(3)
    positions = np.cumsum(rng.normal(size=(400, 24, 3)) * (rng.random((400, 1, 1)) < 0.5), axis=0) * 0.01
    positions[100:130] = positions[100]  # a held pose: zero speed, smoothed into one bowl
    expected = argrelextrema(gaussian_filter1d(mean_joint_speed(positions), 5.0), np.less, order=1)[0]
    np.testing.assert_array_equal(motion_beats(positions), expected)
    assert len(expected) > 10


def test_a_stop_exactly_between_two_frames_is_one_motion_beat():
    """Positions (t - 20)^2 along x: the speeds of steps 19 -> 20 and 20 -> 21 tie at the bottom.
    The strict reference rule finds no beat there (or one, by rounding luck); choreo finds one,
    at the first of the two (speed index 19, the reference's indexing)."""
    from scipy.signal import argrelextrema

    from choreo.motion.beats import motion_beats

    t = np.arange(41, dtype=np.float64)
    positions = np.zeros((41, 1, 3))
    positions[:, 0, 0] = 0.01 * (t - 20) ** 2
    assert motion_beats(positions, sigma=1e-3).tolist() == [19]
    speed = np.linalg.norm(np.diff(positions, axis=0), axis=-1).mean(-1)
    assert speed[19] == speed[20] and argrelextrema(speed, np.less)[0].tolist() == []
    # without ties the rule is the reference's
    wiggle = np.random.default_rng(0).normal(size=(300, 24, 3)).cumsum(0) * 0.01
    from scipy.ndimage import gaussian_filter1d

    smoothed = gaussian_filter1d(np.linalg.norm(np.diff(wiggle, axis=0), axis=-1).mean(-1), 5.0)
    assert motion_beats(wiggle).tolist() == argrelextrema(smoothed, np.less)[0].tolist()
