"""Gaps found by the motion area's mutation run (docs/mutation.md): boundaries, refusal texts,
dtypes, the chunking contract, metadata copies and the stitching frames, each pinned by a
hand-made case, a closed form or scipy. (No test name may contain "cli", "training" or
"checkpoints": the motion area's mutation run leaves those out by name.)"""

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from choreo.errors import ParameterError
from choreo.motion import (
    Motion, foot_contacts, motion_beats, motion_to_vector, stretched, turned, vector_to_motion,
)
from choreo.skeleton import SMPL24, Skeleton, forward_kinematics


def random_motion(frames=20, fps=30.0, seed=0, scale=0.4):
    rng = np.random.default_rng(seed)
    axis_angle = np.cumsum(rng.normal(scale=scale / 10, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.9, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def counting_motion(frames, fps=30.0, metadata=None):
    """Identity rotations, root x = frame index: a frame's content names the frame."""
    root = np.stack([np.arange(frames, dtype=np.float64), np.full(frames, 0.9), np.zeros(frames)], axis=1)
    rotations = np.tile([1.0, 0.0, 0.0, 0.0], (frames, 24, 1))
    return Motion(root, rotations, fps=fps, metadata=dict(metadata or {}))


def two_joint_skeleton(bone=(0.0, 1.0, 0.0)):
    return Skeleton(("hips", "head"), (-1, 0), np.array([[0.0, 0.0, 0.0], list(bone)]))


def exactly(message):
    return "^" + re.escape(message) + "$"


# -- Motion validation ------------------------------------------------------------------------

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


def test_shape_refusals_name_the_shapes():
    with pytest.raises(ParameterError, match=exactly("root positions must have shape (T, 3), got (5, 2)")):
        Motion(np.zeros((5, 2)), np.zeros((5, 24, 4)))
    with pytest.raises(ParameterError, match=exactly("rotations must have shape (5, 24, 4), got (5, 24, 3)")):
        Motion(np.zeros((5, 3)), np.zeros((5, 24, 3)))
    with pytest.raises(ParameterError, match=exactly("motion contains NaN or infinite values")):
        Motion(np.full((2, 3), np.inf), np.tile([1.0, 0, 0, 0], (2, 24, 1)))


def test_frame_rate_limits_are_inclusive():
    identity = np.tile([1.0, 0, 0, 0], (2, 24, 1))
    assert Motion(np.zeros((2, 3)), identity, fps=1.0).fps == 1.0
    assert Motion(np.zeros((2, 3)), identity, fps=1000.0).fps == 1000.0
    with pytest.raises(ParameterError, match=exactly("fps must be between 1 and 1000, got 0.5")):
        Motion(np.zeros((2, 3)), identity, fps=0.5)
    with pytest.raises(ParameterError, match=exactly("fps must be between 1 and 1000, got 1000.5")):
        Motion(np.zeros((2, 3)), identity, fps=1000.5)


def test_root_coordinate_limit_is_inclusive():
    identity = np.tile([1.0, 0, 0, 0], (1, 24, 1))
    assert Motion(np.array([[1e5, 0.0, -1e5]]), identity).root_positions[0, 0] == 1e5
    message = exactly("root positions beyond 100000 m (wrong units, or a damaged file)")
    with pytest.raises(ParameterError, match=message):
        Motion(np.array([[0.0, 0.0, -1.0000001e5]]), identity)


def test_bone_limit_is_inclusive_and_refuses_long_or_nan_bones():
    identity = np.tile([1.0, 0, 0, 0], (1, 2, 1))
    at_limit = Motion(np.zeros((1, 3)), identity, skeleton=two_joint_skeleton((0.0, -1e3, 0.0)))
    np.testing.assert_array_equal(at_limit.joint_positions()[0], [[0.0, 0.0, 0.0], [0.0, -1e3, 0.0]])
    message = exactly("bone offsets must be finite and under 1000 m (a damaged file?)")
    for bone in [(0.0, 2e3, 0.0), (1000.001, 0.0, 0.0), (np.nan, 0.0, 0.0), (0.0, 0.0, np.inf)]:
        with pytest.raises(ParameterError, match=message):
            Motion(np.zeros((1, 3)), identity, skeleton=two_joint_skeleton(bone))


def test_a_skeleton_without_bones_passes_the_bone_check():
    # the largest offset of no offsets is 0 (max's initial), not an error
    empty = Skeleton((), (), np.zeros((0, 3)))
    motion = Motion(np.zeros((2, 3)), np.zeros((2, 0, 4)), skeleton=empty)
    assert motion.num_joints == 0 and motion.rotations.shape == (2, 0, 4)


def test_a_quaternion_of_norm_exactly_1e8_is_kept_and_a_zero_one_refused():
    rotations = np.tile([1.0, 0, 0, 0], (1, 24, 1))
    rotations[0, 5] = [0.0, 1e-8, 0.0, 0.0]  # norm exactly 1e-8: the smallest accepted
    motion = Motion(np.zeros((1, 3)), rotations)
    np.testing.assert_array_equal(motion.rotations[0, 5], [0.0, 1.0, 0.0, 0.0])
    rotations[0, 5] = 0.0
    with pytest.raises(ParameterError, match=exactly("motion contains a zero quaternion")):
        Motion(np.zeros((1, 3)), rotations)


def test_from_axis_angle_computes_in_float64_from_float32_input():
    rng = np.random.default_rng(5)
    axis_angle = rng.normal(scale=1.0, size=(3, 24, 3)).astype(np.float32)
    motion = Motion.from_axis_angle(np.zeros((3, 3)), axis_angle.reshape(3, 72))
    expected = Rotation.from_rotvec(axis_angle.reshape(-1, 3).astype(np.float64)).as_matrix()
    expected = expected.reshape(3, 24, 3, 3)
    np.testing.assert_allclose(motion.rotation_matrices(), expected, rtol=0, atol=1e-13)


# -- chunking: each frame goes through the converter once, at most FRAME_CHUNK at a time ------------

def test_joint_positions_are_computed_a_chunk_at_a_time(monkeypatch):
    import choreo.motion.motion as motion_module

    motion = random_motion(10)
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


def test_frame_vectors_are_decoded_a_chunk_at_a_time(monkeypatch):
    import choreo.motion.motion as motion_module  # where the chunk size lives (choreo.motion.motion.frame_chunks)
    from choreo.skeleton import rotations

    vectors = motion_to_vector(random_motion(10)).astype(np.float64)
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


# -- frame vectors -----------------------------------------------------------------------------

def gram_schmidt(six):
    """Literal Gram-Schmidt of (..., 6) rows (a1 | a2) into rotation matrices with rows b1, b2, b3."""
    out = np.zeros(six.shape[:-1] + (3, 3))
    for index in np.ndindex(six.shape[:-1]):
        a1, a2 = six[index][:3].astype(np.float64), six[index][3:].astype(np.float64)
        b1 = a1 / np.sqrt(a1 @ a1)
        a2 = a2 - (b1 @ a2) * b1
        b2 = a2 / np.sqrt(a2 @ a2)
        out[index] = [b1, b2, np.cross(b1, b2)]
    return out


def test_frame_vectors_are_float32_and_decoded_in_float64():
    motion = random_motion(6, seed=2)
    vectors = motion_to_vector(motion)
    assert vectors.dtype == np.float32
    decoded, contacts = vector_to_motion(vectors, fps=60.0, metadata={"genre": "pop"})
    assert decoded.fps == 60.0 and decoded.metadata == {"genre": "pop"}
    assert contacts.dtype == np.float64
    np.testing.assert_array_equal(contacts, vectors[:, :4].astype(np.float64))
    # float32 numbers, float64 arithmetic: the decoded rotations are the exact Gram-Schmidt
    # of the stored floats
    np.testing.assert_allclose(decoded.rotation_matrices(), gram_schmidt(vectors[:, 7:].reshape(6, 24, 6)),
                               rtol=0, atol=1e-13)


def test_vector_refusals_name_the_problem():
    with pytest.raises(ParameterError, match=exactly("frame vectors must have shape (T, 151), got (5, 150)")):
        vector_to_motion(np.zeros((5, 150)))
    with pytest.raises(ParameterError, match=exactly("frame vectors must have shape (T, 151), got (151,)")):
        vector_to_motion(np.zeros(151))
    small = Motion(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 2, 1)), skeleton=two_joint_skeleton())
    message = exactly("the 151-d frame vector is defined for the SMPL-24 skeleton")
    with pytest.raises(ParameterError, match=message):
        motion_to_vector(small)


