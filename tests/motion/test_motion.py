"""Motion: FK, slicing, concatenation, resampling, contacts and the 151-d frame vector."""


import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from choreo.errors import ParameterError
from choreo.motion import (
    FRAME_DIM,
    Motion,
    foot_contacts,
    motion_to_vector,
    vector_to_motion,
)
from choreo.skeleton import SMPL24, Skeleton, forward_kinematics
from tests.motion.helpers import counting_motion, exactly, gram_schmidt, short_random_motion, two_joint_skeleton


def random_motion(frames=60, fps=30.0, seed=0, scale=0.4):
    return short_random_motion(frames, fps, seed, scale)


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


@pytest.mark.survivor
def test_inputs_are_stored_in_float64_and_normalised_in_float64():
    root = np.array([[0.1, 0.9, 0.3]], dtype=np.float32)
    rotations = np.zeros((1, 24, 4), dtype=np.float32)
    rotations[..., 0] = 1.0
    rotations[0, 3] = [1.0, 1.0, 0.0, 0.0]  # not unit: normalised to (1/sqrt2, 1/sqrt2, 0, 0)
    motion = Motion(root, rotations)
    assert motion.root_positions.dtype == np.float64 and motion.rotations.dtype == np.float64
    np.testing.assert_array_equal(motion.root_positions, np.float32([[0.1, 0.9, 0.3]]).astype(np.float64))
    half = np.sqrt(0.5)
    np.testing.assert_allclose(motion.rotations[0, 3], [half, half, 0.0, 0.0], rtol=0, atol=1e-15)
    ints = Motion(np.array([[1, 2, 3]]), np.tile([1, 0, 0, 0], (1, 24, 1)))
    assert ints.root_positions.dtype == np.float64


@pytest.mark.survivor
def test_shape_refusals_name_the_shapes():
    with pytest.raises(ParameterError, match=exactly("root positions must have shape (T, 3), got (5, 2)")):
        Motion(np.zeros((5, 2)), np.zeros((5, 24, 4)))
    with pytest.raises(ParameterError, match=exactly("rotations must have shape (5, 24, 4), got (5, 24, 3)")):
        Motion(np.zeros((5, 3)), np.zeros((5, 24, 3)))
    with pytest.raises(ParameterError, match=exactly("motion contains NaN or infinite values")):
        Motion(np.full((2, 3), np.inf), np.tile([1.0, 0, 0, 0], (2, 24, 1)))


@pytest.mark.survivor
def test_frame_rate_limits_are_inclusive():
    identity = np.tile([1.0, 0, 0, 0], (2, 24, 1))
    assert Motion(np.zeros((2, 3)), identity, fps=1.0).fps == 1.0
    assert Motion(np.zeros((2, 3)), identity, fps=1000.0).fps == 1000.0
    with pytest.raises(ParameterError, match=exactly("fps must be between 1 and 1000, got 0.5")):
        Motion(np.zeros((2, 3)), identity, fps=0.5)
    with pytest.raises(ParameterError, match=exactly("fps must be between 1 and 1000, got 1000.5")):
        Motion(np.zeros((2, 3)), identity, fps=1000.5)


@pytest.mark.survivor
def test_root_coordinate_limit_is_inclusive():
    identity = np.tile([1.0, 0, 0, 0], (1, 24, 1))
    assert Motion(np.array([[1e5, 0.0, -1e5]]), identity).root_positions[0, 0] == 1e5
    message = exactly("root positions beyond 100000 m (wrong units, or a damaged file)")
    with pytest.raises(ParameterError, match=message):
        Motion(np.array([[0.0, 0.0, -1.0000001e5]]), identity)


