"""The constraints package function by function, on hand-made motions and files, no model sampled.

Every expected value is written out or computed by a plain loop here; each error is matched by
the words of its message, so the mutation run of src/choreo/constraints/* can rely on this file.
"""

import numpy as np
import pytest

import choreo.constraints as constraints_package
from choreo.constraints import (ALL_JOINTS, JOINT_SETS, Constraints, as_smpl, parse_frame_range, parse_joints,
                                parse_style_schedule, parse_time_key, path_to_frames, read_pose, read_root_path)
from choreo.constraints import parse as parse_module
from choreo.constraints.displacement import REACH_FRAMES, displace_motion, displace_to_constraints, offset_anchors
from choreo.constraints.mask import check_joints
from choreo.errors import InputError, ParameterError
from choreo.formats import write_motion
from choreo.motion import Motion
from choreo.skeleton import Skeleton

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def numbered_motion(frames=6, fps=30.0):
    """Root x = frame number, every joint turned about z by an angle of its own per frame."""
    root = np.zeros((frames, 3))
    root[:, 0] = np.arange(frames)
    root[:, 1] = 0.9
    root[:, 2] = -0.5 * np.arange(frames)
    half = 0.01 * (np.arange(frames)[:, None] + 1) * (np.arange(24)[None] + 1)  # half angles
    rotations = np.zeros((frames, 24, 4))
    rotations[..., 0] = np.cos(half)
    rotations[..., 3] = np.sin(half)
    return Motion(root, rotations, fps=fps)


def other_skeleton_motion():
    small = Skeleton(("a", "b"), (-1, 0), np.array([[0, 0, 0], [0, 1, 0.0]]))
    return Motion(np.zeros((4, 3)), np.tile([1.0, 0, 0, 0], (4, 2, 1)), skeleton=small)


# -- mask.py: Constraints ---------------------------------------------------------------------------

def test_package_exports_and_joint_sets():
    assert sorted(constraints_package.__all__) == sorted(
        ["ALL_JOINTS", "Constraints", "JOINT_SETS", "as_smpl", "parse_frame_range", "parse_joints",
         "parse_style_schedule", "parse_time_key", "path_to_frames", "read_pose", "read_root_path"])
    for name in constraints_package.__all__:
        assert hasattr(constraints_package, name)
    assert ALL_JOINTS == tuple(range(24))
    assert JOINT_SETS["all"] == tuple(range(24))
    assert JOINT_SETS["lower"] == (0, 1, 2, 4, 5, 7, 8, 10, 11)
    assert JOINT_SETS["upper"] == (3, 6, 9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23)
    assert set(JOINT_SETS) == {"all", "upper", "lower"}
    assert REACH_FRAMES == 15
    assert parse_module.MAX_PATH_BYTES == 32 * 1024 * 1024
    assert parse_module.MAX_PATH_VALUE == 10000.0
    assert parse_module.PATH_SUFFIXES == (".csv", ".txt")


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


@pytest.mark.parametrize("frames", [0, -3])
def test_none_refuses_a_dance_without_frames(frames):
    with pytest.raises(ParameterError, match="^a dance needs at least one frame$"):
        Constraints.none(frames, 30)


def test_fixed_frames_are_those_with_any_joint_or_root_axis():
    c = Constraints.none(6, 30)
    c.joints_known[2, 7] = True
    c.root_known[4, 1] = True
    c.joints_known[5, :] = True
    c.root_known[5, :] = True
    assert c.fixed_frames().tolist() == [False, False, True, False, True, True]


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


def test_fix_motion_resamples_to_the_constraints_frame_rate():
    at_60 = numbered_motion(10, fps=60)
    c = Constraints.none(8, 30).fix_motion(at_60)
    assert c.root_known[:, 0].tolist() == [True] * 5 + [False] * 3
    np.testing.assert_allclose(c.root[:5, 0], [0, 2, 4, 6, 8])
    at_30 = numbered_motion(3, fps=30)
    c = Constraints.none(8, 60).fix_motion(at_30)
    assert c.root_known[:, 0].tolist() == [True] * 6 + [False] * 2
    np.testing.assert_allclose(c.root[:6, 0], [0, 0.5, 1, 1.5, 2, 2])