# -- editing -----------------------------------------------------------------------------------

def test_edits_copy_the_metadata():
    import choreo.motion.stitch as stitch

    motion = counting_motion(6, metadata={"genre": "waltz"})
    results = {
        "slice_frames": motion.slice_frames(1, 3),
        "concatenate": Motion.concatenate([motion, counting_motion(2)]),
        "resample same rate": motion.resample(30.0),
        "sample_frames": motion.sample_frames(np.array([0.5, 1.5])),
        "turned_and_moved": stitch.turned_and_moved(motion, 0.3, np.array([1.0, 0.0, 0.0])),
    }
    for name, result in results.items():
        assert result.metadata == {"genre": "waltz"}, name
        result.metadata["edited"] = True
        assert motion.metadata == {"genre": "waltz"}, name


def test_indexing_takes_contiguous_slices_only():
    motion = counting_motion(6)
    np.testing.assert_array_equal(motion[1:4:1].root_positions[:, 0], [1.0, 2.0, 3.0])
    message = exactly("motions are sliced with contiguous frame ranges, e.g. motion[30:90]")
    for key in [3, slice(0, 4, 2), slice(None, None, -1)]:
        with pytest.raises(ParameterError, match=message):
            motion[key]


def test_slice_seconds_picks_the_frames_of_the_window():
    motion = counting_motion(60)
    np.testing.assert_array_equal(motion.slice_seconds(0.5, 1.0).root_positions[:, 0], np.arange(15, 30))
    np.testing.assert_array_equal(motion.slice_seconds(1.5).root_positions[:, 0], np.arange(45, 60))
    np.testing.assert_array_equal(motion.slice_seconds(stop=0.5).root_positions[:, 0], np.arange(0, 15))