@pytest.mark.survivor
def test_bone_limit_is_inclusive_and_refuses_long_or_nan_bones():
    identity = np.tile([1.0, 0, 0, 0], (1, 2, 1))
    at_limit = Motion(np.zeros((1, 3)), identity, skeleton=two_joint_skeleton((0.0, -1e3, 0.0)))
    np.testing.assert_array_equal(at_limit.joint_positions()[0], [[0.0, 0.0, 0.0], [0.0, -1e3, 0.0]])
    message = exactly("bone offsets must be finite and under 1000 m (a damaged file?)")
    for bone in [(0.0, 2e3, 0.0), (1000.001, 0.0, 0.0), (np.nan, 0.0, 0.0), (0.0, 0.0, np.inf)]:
        with pytest.raises(ParameterError, match=message):
            Motion(np.zeros((1, 3)), identity, skeleton=two_joint_skeleton(bone))


@pytest.mark.survivor
def test_a_skeleton_without_bones_passes_the_bone_check():
    # the largest offset of no offsets is 0 (max's initial), not an error
    empty = Skeleton((), (), np.zeros((0, 3)))
    motion = Motion(np.zeros((2, 3)), np.zeros((2, 0, 4)), skeleton=empty)
    assert motion.num_joints == 0 and motion.rotations.shape == (2, 0, 4)


@pytest.mark.survivor
def test_a_quaternion_of_norm_exactly_1e8_is_kept_and_a_zero_one_refused():
    rotations = np.tile([1.0, 0, 0, 0], (1, 24, 1))
    rotations[0, 5] = [0.0, 1e-8, 0.0, 0.0]  # norm exactly 1e-8: the smallest accepted
    motion = Motion(np.zeros((1, 3)), rotations)
    np.testing.assert_array_equal(motion.rotations[0, 5], [0.0, 1.0, 0.0, 0.0])
    rotations[0, 5] = 0.0
    with pytest.raises(ParameterError, match=exactly("motion contains a zero quaternion")):
        Motion(np.zeros((1, 3)), rotations)


@pytest.mark.survivor
def test_from_axis_angle_computes_in_float64_from_float32_input():
    rng = np.random.default_rng(5)
    axis_angle = rng.normal(scale=1.0, size=(3, 24, 3)).astype(np.float32)
    motion = Motion.from_axis_angle(np.zeros((3, 3)), axis_angle.reshape(3, 72))
    expected = Rotation.from_rotvec(axis_angle.reshape(-1, 3).astype(np.float64)).as_matrix()
    expected = expected.reshape(3, 24, 3, 3)
    np.testing.assert_allclose(motion.rotation_matrices(), expected, rtol=0, atol=1e-13)


@pytest.mark.survivor
def test_joint_positions_are_computed_a_chunk_at_a_time(monkeypatch):
    import choreo.motion.motion as motion_module

    motion = short_random_motion(10)
    expected = forward_kinematics(Rotation.from_quat(motion.rotations.reshape(-1, 4), scalar_first=True)
                                  .as_matrix().reshape(10, 24, 3, 3), motion.root_positions,
                                  SMPL24.offsets, SMPL24.parents)
    calls = []

    def recording_fk(rotmats, root, offsets, parents):
        calls.append(np.shape(root))
        return forward_kinematics(rotmats, root, offsets, parents)

    monkeypatch.setattr(motion_module, "FRAME_CHUNK", 4)
    monkeypatch.setattr(motion_module, "forward_kinematics", recording_fk)
    np.testing.assert_allclose(motion.joint_positions(), expected, rtol=0, atol=1e-12)
    assert calls == [(4, 3), (4, 3), (2, 3)]