def test_fix_motion_refuses_other_skeletons_and_bad_joints():
    with pytest.raises(ParameterError, match="constraints need an SMPL-24 motion; this one has 2 joints"):
        Constraints.none(10, 30).fix_motion(other_skeleton_motion())
    for joints in ([], [24], [-1, 3]):
        with pytest.raises(ParameterError, match=r"joint indices must lie in 0\.\.23"):
            Constraints.none(10, 30).fix_motion(numbered_motion(2), joints=joints)


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


def test_check_joints_sorts_and_refuses_out_of_range():
    assert check_joints([5, 3, 3.0, 0]) == [0, 3, 5]
    assert check_joints(iter([23])) == [23]
    assert check_joints(range(24)) == list(range(24))
    for bad in ([], [-1], [24], [0, 24], [-1, 23]):
        with pytest.raises(ParameterError, match=r"^joint indices must lie in 0\.\.23$"):
            check_joints(bad)


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


def test_fix_root_path_reads_its_points_as_numbers():
    c = Constraints.none(2, 30).fix_root_path(np.array([["0.5", "1"], ["2", "-3"]]), height=np.array(["0.9", "1.25"]))
    assert c.root.tolist() == [[0.5, 0.9, 1], [2, 1.25, -3]] and c.root_known.all()


@pytest.mark.parametrize("xz", [np.zeros((2, 2)), np.zeros((3, 3)), np.zeros(6), [[0, 0], [1, np.inf], [2, 2]],
                                [[0, 0], [np.nan, 1], [2, 2]]])
def test_fix_root_path_refuses_wrong_shapes_and_non_finite_points(xz):
    c = Constraints.none(3, 30)
    with pytest.raises(ParameterError, match="a root path must be 3 finite"):
        c.fix_root_path(xz)
    assert not c.root_known.any()


@pytest.mark.parametrize("height", [np.zeros(2), np.zeros((3, 1)), [0.9, np.nan, 1.0], [0.9, 1.0, -np.inf]])
def test_fix_root_path_refuses_wrong_or_non_finite_heights(height):
    c = Constraints.none(3, 30)
    with pytest.raises(ParameterError, match="^root heights must be one finite value per frame$"):
        c.fix_root_path(np.zeros((3, 2)), height=height)
    assert not c.root_known[:, 1].any()


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


def test_target_motion_carries_root_rotations_and_rate():
    c = Constraints.none(3, 25).fix_motion(numbered_motion(2, fps=25), at=1)
    motion = c.target_motion()
    assert isinstance(motion, Motion) and motion.fps == 25.0 and motion.num_frames == 3
    assert motion.root_positions.tolist() == [[0, 0, 0], [0, 0.9, 0], [1, 0.9, -0.5]]
    np.testing.assert_allclose(motion.rotations[0], np.tile(IDENTITY, (24, 1)))
    np.testing.assert_allclose(motion.rotations[2, 6], [np.cos(0.14), 0, 0, np.sin(0.14)])


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


# -- parse.py: user syntax --------------------------------------------------------------------------

@pytest.mark.parametrize("text, expected", [
    ("60:90", slice(60, 90)), ("60:", slice(60, 100)), (":90", slice(0, 90)), (" :90", slice(0, 90)),
    ("60: ", slice(60, 100)), ("0:100", slice(0, 100)), ("99:100", slice(99, 100)), (" 4 : 5 ", slice(4, 5)),
    (":", slice(0, 100)),
])  # fmt: skip
def test_frame_ranges(text, expected):
    assert parse_frame_range(text, 100) == expected