def test_concatenate_refusals_name_the_problem():
    with pytest.raises(ParameterError, match=exactly("nothing to concatenate")):
        Motion.concatenate([])
    with pytest.raises(ParameterError, match=exactly("cannot concatenate motions at 30.0 and 60.0 fps")):
        Motion.concatenate([counting_motion(2), counting_motion(2, fps=60.0)])
    small = Motion(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 2, 1)), skeleton=two_joint_skeleton())
    with pytest.raises(ParameterError, match=exactly("cannot concatenate motions on different skeletons")):
        Motion.concatenate([counting_motion(2), small])


def test_resample_to_the_slowest_rate_and_refusals():
    one = counting_motion(30).resample(1.0)  # 30 frames at 30 fps: one second, one frame at 1 fps
    assert one.fps == 1.0 and one.num_frames == 1
    np.testing.assert_array_equal(one.root_positions, [[0.0, 0.9, 0.0]])
    # round(0.5) = 0 frames -> at least one
    assert counting_motion(1, fps=60.0).resample(30.0).num_frames == 1
    for fps in [0, 0.0, -2.0]:
        with pytest.raises(ParameterError, match=exactly(f"fps must be positive, got {fps}")):
            counting_motion(3).resample(fps)


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


# -- augmentation ------------------------------------------------------------------------------

def test_stretch_limits_are_inclusive():
    motion = counting_motion(9)
    slowest = stretched(motion, 0.25)
    np.testing.assert_allclose(slowest.root_positions[:, 0], np.arange(33) * 0.25, rtol=0, atol=1e-12)
    fastest = stretched(motion, 4.0)
    np.testing.assert_allclose(fastest.root_positions[:, 0], [0.0, 4.0, 8.0], rtol=0, atol=1e-12)
    for factor in [0.2, 4.5]:
        message = exactly(f"stretch factor must be within [0.25, 4], got {factor}")
        with pytest.raises(ParameterError, match=message):
            stretched(motion, factor)


def test_turns_add_up_in_the_metadata_and_keep_the_rest():
    motion = counting_motion(4, metadata={"genre": "waltz"})
    twice = turned(turned(motion, 30.0), 45.0)
    assert twice.metadata == {"genre": "waltz", "turned_degrees": 75.0}


# -- beats and contacts on short clips -----------------------------------------------------------

def test_dances_too_short_for_a_beat_have_an_empty_integer_array():
    for frames in [0, 1, 2]:
        beats = motion_beats(np.zeros((frames, 24, 3)))
        assert beats.shape == (0,) and beats.dtype.kind == "i", frames
        assert np.arange(5)[beats].tolist() == []  # usable as an index


