"""Tests of choreo.constraints.mask.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.constraints import (
    Constraints,
    as_smpl,
)
from choreo.constraints.mask import check_joints
from choreo.errors import ParameterError
from choreo.motion import Motion
from choreo.skeleton import Skeleton
from tests.constraints.helpers import numbered_motion

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def other_skeleton_motion():
    small = Skeleton(("a", "b"), (-1, 0), np.array([[0, 0, 0], [0, 1, 0.0]]))
    return Motion(np.zeros((4, 3)), np.tile([1.0, 0, 0, 0], (4, 2, 1)), skeleton=small)


@pytest.mark.survivor
def test_none_knows_nothing_and_holds_identity_rotations():
    c = Constraints.none(3, 25)
    assert c.num_frames == 3 and c.fps == 25.0 and type(c.fps) is float
    assert c.root.shape == (3, 3) and (c.root == 0).all()
    assert c.root_known.shape == (3, 3) and c.root_known.dtype == bool and not c.root_known.any()
    assert c.joints_known.shape == (3, 24) and c.joints_known.dtype == bool and not c.joints_known.any()
    assert c.rotations.shape == (3, 24, 4)
    for t in range(3):
        for j in range(24):
            assert list(c.rotations[t, j]) == [1.0, 0.0, 0.0, 0.0]
    one = Constraints.none(1, 30)
    assert one.num_frames == 1 and one.rotations.shape == (1, 24, 4)
    assert one.is_empty and one.known_fraction() == 0.0


@pytest.mark.survivor
@pytest.mark.parametrize("frames", [0, -3])
def test_none_refuses_a_dance_without_frames(frames):
    with pytest.raises(ParameterError, match="^a dance needs at least one frame$"):
        Constraints.none(frames, 30)


@pytest.mark.survivor
def test_fixed_frames_are_those_with_any_joint_or_root_axis():
    c = Constraints.none(6, 30)
    c.joints_known[2, 7] = True
    c.root_known[4, 1] = True
    c.joints_known[5, :] = True
    c.root_known[5, :] = True
    assert c.fixed_frames().tolist() == [False, False, True, False, True, True]


@pytest.mark.survivor
def test_describe_names_what_is_given_a_root_path_included():
    assert Constraints.none(10, 30).describe() == "nothing given"
    path = Constraints.none(10, 30).fix_root_path(np.zeros((10, 2)))
    assert path.describe() == "the floor path on 100 % of frames given"  # no joint: not "0 % of joints"
    assert Constraints.none(10, 30).fix_root_path(np.zeros((10, 2)), np.ones(10)).describe() == \
        "the root on 100 % of frames given"
    keys = Constraints.none(10, 30)
    keys.joints_known[:2, :12] = True  # 24 of 240 joint values
    keys.root_known[:2] = True
    assert keys.describe() == "10 % of joint rotations and the root on 20 % of frames given"


@pytest.mark.survivor
def test_fix_motion_copies_every_frame_joint_and_root_from_at():
    motion = numbered_motion(4)
    c = Constraints.none(10, 30)
    assert c.fix_motion(motion, at=3) is c
    for t in range(10):
        given = 3 <= t < 7
        assert c.joints_known[t].tolist() == [given] * 24
        assert c.root_known[t].tolist() == [given] * 3
        if given:
            assert c.root[t].tolist() == [t - 3, 0.9, -0.5 * (t - 3)]
            for j in range(24):
                np.testing.assert_array_equal(c.rotations[t, j], motion.rotations[t - 3, j])
        else:
            assert c.root[t].tolist() == [0, 0, 0]
            for j in range(24):
                assert list(c.rotations[t, j]) == [1.0, 0, 0, 0]


@pytest.mark.survivor
def test_fix_motion_some_joints_without_the_root():
    motion = numbered_motion(3)
    c = Constraints.none(5, 30).fix_motion(motion, at=1, joints=[5, 2, 2], root=False)
    assert not c.root_known.any() and (c.root == 0).all()
    for t in range(5):
        for j in range(24):
            given = 1 <= t < 4 and j in (2, 5)
            assert c.joints_known[t, j] == given
            expected = motion.rotations[t - 1, j] if given else IDENTITY
            np.testing.assert_array_equal(c.rotations[t, j], expected)


@pytest.mark.survivor
def test_fix_motion_chosen_frames_by_index_and_by_mask():
    motion = numbered_motion(5)
    by_index = Constraints.none(8, 30).fix_motion(motion, at=2, frames=np.array([0, 3]))
    assert by_index.root_known[:, 0].tolist() == [False, False, True, False, False, True, False, False]
    assert by_index.root[2].tolist() == [0, 0.9, 0] and by_index.root[5].tolist() == [3, 0.9, -1.5]
    np.testing.assert_array_equal(by_index.rotations[5, 10], motion.rotations[3, 10])
    assert by_index.joints_known.sum(1).tolist() == [0, 0, 24, 0, 0, 24, 0, 0]

    by_mask = Constraints.none(8, 30).fix_motion(motion, at=2, frames=np.array([False, True, False, False, True]))
    assert by_mask.root_known[:, 2].tolist() == [False, False, False, True, False, False, True, False]
    assert by_mask.root[3].tolist() == [1, 0.9, -0.5] and by_mask.root[6].tolist() == [4, 0.9, -2.0]

    nothing = Constraints.none(8, 30).fix_motion(motion, at=2, frames=np.zeros(5, bool))
    assert nothing.is_empty


@pytest.mark.survivor
def test_fix_motion_fits_to_the_last_frame_and_refuses_beyond_either_end():
    motion = numbered_motion(4)
    c = Constraints.none(10, 30).fix_motion(motion, at=6)  # frames 6..9: the very last frame
    assert c.root_known[:, 0].tolist() == [False] * 6 + [True] * 4
    c = Constraints.none(4, 30).fix_motion(motion, at=0)
    assert c.root_known.all() and c.joints_known.all()
    with pytest.raises(ParameterError, match=r"constrained frames 7\.\.10 fall outside the dance's 0\.\.9"):
        Constraints.none(10, 30).fix_motion(motion, at=7)
    with pytest.raises(ParameterError, match=r"constrained frames -1\.\.2 fall outside"):
        Constraints.none(10, 30).fix_motion(motion, at=-1)


@pytest.mark.survivor
def test_fix_motion_resamples_to_the_constraints_frame_rate():
    at_60 = numbered_motion(10, fps=60)
    c = Constraints.none(8, 30).fix_motion(at_60)
    assert c.root_known[:, 0].tolist() == [True] * 5 + [False] * 3
    np.testing.assert_allclose(c.root[:5, 0], [0, 2, 4, 6, 8])
    at_30 = numbered_motion(3, fps=30)
    c = Constraints.none(8, 60).fix_motion(at_30)
    assert c.root_known[:, 0].tolist() == [True] * 6 + [False] * 2
    np.testing.assert_allclose(c.root[:6, 0], [0, 0.5, 1, 1.5, 2, 2])


@pytest.mark.survivor
def test_fix_motion_refuses_other_skeletons_and_bad_joints():
    with pytest.raises(ParameterError, match="constraints need an SMPL-24 motion; this one has 2 joints"):
        Constraints.none(10, 30).fix_motion(other_skeleton_motion())
    for joints in ([], [24], [-1, 3]):
        with pytest.raises(ParameterError, match=r"joint indices must lie in 0\.\.23"):
            Constraints.none(10, 30).fix_motion(numbered_motion(2), joints=joints)


@pytest.mark.survivor
def test_as_smpl_keeps_a_motion_at_the_same_rate_and_resamples_others():
    motion = numbered_motion(4, fps=30)
    assert as_smpl(motion, 30) is motion
    assert as_smpl(motion, 30 + 1e-7) is motion
    assert as_smpl(motion, 30 - 1e-7) is motion
    assert as_smpl(motion, 30 + 1e-5) is not motion  # resampled (to a copy: Motion.resample's own tolerance)
    assert as_smpl(motion, 30 - 1e-5) is not motion
    doubled = as_smpl(motion, 60)
    assert doubled.fps == 60 and doubled.num_frames == 8
    np.testing.assert_allclose(doubled.root_positions[:, 0], [0, 0.5, 1, 1.5, 2, 2.5, 3, 3])
    with pytest.raises(ParameterError, match="this one has 2 joints in another hierarchy"):
        as_smpl(other_skeleton_motion(), 30)


@pytest.mark.survivor
def test_check_joints_sorts_and_refuses_out_of_range():
    assert check_joints([5, 3, 3.0, 0]) == [0, 3, 5]
    assert check_joints(iter([23])) == [23]
    assert check_joints(range(24)) == list(range(24))
    for bad in ([], [-1], [24], [0, 24], [-1, 23]):
        with pytest.raises(ParameterError, match=r"^joint indices must lie in 0\.\.23$"):
            check_joints(bad)


@pytest.mark.survivor
def test_fix_root_path_sets_floor_position_and_optionally_height():
    c = Constraints.none(3, 30)
    xz = [[0, 1], [2, 3], [4, 5]]
    assert c.fix_root_path(xz) is c
    assert c.root.tolist() == [[0, 0, 1], [2, 0, 3], [4, 0, 5]]
    assert c.root_known.tolist() == [[True, False, True]] * 3
    assert not c.joints_known.any()
    c.fix_root_path(xz, height=[0.9, 1.0, 1.1])
    assert c.root.tolist() == [[0, 0.9, 1], [2, 1.0, 3], [4, 1.1, 5]]
    assert c.root_known.all()


@pytest.mark.survivor
def test_fix_root_path_reads_its_points_as_numbers():
    c = Constraints.none(2, 30).fix_root_path(np.array([["0.5", "1"], ["2", "-3"]]), height=np.array(["0.9", "1.25"]))
    assert c.root.tolist() == [[0.5, 0.9, 1], [2, 1.25, -3]] and c.root_known.all()


@pytest.mark.survivor
@pytest.mark.parametrize("xz", [np.zeros((2, 2)), np.zeros((3, 3)), np.zeros(6), [[0, 0], [1, np.inf], [2, 2]],
                                [[0, 0], [np.nan, 1], [2, 2]]])
def test_fix_root_path_refuses_wrong_shapes_and_non_finite_points(xz):
    c = Constraints.none(3, 30)
    with pytest.raises(ParameterError, match="a root path must be 3 finite"):
        c.fix_root_path(xz)
    assert not c.root_known.any()


@pytest.mark.survivor
@pytest.mark.parametrize("height", [np.zeros(2), np.zeros((3, 1)), [0.9, np.nan, 1.0], [0.9, 1.0, -np.inf]])
def test_fix_root_path_refuses_wrong_or_non_finite_heights(height):
    c = Constraints.none(3, 30)
    with pytest.raises(ParameterError, match="^root heights must be one finite value per frame$"):
        c.fix_root_path(np.zeros((3, 2)), height=height)
    assert not c.root_known[:, 1].any()


@pytest.mark.survivor
def test_free_clears_frames_and_joints_and_optionally_the_root():
    c = Constraints.none(6, 30).fix_motion(numbered_motion(6))
    assert c.free(slice(1, 3), joints=[4, 2], root=False) is c
    for t in range(6):
        for j in range(24):
            assert c.joints_known[t, j] == (not (t in (1, 2) and j in (2, 4)))
    assert c.root_known.all()
    c.free(slice(4, 6))
    assert c.joints_known.sum(1).tolist() == [24, 22, 22, 24, 0, 0]
    assert c.root_known.all(1).tolist() == [True, True, True, True, False, False]
    c.free(np.array([True, False, False, False, False, False]), joints=[0])
    assert c.joints_known[0].tolist() == [False] + [True] * 23 and not c.root_known[0].any()
    with pytest.raises(ParameterError, match="joint indices"):
        c.free(slice(0, 1), joints=[30])


@pytest.mark.survivor
def test_is_empty_and_known_fraction():
    c = Constraints.none(4, 30)
    assert c.is_empty is True
    c.root_known[2, 1] = True
    assert c.is_empty is False and c.known_fraction() == 0.0
    c = Constraints.none(4, 30)
    c.joints_known[1, 3] = True
    c.joints_known[3, 0:5] = True
    assert c.is_empty is False
    fraction = c.known_fraction()
    assert type(fraction) is float and fraction == 6 / 96


@pytest.mark.survivor
def test_target_motion_carries_root_rotations_and_rate():
    c = Constraints.none(3, 25).fix_motion(numbered_motion(2, fps=25), at=1)
    motion = c.target_motion()
    assert isinstance(motion, Motion) and motion.fps == 25.0 and motion.num_frames == 3
    assert motion.root_positions.tolist() == [[0, 0, 0], [0, 0.9, 0], [1, 0.9, -0.5]]
    np.testing.assert_allclose(motion.rotations[0], np.tile(IDENTITY, (24, 1)))
    np.testing.assert_allclose(motion.rotations[2, 6], [np.cos(0.14), 0, 0, np.sin(0.14)])


@pytest.mark.survivor
def test_frame_vectors_mask_every_channel_by_what_is_known():
    c = Constraints.none(5, 30)
    c.joints_known[0] = True
    c.root_known[0] = True  # frame 0: everything: contacts too
    c.joints_known[1] = True
    c.root_known[1, [0, 2]] = True  # frame 1: the root's height is free: no contacts
    c.joints_known[2, :23] = True
    c.root_known[2] = True  # frame 2: one joint free: no contacts
    c.joints_known[3, [1, 22]] = True  # frame 3: two joints only
    c.root[:, 0] = [1.0, 2.0, 3.0, 4.0, 5.0]
    c.root[:, 1] = 0.5
    c.rotations[3, 22] = [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]  # 90 degrees about z
    values, mask = c.frame_vectors()
    assert values.shape == (5, 151) and mask.shape == (5, 151) and mask.dtype == bool
    assert mask[:, 0:4].tolist() == [[True] * 4, [False] * 4, [False] * 4, [False] * 4, [False] * 4]
    assert mask[:, 4:7].tolist() == [[True] * 3, [True, False, True], [True] * 3, [False] * 3, [False] * 3]
    for t in range(5):
        for j in range(24):
            for k in range(6):
                assert mask[t, 7 + 6 * j + k] == c.joints_known[t, j], (t, j, k)
    np.testing.assert_allclose(values[:, 4], [1, 2, 3, 4, 5])
    np.testing.assert_allclose(values[:, 5], 0.5)
    np.testing.assert_allclose(values[0, 7:13], [1, 0, 0, 0, 1, 0], atol=1e-6)  # identity: first two rows
    np.testing.assert_allclose(values[3, 7 + 6 * 22:7 + 6 * 23], [0, -1, 0, 1, 0, 0], atol=1e-6)