@pytest.mark.parametrize("text, message", [
    ("60", "must look like START:END"), ("1:2:3", "must look like START:END"), ("", "must look like START:END"),
    ("a:b", "must hold whole frame numbers"), ("1.5:3", "must hold whole frame numbers"),
    ("2:x", "must hold whole frame numbers"),
    ("0:101", "is outside the dance's frames 0..100"), ("-1:5", "outside"), ("5:5", "outside"), ("6:5", "outside"),
    ("100:", "outside"), (":0", "outside"),
])  # fmt: skip
def test_bad_frame_ranges(text, message):
    with pytest.raises(ParameterError, match=message.replace(".", r"\.")):
        parse_frame_range(text, 100)


@pytest.mark.parametrize("text, expected", [
    ("upper", (3, 6, 9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23)), (" Lower ", (0, 1, 2, 4, 5, 7, 8, 10, 11)),
    ("ALL", tuple(range(24))), ("l_wrist, 21", (20, 21)), ("L_Hip,pelvis", (0, 1)), ("23", (23,)), ("0", (0,)),
    ("r_hip , l_hip,1, 2", (1, 2)), ("r_hand,10,l_hand", (10, 22, 23)),
])  # fmt: skip
def test_joint_lists(text, expected):
    assert parse_joints(text) == expected


@pytest.mark.parametrize("text", ["24", "-1", "l_wing", "upper,lower", "", "1,,2", "3.0"])
def test_unknown_joints(text):
    with pytest.raises(ParameterError, match=r"unknown joint .* \(use upper, lower, all, or names like l_elbow\)"):
        parse_joints(text)


def test_style_schedules():
    assert parse_style_schedule("0:30=waltz,30:=cha-cha", 60) == [(0.0, 30.0, "waltz"), (30.0, None, "cha-cha")]
    assert parse_style_schedule(" 30 : = tango ,  : 30 =  slow waltz ", 60) == [(0.0, 30.0, "slow waltz"),
                                                                             (30.0, None, "tango")]
    assert parse_style_schedule("0:10=a,10:20=b,25.5:=c", 30) == [(0.0, 10.0, "a"), (10.0, 20.0, "b"), (25.5, None, "c")]
    assert parse_style_schedule("0:59.9=a", 60) == [(0.0, 59.9, "a")]
    assert parse_style_schedule("59.5:=a", 60) == [(59.5, None, "a")]
    start, stop, _ = parse_style_schedule("2:3=a", 60)[0]
    assert type(start) is float and type(stop) is float
    for plain in ("slow, romantic, hips leading", "waltz", "a=b", "1=2"):
        assert parse_style_schedule(plain, 60) is None


@pytest.mark.parametrize("text, message", [
    ("0:30=waltz,tango", "every entry must look like START:END=STYLE"),
    ("0:30=,30:=b", "every entry must look like START:END=STYLE"),
    ("1.2.3:5=waltz", "times must be seconds"), ("0:..=waltz", "times must be seconds"),
    ("10:5=waltz", "10:5 is empty"), ("10:10=waltz", "10:10 is empty"),
    ("60:=waltz", "60 s is past the song's end (60.0 s)"), ("70:80=waltz", "past the song's end"),
    ("0:30=waltz,20:=rumba", "time ranges overlap"), ("0:31=a,30:=b", "time ranges overlap"),
    ("0:=a,30:40=b", "time ranges overlap"), ("0:10=a,10:20=b,15:30=c", "time ranges overlap"),
    ("0:10=a,20:=b,5:8=c", "time ranges overlap"), ("0:=a,0:10=b", "time ranges overlap"),
    ("5:10=a,5:=b", "time ranges overlap"),
])  # fmt: skip
def test_bad_style_schedules(text, message):
    with pytest.raises(ParameterError, match="style schedule .*" + message.replace(".", r"\.").replace("(", r"\(")
                       .replace(")", r"\)")):
        parse_style_schedule(text, 60)


@pytest.mark.parametrize("text, expected", [
    ("4.0=pose.bvh", (4.0, "pose.bvh")), ("0=a", (0.0, "a")), (" 2 =x.npz@3", (2.0, "x.npz@3")),
    ("1.5=a=b.bvh", (1.5, "a=b.bvh")),
])  # fmt: skip
def test_time_keys(text, expected):
    seconds, source = parse_time_key(text)
    assert (seconds, source) == expected and type(seconds) is float