@pytest.mark.survivor
def test_frame_vectors_are_decoded_a_chunk_at_a_time(monkeypatch):
    import choreo.motion.motion as motion_module  # where the chunk size lives (choreo.motion.motion.frame_chunks)
    from choreo.skeleton import rotations

    vectors = motion_to_vector(short_random_motion(10)).astype(np.float64)
    calls = []
    original = rotations.rot6d_to_matrix

    def recording(rot6d):
        calls.append(np.shape(rot6d))
        return original(rot6d)

    monkeypatch.setattr(motion_module, "FRAME_CHUNK", 4)
    monkeypatch.setattr(rotations, "rot6d_to_matrix", recording)
    motion, _ = vector_to_motion(vectors)
    assert calls == [(4, 24, 6), (4, 24, 6), (2, 24, 6)]
    np.testing.assert_allclose(motion.rotation_matrices(), gram_schmidt(vectors[:, 7:].reshape(10, 24, 6)),
                               rtol=0, atol=1e-12)


@pytest.mark.survivor
def test_indexing_takes_contiguous_slices_only():
    motion = counting_motion(6)
    np.testing.assert_array_equal(motion[1:4:1].root_positions[:, 0], [1.0, 2.0, 3.0])
    message = exactly("motions are sliced with contiguous frame ranges, e.g. motion[30:90]")
    for key in [3, slice(0, 4, 2), slice(None, None, -1)]:
        with pytest.raises(ParameterError, match=message):
            motion[key]


@pytest.mark.survivor
def test_slice_seconds_picks_the_frames_of_the_window():
    motion = counting_motion(60)
    np.testing.assert_array_equal(motion.slice_seconds(0.5, 1.0).root_positions[:, 0], np.arange(15, 30))
    np.testing.assert_array_equal(motion.slice_seconds(1.5).root_positions[:, 0], np.arange(45, 60))
    np.testing.assert_array_equal(motion.slice_seconds(stop=0.5).root_positions[:, 0], np.arange(0, 15))


@pytest.mark.survivor
def test_concatenate_refusals_name_the_problem():
    with pytest.raises(ParameterError, match=exactly("nothing to concatenate")):
        Motion.concatenate([])
    with pytest.raises(ParameterError, match=exactly("cannot concatenate motions at 30.0 and 60.0 fps")):
        Motion.concatenate([counting_motion(2), counting_motion(2, fps=60.0)])
    small = Motion(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 2, 1)), skeleton=two_joint_skeleton())
    with pytest.raises(ParameterError, match=exactly("cannot concatenate motions on different skeletons")):
        Motion.concatenate([counting_motion(2), small])


@pytest.mark.survivor
def test_resample_to_the_slowest_rate_and_refusals():
    one = counting_motion(30).resample(1.0)  # 30 frames at 30 fps: one second, one frame at 1 fps
    assert one.fps == 1.0 and one.num_frames == 1
    np.testing.assert_array_equal(one.root_positions, [[0.0, 0.9, 0.0]])
    # round(0.5) = 0 frames -> at least one
    assert counting_motion(1, fps=60.0).resample(30.0).num_frames == 1
    for fps in [0, 0.0, -2.0]:
        with pytest.raises(ParameterError, match=exactly(f"fps must be positive, got {fps}")):
            counting_motion(3).resample(fps)


@pytest.mark.survivor
def test_sample_frames_clamps_to_the_first_and_last_frame():
    angles = np.deg2rad(10.0) * np.arange(5)
    rotations = np.tile([1.0, 0, 0, 0], (5, 24, 1))
    rotations[:, 0] = Rotation.from_euler("y", angles[:, None]).as_quat(scalar_first=True)
    root = np.stack([np.arange(5.0), np.full(5, 0.9), np.zeros(5)], axis=1)
    motion = Motion(root, rotations)
    out = motion.sample_frames(np.array([-2.0, 0.5, 4.0, 6.5, 100.0]))
    np.testing.assert_allclose(out.root_positions[:, 0], [0.0, 0.5, 4.0, 4.0, 4.0], rtol=0, atol=1e-15)
    expected = Rotation.from_euler("y", np.deg2rad([[0.0], [5.0], [40.0], [40.0], [40.0]])).as_matrix()
    np.testing.assert_allclose(out.rotation_matrices()[:, 0], expected, rtol=0, atol=1e-12)
