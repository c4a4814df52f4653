"""Tests of choreo.constraints.parse.

Markers say where a test came from: fuzz_finding, survivor (pyproject.toml, tests/README.md)."""


import numpy as np
import pytest

import choreo.constraints as constraints_package
from choreo.constraints import (
    ALL_JOINTS,
    JOINT_SETS,
    parse_frame_range,
    parse_joints,
    parse_style_schedule,
    parse_time_key,
    path_to_frames,
    read_pose,
    read_root_path,
)
from choreo.constraints import parse as parse_module
from choreo.constraints.displacement import REACH_FRAMES
from choreo.errors import InputError, ParameterError
from choreo.formats import write_motion
from tests.constraints.helpers import numbered_motion


@pytest.mark.survivor
def test_package_exports_and_joint_sets():
    assert sorted(constraints_package.__all__) == sorted(
        ["ALL_JOINTS", "Constraints", "JOINT_SETS", "along_path", "as_smpl", "between_poses", "inpainting",
         "parse_frame_range", "parse_joints", "parse_style_schedule", "parse_time_key", "path_to_frames", "read_pose",
         "read_root_path", "seed_motion"])
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


@pytest.mark.survivor
@pytest.mark.parametrize("text, expected", [
    ("60:90", slice(60, 90)), ("60:", slice(60, 100)), (":90", slice(0, 90)), (" :90", slice(0, 90)),
    ("60: ", slice(60, 100)), ("0:100", slice(0, 100)), ("99:100", slice(99, 100)), (" 4 : 5 ", slice(4, 5)),
    (":", slice(0, 100)),
])  # fmt: skip
def test_frame_ranges(text, expected):
    assert parse_frame_range(text, 100) == expected


@pytest.mark.survivor
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


@pytest.mark.survivor
@pytest.mark.parametrize("text, expected", [
    ("upper", (3, 6, 9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23)), (" Lower ", (0, 1, 2, 4, 5, 7, 8, 10, 11)),
    ("ALL", tuple(range(24))), ("l_wrist, 21", (20, 21)), ("L_Hip,pelvis", (0, 1)), ("23", (23,)), ("0", (0,)),
    ("r_hip , l_hip,1, 2", (1, 2)), ("r_hand,10,l_hand", (10, 22, 23)),
])  # fmt: skip
def test_joint_lists(text, expected):
    assert parse_joints(text) == expected


@pytest.mark.survivor
@pytest.mark.parametrize("text", ["24", "-1", "l_wing", "upper,lower", "", "1,,2", "3.0"])
def test_unknown_joints(text):
    with pytest.raises(ParameterError, match=r"unknown joint .* \(use upper, lower, all, or names like l_elbow\)"):
        parse_joints(text)


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
@pytest.mark.parametrize("text, expected", [
    ("4.0=pose.bvh", (4.0, "pose.bvh")), ("0=a", (0.0, "a")), (" 2 =x.npz@3", (2.0, "x.npz@3")),
    ("1.5=a=b.bvh", (1.5, "a=b.bvh")),
])  # fmt: skip
def test_time_keys(text, expected):
    seconds, source = parse_time_key(text)
    assert (seconds, source) == expected and type(seconds) is float


@pytest.mark.survivor
@pytest.mark.parametrize("text", ["4.0=", "4.0", "-1=a", "-0.5=a", "inf=a", "nan=a", "abc=a", "=a", "",
                                  "1e999=a", "1_0=a", "\uff14=a", "9" * 5000 + "=a"])
def test_bad_time_keys(text):
    with pytest.raises(ParameterError, match=r"must look like SECONDS=FILE \(e\.g\. 4\.0=pose\.bvh\)") as refused:
        parse_time_key(text)
    assert len(str(refused.value)) < 100


@pytest.mark.survivor
def test_a_key_past_any_song_is_refused_before_it_overflows():
    """Issue 48, item 10: --key 1e308=... became an infinite frame (exit 70)."""
    with pytest.raises(ParameterError, match="--key .*past any song's end"):
        parse_time_key("1e308=pose.bvh")


@pytest.mark.survivor
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