@pytest.mark.parametrize("text", ["4.0=", "4.0", "-1=a", "-0.5=a", "inf=a", "nan=a", "abc=a", "=a", "",
                                  "1e999=a", "1_0=a", "\uff14=a", "9" * 5000 + "=a"])
def test_bad_time_keys(text):
    with pytest.raises(ParameterError, match=r"must look like SECONDS=FILE \(e\.g\. 4\.0=pose\.bvh\)") as refused:
        parse_time_key(text)
    assert len(str(refused.value)) < 100


def test_a_key_past_any_song_is_refused_before_it_overflows():
    """Issue 48, item 10: --key 1e308=... became an infinite frame (exit 70)."""
    with pytest.raises(ParameterError, match="--key .*past any song's end"):
        parse_time_key("1e308=pose.bvh")


def test_poses_from_any_frame(tmp_path):
    folder = tmp_path / "a@b"  # an @ in a folder name: only the last one splits off the frame
    folder.mkdir()
    motion = numbered_motion(5)
    write_motion(motion, folder / "m.npz")
    name = str(folder / "m.npz")
    for spec, frame in ((f"{name}@0", 0), (f"{name}@3", 3), (f"{name}@4", 4), (f"{name}@-1", 4),
                        (f"{name}@-5", 0), (f"{name}@-2", 3)):
        pose = read_pose(spec)
        assert pose.num_frames == 1, spec
        np.testing.assert_allclose(pose.root_positions[0], [frame, 0.9, -0.5 * frame], atol=1e-6, err_msg=spec)
        np.testing.assert_allclose(pose.rotations[0], motion.rotations[frame], atol=1e-6, err_msg=spec)
    write_motion(motion, tmp_path / "plain.npz")
    np.testing.assert_allclose(read_pose(str(tmp_path / "plain.npz")).root_positions, [[0, 0.9, 0]], atol=1e-6)
    for spec in (f"{name}@5", f"{name}@-6", f"{name}@99"):
        with pytest.raises(ParameterError, match="m.npz has 5 frames"):
            read_pose(spec)
    for spec in (f"{name}@x", f"{name}@", f"{name}@1.5"):
        with pytest.raises(ParameterError, match="the part after @ must be a frame number"):
            read_pose(spec)


# -- parse.py: path files ---------------------------------------------------------------------------

def write(tmp_path, text, name="p.csv"):
    path = tmp_path / name
    (path.write_bytes if isinstance(text, bytes) else path.write_text)(text)
    return path


def test_path_with_header_in_any_order_and_case(tmp_path):
    times, xz, heights = read_root_path(write(tmp_path, " Z , y,X, Time \n1,0.9,2,0\n3,1.0,4,0.5\n\n , \n5,1.1,6,2\n"))
    assert times.tolist() == [0, 0.5, 2]
    assert xz.tolist() == [[2, 1], [4, 3], [6, 5]]
    assert heights.tolist() == [0.9, 1.0, 1.1]
    times, xz, heights = read_root_path(write(tmp_path, "x,z,t\n1,2,0\n3,4,1\n", "q.TXT"))
    assert times.tolist() == [0, 1] and xz.tolist() == [[1, 2], [3, 4]] and heights is None
    times, xz, heights = read_root_path(write(tmp_path, "x,z\n1,2\n3,4\n", "r.CSV"))
    assert times is None and heights is None and xz.tolist() == [[1, 2], [3, 4]]


def test_path_without_header(tmp_path):
    times, xz, heights = read_root_path(write(tmp_path, "1,2\n3,4\n"))
    assert times is None and heights is None and xz.tolist() == [[1, 2], [3, 4]]
    times, xz, heights = read_root_path(write(tmp_path, "0,1,2\n2,3,4\n"))
    assert times.tolist() == [0, 2] and xz.tolist() == [[1, 2], [3, 4]] and heights is None
    with pytest.raises(InputError, match="path values must be finite numbers"):  # 'nan' is a number: no header
        read_root_path(write(tmp_path, "nan,1\n2,3\n"))