def test_contacts_of_one_and_two_frames():
    np.testing.assert_array_equal(foot_contacts(np.zeros((1, 24, 3)), fps=30), np.ones((1, 4)))
    assert foot_contacts(np.zeros((0, 24, 3)), fps=30).shape == (0, 4)
    moving = np.zeros((2, 24, 3))
    moving[1, [7, 8, 10, 11], 2] = 1.0  # every foot joint moves 1 m in one frame
    np.testing.assert_array_equal(foot_contacts(moving, fps=30), np.zeros((2, 4)))


def test_a_foot_exactly_at_the_threshold_speed_is_moving():
    positions = np.zeros((3, 24, 3))
    positions[:, 7, 0] = [0.0, 0.25, 0.5]  # left ankle: 0.25 m per frame at 2 fps = 0.5 m/s exactly
    contacts = foot_contacts(positions, fps=2.0, speed_threshold=0.5)
    np.testing.assert_array_equal(contacts, [[0, 1, 1, 1]] * 3)
    above = foot_contacts(positions, fps=2.0, speed_threshold=0.5 + 1e-12)
    np.testing.assert_array_equal(above[:, 0], [1, 1, 1])


# -- stitching frames ------------------------------------------------------------------------------

def test_rotate_about_y_is_scipys_rotation():
    from choreo.motion.stitch import rotate_about_y

    points = np.array([[0.0, 0.0, 1.0], [1.0, 0.5, 0.0], [0.3, -0.2, -0.7]])
    for angle in [0.0, 0.4, -2.0]:
        expected = Rotation.from_euler("y", angle).apply(points)
        np.testing.assert_allclose(rotate_about_y(points, angle), expected, rtol=0, atol=1e-15)


# Frame 0: root at (1, 0.9, 2), hips across -z (facing +x, yaw 90 degrees); frame 1: root at
# (1.5, 0.95, 2), hips across +x (facing +z, yaw 0).
HAND_MADE = np.array([
    [[1.0, 0.9, 2.0], [1.0, 0.8, 1.9], [1.0, 0.8, 2.1]],
    [[1.5, 0.95, 2.0], [1.6, 0.85, 2.0], [1.4, 0.85, 2.0]],
])


def test_local_positions_of_a_hand_made_excerpt():
    from choreo.motion.stitch import local_positions

    # (p - (1, 0, 2)) turned by -90 degrees about y: (x, y, z) -> (-z, y, x)
    expected = [
        [[0.0, 0.9, 0.0], [0.1, 0.8, 0.0], [-0.1, 0.8, 0.0]],
        [[0.0, 0.95, 0.5], [0.0, 0.85, 0.6], [0.0, 0.85, 0.4]],
    ]
    np.testing.assert_allclose(local_positions(HAND_MADE), expected, rtol=0, atol=1e-12)


def test_frame_local_positions_of_a_hand_made_pair_of_poses():
    from choreo.motion.stitch import frame_local_positions

    expected = [
        [[0.0, 0.9, 0.0], [0.1, 0.8, 0.0], [-0.1, 0.8, 0.0]],
        [[0.0, 0.95, 0.0], [0.1, 0.85, 0.0], [-0.1, 0.85, 0.0]],
    ]
    np.testing.assert_allclose(frame_local_positions(HAND_MADE), expected, rtol=0, atol=1e-12)


def test_crossfade_ramps_by_k_plus_1_over_n_plus_1():
    from choreo.motion.stitch import crossfade

    outgoing = Motion(np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (3, 24, 1)))
    turn = Rotation.from_euler("y", np.pi / 2).as_quat(scalar_first=True)
    incoming_rotations = np.tile([1.0, 0, 0, 0], (5, 24, 1))
    incoming_rotations[:, 0] = turn
    incoming = Motion(np.tile([1.0, 0.0, 0.0], (5, 1)), incoming_rotations)
    out = crossfade(outgoing, incoming)
    np.testing.assert_allclose(out.root_positions[:, 0], [0.25, 0.5, 0.75, 1.0, 1.0], rtol=0, atol=1e-15)
    ramp = np.array([[0.25], [0.5], [0.75], [1.0], [1.0]])
    expected = Rotation.from_euler("y", np.pi / 2 * ramp).as_matrix()
    np.testing.assert_allclose(out.rotation_matrices()[:, 0], expected, rtol=0, atol=1e-12)