def write(tmp_path, text, name="p.csv"):
    path = tmp_path / name
    (path.write_bytes if isinstance(text, bytes) else path.write_text)(text)
    return path


@pytest.mark.survivor
def test_path_with_header_in_any_order_and_case(tmp_path):
    times, xz, heights = read_root_path(write(tmp_path, " Z , y,X, Time \n1,0.9,2,0\n3,1.0,4,0.5\n\n , \n5,1.1,6,2\n"))
    assert times.tolist() == [0, 0.5, 2]
    assert xz.tolist() == [[2, 1], [4, 3], [6, 5]]
    assert heights.tolist() == [0.9, 1.0, 1.1]
    times, xz, heights = read_root_path(write(tmp_path, "x,z,t\n1,2,0\n3,4,1\n", "q.TXT"))
    assert times.tolist() == [0, 1] and xz.tolist() == [[1, 2], [3, 4]] and heights is None
    times, xz, heights = read_root_path(write(tmp_path, "x,z\n1,2\n3,4\n", "r.CSV"))
    assert times is None and heights is None and xz.tolist() == [[1, 2], [3, 4]]


@pytest.mark.survivor
def test_path_without_header(tmp_path):
    times, xz, heights = read_root_path(write(tmp_path, "1,2\n3,4\n"))
    assert times is None and heights is None and xz.tolist() == [[1, 2], [3, 4]]
    times, xz, heights = read_root_path(write(tmp_path, "0,1,2\n2,3,4\n"))
    assert times.tolist() == [0, 2] and xz.tolist() == [[1, 2], [3, 4]] and heights is None
    with pytest.raises(InputError, match="path values must be finite numbers"):  # 'nan' is a number: no header
        read_root_path(write(tmp_path, "nan,1\n2,3\n"))


@pytest.mark.survivor
def test_path_limits_at_their_edges(tmp_path):
    _, xz, _ = read_root_path(write(tmp_path, "x,z\n10000,-10000\n0,0\n"))
    assert xz.tolist() == [[10000, -10000], [0, 0]]
    for text in ("x,z\n10000.5,0\n0,0\n", "x,z\n0,-10000.5\n0,0\n", "t,x,z,y\n0,0,0,0\n1,0,0,20000\n"):
        with pytest.raises(InputError, match="path values beyond 10000 .metres or seconds. are not a dance floor"):
            read_root_path(write(tmp_path, text))


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
def test_path_to_frames_needs_two_points():
    with pytest.raises(InputError, match="^a path needs at least two points$"):
        path_to_frames(None, np.zeros((1, 2)), None, 10)
    with pytest.raises(InputError, match="at least two points"):
        path_to_frames(np.zeros(0), np.zeros((0, 2)), None, 10)


@pytest.mark.survivor
def test_a_superscript_digit_is_an_unknown_joint():
    with pytest.raises(ParameterError, match="unknown joint"):
        parse_joints("²")


@pytest.mark.survivor
def test_a_pose_file_with_at_in_its_path(tmp_path):
    """'takes@2/pose.bvh' is a file, not frame '2/pose.bvh' of 'takes'; a frame still follows a last @."""
    folder = tmp_path / "takes@2"
    folder.mkdir()
    write_motion(numbered_motion(4), folder / "pose.bvh")
    assert read_pose(str(folder / "pose.bvh")).root_positions[0, 0] == pytest.approx(0.0, abs=1e-6)
    assert read_pose(f"{folder / 'pose.bvh'}@2").root_positions[0, 0] == pytest.approx(2.0, abs=1e-6)
    with pytest.raises(ParameterError, match="the part after @ must be a frame number"):
        read_pose(f"{folder / 'pose.bvh'}@two")


@pytest.mark.fuzz_finding
def test_a_path_csv_header_with_a_newline_is_named_in_one_line(tmp_path):
    """Found by the fuzzer (a two-line refusal): the header's cells were printed as they were."""
    from choreo.constraints.parse import read_root_path
    from choreo.errors import InputError

    path = tmp_path / "path.csv"
    path.write_bytes(b'"\xff\n0",1\n1,1,1\n')
    with pytest.raises(InputError) as raised:
        read_root_path(path)
    assert "\n" not in str(raised.value)