def test_path_limits_at_their_edges(tmp_path):
    _, xz, _ = read_root_path(write(tmp_path, "x,z\n10000,-10000\n0,0\n"))
    assert xz.tolist() == [[10000, -10000], [0, 0]]
    for text in ("x,z\n10000.5,0\n0,0\n", "x,z\n0,-10000.5\n0,0\n", "t,x,z,y\n0,0,0,0\n1,0,0,20000\n"):
        with pytest.raises(InputError, match="path values beyond 10000 .metres or seconds. are not a dance floor"):
            read_root_path(write(tmp_path, text))


@pytest.mark.parametrize("text, message", [
    ("", "is empty"), ("\n , \n\n", "is empty"),
    ("x,z\n", "every row needs 2 values"), ("x,z\n1,2,3\n4,5,6\n", "every row needs 2 values"),
    ("x,z\n1,2\n", "a path needs at least two points"), ("1,2\n", "a path needs at least two points"),
    ("x,z\n1,2\n3,oops\n", "every value must be a number"), ("x,z\n1,2\n3\n", "every value must be a number"),
    (b"x,z\n1,2\n3,\xff\n", "every value must be a number"),
    ("a,b\n1,2\n3,4\n", "header must name x and z .and optionally t, y., got 'a, b'"),
    ("x,y\n1,2\n3,4\n", "header must name x and z"), ("z,t\n1,2\n3,4\n", "header must name x and z"),
    ("x,z,w\n1,2,3\n3,4,5\n", "header must name x and z"),
    ("1,2,3,4\n5,6,7,8\n", "without a header a path has 2 columns .x, z. or 3 .t, x, z., not 4"),
    ("1\n2\n", "without a header a path has 2 columns"),
    ("t,x,z\n0,0,0\n0,1,1\n", "times must increase"), ("t,x,z\n0,0,0\n1,1,1\n0.5,2,2\n", "times must increase"),
    ("x,z\n1,2\nnan,3\n", "path values must be finite numbers"), ("x,z\n1,2\n3,-inf\n", "must be finite"),
])  # fmt: skip
def test_bad_path_files(tmp_path, text, message):
    with pytest.raises(InputError, match=message):
        read_root_path(write(tmp_path, text))


def test_path_files_that_are_missing_or_too_big(tmp_path, monkeypatch):
    with pytest.raises(InputError, match="path file .*nowhere.csv does not exist"):
        read_root_path(tmp_path / "nowhere.csv")
    (tmp_path / "folder.csv").mkdir()
    with pytest.raises(InputError, match="does not exist"):
        read_root_path(tmp_path / "folder.csv")
    huge = tmp_path / "huge.csv"
    with open(huge, "wb") as f:  # sparse: no disk used
        f.truncate(32 * 1024 * 1024 + 1)
    with pytest.raises(InputError, match=r"is larger than 32 MiB: thin it out \(a point per frame is plenty\)"):
        read_root_path(huge)
    text = "x,z\n1,2\n3,4\n"  # 12 bytes
    monkeypatch.setattr(parse_module, "MAX_PATH_BYTES", 12)
    assert read_root_path(write(tmp_path, text)) is not None
    monkeypatch.setattr(parse_module, "MAX_PATH_BYTES", 11)
    with pytest.raises(InputError, match="is larger than"):
        read_root_path(write(tmp_path, text))


def test_path_from_a_motion_file(tmp_path):
    motion = numbered_motion(4, fps=25)
    write_motion(motion, tmp_path / "m.npz")
    times, xz, heights = read_root_path(tmp_path / "m.npz")
    np.testing.assert_allclose(times, [0, 0.04, 0.08, 0.12])
    np.testing.assert_allclose(xz, [[0, 0], [1, -0.5], [2, -1], [3, -1.5]], atol=1e-6)
    np.testing.assert_allclose(heights, [0.9] * 4, atol=1e-6)


def piecewise_linear(x, xp, fp):
    """A plain loop: the value at x on the polyline through (xp, fp), held beyond the ends."""
    out = []
    for value in x:
        if value <= xp[0]:
            out.append(fp[0])
            continue
        for i in range(1, len(xp)):
            if value <= xp[i]:
                w = (value - xp[i - 1]) / (xp[i] - xp[i - 1])
                out.append(fp[i - 1] + w * (fp[i] - fp[i - 1]))
                break
        else:
            out.append(fp[-1])
    return np.array(out)


def test_path_to_frames_by_times_and_evenly():
    xz = np.array([[0.0, 6.0], [3.0, 0.0], [9.0, 3.0]])
    frames, heights = path_to_frames(np.array([1.0, 2.0, 4.0]), xz, np.array([1.0, 2.0, 0.0]), 7)
    assert frames.shape == (7, 2)
    progress = [0, 1 / 3, 1]
    sample = [i / 6 for i in range(7)]
    np.testing.assert_allclose(frames[:, 0], piecewise_linear(sample, progress, [0, 3, 9]))
    np.testing.assert_allclose(frames[:, 1], piecewise_linear(sample, progress, [6, 0, 3]))
    np.testing.assert_allclose(frames[2], [3, 0])  # t = 2 of 1..4 is a third through: frame 2 of 0..6
    np.testing.assert_allclose(heights, piecewise_linear(sample, progress, [1, 2, 0]))
    frames, heights = path_to_frames(None, np.array([[0.0, 0.0], [2.0, -4.0]]), None, 5)
    assert heights is None
    assert frames.tolist() == [[0, 0], [0.5, -1], [1, -2], [1.5, -3], [2, -4]]
    frames, _ = path_to_frames(None, np.array([[0.0, 0.0], [2.0, 4.0], [4.0, 4.0]]), None, 3)
    assert frames.tolist() == [[0, 0], [2, 4], [4, 4]]


def test_path_to_frames_needs_two_points():
    with pytest.raises(InputError, match="^a path needs at least two points$"):
        path_to_frames(None, np.zeros((1, 2)), None, 10)
    with pytest.raises(InputError, match="at least two points"):
        path_to_frames(np.zeros(0), np.zeros((0, 2)), None, 10)


# -- displacement.py --------------------------------------------------------------------------------

def one_channel(length, keys, reach, base=None):
    """Frames ``base`` (zeros) moved to {frame: value} ``keys`` on a single channel."""
    frames = np.zeros((length, 1)) if base is None else np.asarray(base, dtype=np.float64)[:, None]
    values = np.zeros((length, 1))
    mask = np.zeros((length, 1), bool)
    for frame, value in keys.items():
        values[frame, 0] = value
        mask[frame, 0] = True
    return displace_to_constraints(frames, values, mask, reach=reach)[:, 0]


def test_one_keyframe_makes_a_tent_reach_frames_wide():
    moved = one_channel(20, {10: 8.0}, reach=4)
    assert moved.tolist() == [0] * 6 + [0, 2, 4, 6, 8, 6, 4, 2, 0] + [0] * 5


def test_default_reach_is_fifteen_frames():
    frames = np.zeros((60, 1))
    values = np.full((60, 1), 15.0)
    mask = np.zeros((60, 1), bool)
    mask[30] = True
    moved = displace_to_constraints(frames, values, mask)[:, 0]
    expected = [max(0.0, 15.0 - abs(t - 30)) for t in range(60)]
    assert moved.tolist() == expected


def test_close_keyframes_are_bridged_and_far_ones_fade_alone():
    bridged = one_channel(20, {5: 4.0, 11: -2.0}, reach=4)  # 6 frames apart, up to 8 bridged
    expected = [0, 0, 1, 2, 3, 4, 3, 2, 1, 0, -1, -2, -1.5, -1, -0.5, 0, 0, 0, 0, 0]
    np.testing.assert_allclose(bridged, expected)
    edge = one_channel(16, {2: 6.0, 8: 0.0}, reach=3)  # exactly 2 x reach apart: still bridged
    np.testing.assert_allclose(edge, [2, 4, 6, 5, 4, 3, 2, 1, 0, 0, 0, 0, 0, 0, 0, 0])
    apart = one_channel(16, {2: 6.0, 9: 3.0}, reach=3)  # one frame more: each fades on its own
    np.testing.assert_allclose(apart, [2, 4, 6, 4, 2, 0, 0, 1, 2, 3, 2, 1, 0, 0, 0, 0])


def test_three_runs_of_keyframes():
    moved = one_channel(30, {3: 3.0, 4: 3.0, 14: 6.0, 25: 3.0}, reach=3)
    expected = np.zeros(30)
    expected[0:8] = [0, 1, 2, 3, 3, 2, 1, 0]
    expected[11:18] = [0, 2, 4, 6, 4, 2, 0]
    expected[22:29] = [0, 1, 2, 3, 2, 1, 0]
    np.testing.assert_allclose(moved, expected)


def test_displacement_adds_to_the_frames_and_lands_exactly_on_the_values():
    base = np.array([10.0, 11, 12, 13, 14, 15, 16, 17, 18, 19])
    moved = one_channel(10, {4: 20.0}, reach=2)  # from zeros first, then from the ramp
    assert moved.tolist() == [0, 0, 0, 10, 20, 10, 0, 0, 0, 0]
    moved = one_channel(10, {4: 20.0}, reach=2, base=base)  # offset 20 - 14 = 6
    assert moved.tolist() == [10, 11, 12, 13 + 3, 20, 15 + 3, 16, 17, 18, 19]
    moved = one_channel(10, {0: 0.0, 9: 29.0}, reach=20, base=base)  # offsets -10 and +10, bridged
    np.testing.assert_allclose(moved, [(10 + t) + (-10 + 20 * t / 9) for t in range(10)])  # 29 t / 9


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


def test_offset_anchors_by_hand():
    anchors, values = offset_anchors(np.array([10]), np.array([5.0]), 4)
    assert anchors.tolist() == [6, 10, 14] and values.tolist() == [0, 5, 0] and anchors.dtype == np.float64
    anchors, values = offset_anchors(np.array([2, 3, 20]), np.array([1.0, 2.0, 3.0]), 4)
    assert anchors.tolist() == [-2, 2, 3, 7, 16, 20, 24]
    assert values.tolist() == [0, 1, 2, 0, 0, 3, 0]
    anchors, values = offset_anchors(np.array([0, 8, 17, 40]), np.array([1.0, 2.0, 3.0, 4.0]), 4)
    assert anchors.tolist() == [-4, 0, 8, 12, 13, 17, 21, 36, 40, 44]
    assert values.tolist() == [0, 1, 2, 0, 0, 3, 0, 0, 4, 0]


# -- bugs found here, left for the owners: each test says what should happen ------------------------

def test_a_superscript_digit_is_an_unknown_joint():
    with pytest.raises(ParameterError, match="unknown joint"):
        parse_joints("²")


def test_reach_zero_moves_only_the_given_frames():
    moved = one_channel(10, {2: 5.0, 7: 10.0}, reach=0)
    assert moved.tolist() == [0, 0, 5, 0, 0, 0, 0, 10, 0, 0]


def test_a_pose_file_with_at_in_its_path(tmp_path):
    """'takes@2/pose.bvh' is a file, not frame '2/pose.bvh' of 'takes'; a frame still follows a last @."""
    folder = tmp_path / "takes@2"
    folder.mkdir()
    write_motion(numbered_motion(4), folder / "pose.bvh")
    assert read_pose(str(folder / "pose.bvh")).root_positions[0, 0] == pytest.approx(0.0, abs=1e-6)
    assert read_pose(f"{folder / 'pose.bvh'}@2").root_positions[0, 0] == pytest.approx(2.0, abs=1e-6)
    with pytest.raises(ParameterError, match="the part after @ must be a frame number"):
        read_pose(f"{folder / 'pose.bvh'}@two")
