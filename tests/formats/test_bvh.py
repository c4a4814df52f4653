"""Tests of choreo.formats.bvh.

Markers say where a test came from: hardening, survivor (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import io
import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from choreo.errors import ChoreoError, MotionFormatError
from choreo.formats import (
    bvh,
    parse_bvh,
    read_bvh_raw,
    read_motion,
    write_motion,
)
from choreo.formats.bvh import detect_scale, write_bvh
from choreo.formats.rigs import read_bvh_rig, write_bvh_rig
from choreo.motion import Motion
from choreo.skeleton import SMPL24, Skeleton, continuous_euler, euler_to_matrix, matrix_to_euler
from tests.conftest import wandering_dance
from tests.formats.helpers import TOLERANCE, J, file_forward_kinematics, max_joint_error, random_motion, save, still
from tests.formats.hostile import hostile_dance, peak_bytes


def gimbal_motion():
    """Every joint at the ZXY gimbal lock (X = +-90 deg), where Euler angles are ill-conditioned."""
    rng = np.random.default_rng(3)
    angles = rng.uniform(-math.pi, math.pi, size=(20, 24, 3))
    angles[..., 1] = np.where(rng.random((20, 24)) < 0.5, math.pi / 2, -math.pi / 2) + rng.normal(scale=1e-7, size=(20, 24))
    return Motion.from_rotation_matrices(rng.normal(size=(20, 3)), euler_to_matrix(angles, "ZXY"))


def test_bvh_round_trip_at_gimbal_lock(tmp_path):
    motion = gimbal_motion()
    write_motion(motion, tmp_path / "lock.bvh")
    assert max_joint_error(read_motion(tmp_path / "lock.bvh"), motion) < TOLERANCE


def bvh_rotation_channels(path) -> np.ndarray:
    """(T, 3 J) the rotation channels of a BVH written by choreo (after the root's 3 positions)."""
    values = np.loadtxt(str(path), skiprows=path.read_text().splitlines().index("MOTION") + 3, ndmin=2)
    return values[:, 3:]


def test_bvh_curves_are_continuous_for_a_spinning_dancer_and_read_back_the_same(tmp_path):
    """A root turning two and a half times and a limb swinging through its middle axis's 90 degrees:
    each frame's Euler triple is the one nearest the previous frame's (no 360 degree wraps, no
    flips to the other solution), and the rotations read back unchanged."""
    frames = 150
    t = np.linspace(0.0, 1.0, frames)
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 0, 1] = 5 * np.pi * t  # the root spins about Y (up)
    axis_angle[:, 16, 0] = np.pi * (t - 0.5) * 1.6  # the left shoulder swings about X through +-72 degrees
    axis_angle[:, 18, :] = np.stack([np.sin(9 * t), np.pi / 2 * np.cos(3 * t), 2 * t], axis=1)  # near gimbal
    motion = Motion.from_axis_angle(np.tile([0.0, 0.9, 0.0], (frames, 1)), axis_angle)
    write_motion(motion, tmp_path / "spin.bvh")
    channels = bvh_rotation_channels(tmp_path / "spin.bvh")
    assert np.abs(np.diff(channels, axis=0)).max() < 45.0  # degrees between frames: no wrap, no flip
    assert np.ptp(channels) > 720  # the spin accumulates instead of wrapping
    back = read_motion(tmp_path / "spin.bvh")
    assert np.abs(back.rotation_matrices() - motion.rotation_matrices()).max() < 1e-5


def test_continuous_euler_keeps_each_rotation():
    rng = np.random.default_rng(3)
    for order in ("ZXY", "XYZ", "YZX"):
        angles = matrix_to_euler(euler_to_matrix(rng.uniform(-np.pi, np.pi, (200, 5, 3)), order), order)
        smooth = continuous_euler(angles)
        np.testing.assert_allclose(euler_to_matrix(smooth, order), euler_to_matrix(angles, order), atol=1e-12)
        step = np.abs(np.diff(smooth, axis=0)).sum(-1)
        assert (step <= np.abs(np.diff(angles, axis=0)).sum(-1) + 1e-9).all()  # never further than as solved


def test_bvh_in_centimetres_reads_back_in_metres(tmp_path):
    motion = random_motion()
    with open(tmp_path / "cm.bvh", "wb") as handle:
        write_bvh(motion, handle, units="cm")
    text = (tmp_path / "cm.bvh").read_text()
    assert "OFFSET 5.858135 -8.228004 -1.766408" in text  # l_hip in centimetres
    assert max_joint_error(read_motion(tmp_path / "cm.bvh"), motion) < TOLERANCE


def test_rest_pose_bvh_gives_the_template(tmp_path):
    motion = Motion.rest(3).translated([0.5, 0.0, -1.0])
    write_motion(motion, tmp_path / "rest.bvh")
    text = (tmp_path / "rest.bvh").read_text()
    assert "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation" in text
    assert "Frame Time: 0.03333333" in text
    positions = read_motion(tmp_path / "rest.bvh").joint_positions()
    np.testing.assert_allclose(positions[0], SMPL24.rest_positions() + motion.root_positions[0], atol=1e-5)


def _bvh_with_order(motion: Motion, order: str) -> str:
    """Our skeleton, written by hand with another rotation order, as another tool might."""
    ours = io.BytesIO()
    write_bvh(motion, ours)
    text = ours.getvalue().decode()
    head = text[: text.index("MOTION")].replace("Zrotation Xrotation Yrotation", " ".join(f"{a}rotation" for a in order))
    depth_first = [0, 1, 4, 7, 10, 2, 5, 8, 11, 3, 6, 9, 12, 15, 13, 16, 18, 20, 22, 14, 17, 19, 21, 23]
    angles = np.degrees(matrix_to_euler(motion.rotation_matrices(), order))[:, depth_first]
    rows = np.concatenate([motion.root_positions, angles.reshape(len(angles), -1)], axis=1)
    body = "\n".join(" ".join(f"{v:.6f}" for v in row) for row in rows)
    return f"{head}MOTION\nFrames: {len(rows)}\nFrame Time: {1 / motion.fps:.8f}\n{body}\n"


@pytest.mark.parametrize("order", ["XYZ", "YXZ", "ZYX"])
def test_bvh_with_another_rotation_order(tmp_path, order):
    motion = random_motion(wild=True)
    (tmp_path / "other.bvh").write_text(_bvh_with_order(motion, order))
    assert max_joint_error(read_motion(tmp_path / "other.bvh"), motion) < TOLERANCE


def test_bvh_with_smpl_names_in_another_style_and_order(tmp_path):
    motion = random_motion()
    write_motion(motion, tmp_path / "a.bvh")
    text = (tmp_path / "a.bvh").read_text()
    for name in sorted(SMPL24.names, key=len, reverse=True):  # m_avg_L_Hip style, as SMPL-to-FBX tools name them
        styled = "m_avg_" + "_".join(part.capitalize() if len(part) > 1 else part.upper() for part in name.split("_"))
        text = text.replace(f"JOINT {name}\n", f"JOINT {styled}\n").replace(f"ROOT {name}\n", f"ROOT {styled}\n")
    assert "m_avg_L_Hip" in text
    (tmp_path / "b.bvh").write_text(text)
    assert max_joint_error(read_motion(tmp_path / "b.bvh"), motion) < TOLERANCE


def test_truncated_bvh(tmp_path):
    write_motion(random_motion(), tmp_path / "a.bvh")
    text = (tmp_path / "a.bvh").read_text()
    for cut in (0.3, 0.8, 0.999):
        (tmp_path / "cut.bvh").write_text(text[: int(len(text) * cut)])
        with pytest.raises(MotionFormatError) as info:
            read_motion(tmp_path / "cut.bvh")
        assert "\n" not in str(info.value) and "cut.bvh" in str(info.value)


def test_bvh_with_another_skeleton(tmp_path):
    text = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 10 0
\t\t}
\t}
}
MOTION
Frames: 1
Frame Time: 0.033333
0 90 0 0 0 0 0 0 0
"""
    (tmp_path / "other.bvh").write_text(text)
    with pytest.raises(MotionFormatError, match="not SMPL-24"):
        read_motion(tmp_path / "other.bvh")
    raw = parse_bvh(text)  # the generic parser still reads it
    assert [j.name for j in raw.joints] == ["Hips", "Spine"] and raw.values.shape == (1, 9)


def test_nan_in_bvh_and_in_npz(tmp_path):
    write_motion(random_motion(), tmp_path / "a.bvh")
    lines = (tmp_path / "a.bvh").read_text().splitlines()
    lines[-3] = " ".join(["nan"] + lines[-3].split()[1:])
    (tmp_path / "nan.bvh").write_text("\n".join(lines) + "\n")
    with pytest.raises(MotionFormatError, match="NaN"):
        read_motion(tmp_path / "nan.bvh")
    poses = np.zeros((4, 72))
    poses[2, 5] = np.inf
    np.savez(tmp_path / "inf.npz", smpl_poses=poses, smpl_trans=np.zeros((4, 3)))
    with pytest.raises(MotionFormatError):
        read_motion(tmp_path / "inf.npz")


@pytest.fixture(scope="module")
def reference_bvh_text():
    buffer = io.BytesIO()
    write_bvh(random_motion(frames=3), buffer)
    return buffer.getvalue().decode()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_fuzz_bvh_parser_only_raises_our_errors(reference_bvh_text, data):
    text = reference_bvh_text
    kind = data.draw(st.sampled_from(["cut", "replace", "insert", "garbage"]))
    if kind == "cut":
        text = text[: data.draw(st.integers(0, len(text)))]
    elif kind == "replace":
        at = data.draw(st.integers(0, len(text) - 1))
        text = text[:at] + data.draw(st.text(max_size=5)) + text[at + 1:]
    elif kind == "insert":
        at = data.draw(st.integers(0, len(text)))
        text = text[:at] + data.draw(st.sampled_from(["{", "}", " JOINT x ", "nan", "1e999", "\n", "End Site"])) + text[at:]
    else:
        text = data.draw(st.text(max_size=200))
    try:
        motion = parse_bvh(text)
    except ChoreoError:
        return
    assert np.isfinite(motion.values).all()


# -- BVH parsing: a hand-written two-joint file -----------------------------------------------------
ROWS = ["1 2 3 10 20 30 40 50 60", "4 5 6 -10 -20 -30 -40 -50 -60"]


def bvh_text(rows=ROWS, frames=None, frame_time="0.04", chest_channels="CHANNELS 3 Zrotation Xrotation Yrotation"):
    return ("HIERARCHY\n"                                                        # line 1
            "ROOT hips\n{\n"                                                     # 2, 3
            "\tOFFSET 0.5 0 0\n"                                                 # 4
            "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"  # 5
            "\tJOINT chest\n\t{\n"                                               # 6, 7
            "\t\tOFFSET 0 1 0\n"                                                 # 8
            f"\t\t{chest_channels}\n"                                            # 9
            "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 0.5 0\n\t\t}\n"                 # 10-13
            "\t}\n}\n"                                                           # 14, 15
            "MOTION\n"                                                           # 16
            f"Frames: {len(rows) if frames is None else frames}\n"               # 17
            f"Frame Time: {frame_time}\n"                                        # 18
            + "".join(row + "\n" for row in rows))                               # 19, 20


@pytest.mark.survivor
def test_two_joint_file_parses_into_joints_channels_and_values():
    data = bvh.parse_bvh(bvh_text(), "dance.bvh")
    hips, chest = data.joints
    assert (hips.name, hips.parent, chest.name, chest.parent) == ("hips", -1, "chest", 0)
    np.testing.assert_array_equal(hips.offset, [0.5, 0.0, 0.0])
    np.testing.assert_array_equal(chest.offset, [0.0, 1.0, 0.0])
    assert hips.end_site is None
    np.testing.assert_array_equal(chest.end_site, [0.0, 0.5, 0.0])
    assert hips.channels == ["xposition", "yposition", "zposition", "zrotation", "xrotation", "yrotation"]
    assert chest.channels == ["zrotation", "xrotation", "yrotation"]
    assert data.frame_time == 0.04
    np.testing.assert_array_equal(data.values, [[float(v) for v in row.split()] for row in ROWS])
    assert data.channel_slices() == [slice(0, 6), slice(6, 9)]


@pytest.mark.survivor
def test_end_site_offsets_belong_to_the_joint_that_holds_them():
    text = ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\nJOINT b\n{\nOFFSET 0 1 0\nCHANNELS 0\nJOINT c\n{\n"
            "OFFSET 0 2 0\nCHANNELS 0\nJOINT d\n{\nOFFSET 0 3 0\nEnd Site\n{\nOFFSET 0 4 0\n}\n}\n}\n}\n}\n"
            "MOTION\nFrames: 0\nFrame Time: 0.5\n")
    data = bvh.parse_bvh(text)
    assert [j.parent for j in data.joints] == [-1, 0, 1, 2]
    assert [j.end_site is None for j in data.joints] == [True, True, True, False]
    np.testing.assert_array_equal(data.joints[3].end_site, [0, 4, 0])
    assert all(j.channels == [] for j in data.joints) and data.values.shape == (0, 0)
    no_offset = bvh.parse_bvh("HIERARCHY\nROOT a\n{\n}\nMOTION\nFrames: 0\nFrame Time: 0.5\n")
    assert no_offset.joints[0].offset.shape == (3,) and not no_offset.joints[0].offset.any()


@pytest.mark.survivor
def test_zero_frames_and_the_frame_time_limits_are_accepted():
    data = bvh.parse_bvh(bvh_text(rows=[]))
    assert data.values.shape == (0, 9)
    for frame_time in ("0.001", "1.0", "1e-3"):
        assert bvh.parse_bvh(bvh_text(frame_time=frame_time)).frame_time == float(frame_time)


@pytest.mark.survivor
def test_rows_past_the_frame_count_are_ignored():
    data = bvh.parse_bvh(bvh_text(frames=1) + "MOTION\n")
    np.testing.assert_array_equal(data.values, [[float(v) for v in ROWS[0].split()]])


def replaced(old, new, text=None):
    text = bvh_text() if text is None else text
    assert old in text
    return text.replace(old, new, 1)


BROKEN_FILES = [  # (text, the whole message)
    (bvh_text().replace("MOTION", "NOTION"), "dance.bvh: no MOTION section (truncated or not a BVH file)"),
    ("MOTION\nFrames: 1\nFrame Time: 0.04\n1\n", "dance.bvh: not a BVH file (no HIERARCHY header)"),
    ("HIERARCH\nROOT a\n{\n}\nMOTION\nFrames: 1\nFrame Time: 0.04\n1\n", "dance.bvh: not a BVH file (no HIERARCHY header)"),
    ("HIERARCHY\nROOT\nMOTION\nFrames: 1\nFrame Time: 0.04\n", "dance.bvh: hierarchy ends unexpectedly (truncated file?)"),
    ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nMOTION\nFrames: 1\nFrame Time: 0.04\n\n",
     "dance.bvh: hierarchy is truncated (unclosed braces)"),
    (replaced("OFFSET 0 1 0", "OFFSET 0 x 0"), "dance.bvh: line 8: expected numbers"),
    (replaced("OFFSET 0 1 0", "OFFSET 0 nan 0"), "dance.bvh: line 8: NaN or infinite offset"),
    (replaced("\tJOINT chest", "\tROOT chest"), "dance.bvh: line 6: more than one ROOT is not supported"),
    ("HIERARCHY\nJOINT a\n{\n}\nMOTION\nFrames: 1\nFrame Time: 0.04\n\n", "dance.bvh: line 2: JOINT outside a ROOT"),
    (replaced("\t}\n}\n", "\t}\n}\n}\n"), "dance.bvh: line 16: unbalanced braces"),
    ("HIERARCHY\nOFFSET 0 0 0\nMOTION\nFrames: 1\nFrame Time: 0.04\n\n", "dance.bvh: line 2: OFFSET outside a joint"),
    (replaced("CHANNELS 3 Z", "CHANNELS x Z"), "dance.bvh: line 9: bad channel count 'x'"),
    (replaced("CHANNELS 3 Z", "CHANNELS 7 Z"), "dance.bvh: line 9: CHANNELS 7 (a joint has 0 to 6)"),
    (replaced("CHANNELS 3 Zrotation", "CHANNELS 3 Wrotation"), "dance.bvh: line 9: bad CHANNELS declaration"),
    (replaced("\t\t\tOFFSET 0 0.5 0\n", "\t\t\tOFFSET 0 0.5 0\nCHANNELS 1 Xrotation\n"),
     "dance.bvh: line 13: bad CHANNELS declaration"),
    ("HIERARCHY\nCHANNELS 1 Xrotation\nMOTION\nFrames: 1\nFrame Time: 0.04\n\n", "dance.bvh: line 2: bad CHANNELS declaration"),
    (replaced("\tJOINT chest", "\tBONE chest"), "dance.bvh: line 6: unexpected 'BONE' in HIERARCHY"),
    ("HIERARCHY\nMOTION\nFrames: 1\nFrame Time: 0.04\n\n", "dance.bvh: hierarchy has no joints"),
    (bvh_text().split("Frame Time")[0], "dance.bvh: MOTION section is truncated"),
    (replaced("Frame Time: 0.04", "Frame Tim: 0.04"), "dance.bvh: MOTION section lacks 'Frames:' and 'Frame Time:' lines"),
    (replaced("Frame Time: 0.04", "Frame Time: 0.0.4"), "dance.bvh: bad Frame Time '0.0.4'"),
    (replaced("Frame Time: 0.04", "Frame Time: " + "1.2" * 20),
     "dance.bvh: bad Frame Time '" + ("1.2" * 20)[:40] + "'"),
    (replaced("Frame Time: 0.04", "Frame Time: 1.5"), "dance.bvh: Frame Time 1.5 is not between 0.001 and 1 s"),
    (replaced("Frame Time: 0.04", "Frame Time: 0.0009"), "dance.bvh: Frame Time 0.0009 is not between 0.001 and 1 s"),
    (bvh_text(frames=3), "dance.bvh: truncated, 2 of 3 frames present"),
    (bvh_text(rows=[ROWS[0], ROWS[1][:-4]]), "dance.bvh: line 20 has 8 values, expected 9"),
    ("\n" + bvh_text(rows=[ROWS[0], ROWS[1][:-4]]), "dance.bvh: line 21 has 8 values, expected 9"),
    (bvh_text(rows=[ROWS[0], ROWS[1].replace("-20", "twenty")]), "dance.bvh: line 20 has a non-numeric value"),
    (bvh_text(rows=[ROWS[0][:-3], ROWS[1][:-4]]), "dance.bvh: frames have 8 values, expected 9"),
    (bvh_text(rows=[ROWS[0], ROWS[1].replace("-20", "nan")]), "dance.bvh: line 20 contains NaN or infinite values"),
    (bvh_text(rows=[ROWS[0], "1 2 3 4 5 6 7 8 inf", "1 2 3 4 5 6 7 8 9"]), "dance.bvh: line 20 contains NaN or infinite values"),
]  # fmt: skip


@pytest.mark.survivor
def test_parse_errors_name_bvh_by_default():
    with pytest.raises(MotionFormatError, match="^BVH: no MOTION section"):
        bvh.parse_bvh("HIERARCHY\n")


@pytest.mark.survivor
@pytest.mark.parametrize("text, message", BROKEN_FILES)
def test_a_broken_bvh_is_refused_with_its_line(text, message):
    with pytest.raises(MotionFormatError) as error:
        bvh.parse_bvh(text, "dance.bvh")
    assert str(error.value) == message


@pytest.mark.survivor
def test_undecodable_bvh_names_the_file(tmp_path):
    path = tmp_path / "latin.bvh"
    path.write_bytes(bvh_text().replace("chest", "br\xfcst").encode("latin-1"))
    with pytest.raises(MotionFormatError) as error:
        bvh.read_bvh_raw(path)
    assert str(error.value) == f"{path} is not a BVH text file"


# -- local rotations from any channel layout --------------------------------------------------------
@pytest.mark.survivor
def test_local_rotations_follow_each_joints_own_channels():
    angles = [[10, 20, 30, 40], [-15, 25, -35, 45]]
    text = ("HIERARCHY\nROOT a\n{\nOFFSET 1 2 3\nCHANNELS 3 Yrotation Zrotation Xrotation\n"
            "JOINT b\n{\nOFFSET 0 1 0\nCHANNELS 4 Xrotation Yrotation Zrotation Xrotation\n"
            "JOINT c\n{\nOFFSET 0 1 0\nCHANNELS 1 Yrotation\n}\n}\n}\nMOTION\nFrames: 2\nFrame Time: 0.04\n"
            + "".join(f"{a} {b} {c} {a} {b} {c} {d} {d}\n" for a, b, c, d in angles))
    data = bvh.parse_bvh(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rotmats, root = bvh._local_rotations(data)
    np.testing.assert_array_equal(root, [[1, 2, 3], [1, 2, 3]])
    for t, (a, b, c, d) in enumerate(angles):
        np.testing.assert_allclose(rotmats[t, 0], Rotation.from_euler("YZX", [a, b, c], degrees=True).as_matrix(), atol=1e-12)
        expected = (Rotation.from_euler("XYZ", [a, b, c], degrees=True) * Rotation.from_euler("X", d, degrees=True)).as_matrix()
        np.testing.assert_allclose(rotmats[t, 1], expected, atol=1e-12)
        np.testing.assert_allclose(rotmats[t, 2], Rotation.from_euler("Y", d, degrees=True).as_matrix(), atol=1e-12)


@pytest.mark.survivor
def test_root_positions_add_the_root_offset_and_other_joints_positions_are_ignored():
    text = bvh_text(chest_channels="CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                    rows=[r + " 7 8 9" for r in ROWS])
    data = bvh.parse_bvh(text)
    # chest's row: 40 50 60 / 7 8 9 are its positions then rotations
    with pytest.warns(UserWarning) as caught:
        rotmats, root = bvh._local_rotations(data)
    assert [str(w.message) for w in caught] == ["BVH position channels on non-root joints are ignored (bone offsets are used)"]
    np.testing.assert_allclose(root, [[1.5, 2, 3], [4.5, 5, 6]])
    np.testing.assert_allclose(rotmats[1, 1], Rotation.from_euler("ZXY", [7, 8, 9], degrees=True).as_matrix(), atol=1e-12)


@pytest.mark.survivor
def test_unit_guess_by_the_figures_extent():
    guess = bvh.detect_scale
    assert guess(np.array([[-6.0, 0, 0], [0, 6.0, 0]])) == 1.0  # extent per axis, not across axes
    assert guess(np.array([[0.0, 0, 0], [11.0, 11.0, 11.0]])) == 0.01
    assert guess(np.array([[0.0, 0, 0], [0, 20.0, 0]])) == 0.01
    assert guess(np.array([[0.0, 0, 0], [0, 10.0, 0]])) == 1.0
    assert guess(np.array([[0.0, 0, 0], [0, 10.5, 0]])) == 0.01
    assert guess(np.array([[0.0, 0, 0], [0, 300.0, 0]])) == 0.01
    assert guess(np.array([[0.0, 0, 0], [0, 300.5, 0]])) == 0.001
    assert guess(np.array([[0.0, 0, 0], [0, 1000.0, 0]])) == 0.001
    assert guess(np.array([[5.0, 5.0, 5.0]])) == 1.0


@pytest.mark.survivor
@pytest.mark.parametrize("name, key", [
    ("f_avg_L_Hip", "lhip"), ("m_avg_Pelvis", "pelvis"), ("SMPL_Spine1", "spine1"), ("mixamorig:LeftArm", "larm"),
    ("Left Knee", "lknee"), ("left_wrist", "lwrist"), ("RightHand", "rhand"), ("right ankle", "rankle"), ("r_collar", "rcollar"),
])
def test_joint_names_normalise_to_smpl_keys(name, key):
    assert bvh._normalise_joint_name(name) == key


# -- SMPL-24 BVH files ------------------------------------------------------------------------------
def smpl_text(motion, units="m") -> str:
    buffer = io.BytesIO()
    bvh.write_bvh(motion, buffer, units=units)
    return buffer.getvalue().decode()


@pytest.mark.survivor
def test_smpl_file_reads_in_the_units_asked(dance, tmp_path):
    cm = save(tmp_path, smpl_text(dance, "cm"), "cm.bvh")
    metres = save(tmp_path, smpl_text(dance), "m.bvh")
    expected = dance.joint_positions()
    for path, units, factor in ((cm, "auto", 1.0), (cm, "cm", 1.0), (cm, "m", 100.0), (metres, "m", 1.0),
                                (metres, "cm", 0.01)):
        back = bvh.read_bvh(path, units=units)
        np.testing.assert_allclose(back.joint_positions(), expected * factor, atol=1e-4 * max(factor, 1.0))
        np.testing.assert_allclose(back.skeleton.offsets, dance.skeleton.offsets * factor, atol=1e-5 * max(factor, 1.0))
        assert back.metadata == {"source": path.name} and back.fps == 30.0
    data = bvh.read_bvh_raw(cm)
    assert bvh.bvh_to_motion(data).metadata == {"source": "BVH"}  # the default name; units guessed
    np.testing.assert_allclose(bvh.bvh_to_motion(data).joint_positions(), expected, atol=1e-4)


@pytest.mark.survivor
def test_smpl_file_frame_rates_and_frame_counts(dance, tmp_path):
    text = smpl_text(dance[:1])
    head, rest = text.split("Frame Time:", 1)
    row = rest.split("\n", 1)[1]
    for frame_time, fps in (("0.03333333", 30.0), ("0.03", 100.0 / 3.0)):
        back = bvh.read_bvh(save(tmp_path, f"{head}Frame Time: {frame_time}\n{row}"))
        assert back.num_frames == 1 and back.fps == pytest.approx(fps, abs=1e-9)
        assert (back.fps == round(back.fps)) == (fps == round(fps))
    path = save(tmp_path, f"{head.replace('Frames: 1', 'Frames: 0')}Frame Time: 0.04\n", "empty.bvh")
    with pytest.raises(MotionFormatError) as error:
        bvh.read_bvh(path)
    assert str(error.value) == f"{path}: no frames"


def chain_text(names):
    """A chain of joints, one frame, no channels past the root's rotations."""
    body = "".join(f"{'ROOT' if k == 0 else 'JOINT'} {n}\n{{\nOFFSET 0 0.1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
                   for k, n in enumerate(names))
    return ("HIERARCHY\n" + body + "}\n" * len(names) + "MOTION\nFrames: 1\nFrame Time: 0.04\n"
            + " ".join(["0"] * 3 * len(names)) + "\n")


@pytest.mark.survivor
@pytest.mark.parametrize("names, listed", [
    (list("abcdef"), "a, b, c, d, e, f"), (list("abcdefg"), "a, b, c, d, e, f, ..."), (["pelvis"], "pelvis"),
])
def test_other_skeletons_are_named_in_the_refusal(names, listed):
    with pytest.raises(MotionFormatError) as error:
        bvh.bvh_to_motion(bvh.parse_bvh(chain_text(names)), "dance.bvh")
    assert str(error.value) == f"dance.bvh: skeleton is not SMPL-24 (found {len(names)} joints: {listed})"


@pytest.mark.survivor
def test_smpl_file_with_a_foreign_joint_or_a_wrong_parent_is_refused(dance, tmp_path):
    text = smpl_text(dance)
    renamed = bvh.parse_bvh(text.replace("JOINT r_wrist", "JOINT r_paw"), "x.bvh")  # SMPL-24's tree in choreo's order:
    read = bvh.bvh_to_motion(renamed, "x.bvh")  # read by its place in the tree
    np.testing.assert_allclose(read.joint_positions(), dance.joint_positions(), atol=1e-5)
    moved = bvh.parse_bvh(text.replace("JOINT r_wrist", "JOINT r_paw").replace("JOINT l_hip", "JOINT l_leg"), "x.bvh")
    moved.joints[1], moved.joints[2] = moved.joints[2], moved.joints[1]  # no longer in choreo's order, nor all named
    with pytest.raises(MotionFormatError) as error:
        bvh.bvh_to_motion(moved, "x.bvh")
    assert str(error.value).startswith("x.bvh: skeleton is not SMPL-24 (found 24 joints: ")
    swapped = text.replace("JOINT l_knee", "JOINT TMP").replace("JOINT r_knee", "JOINT l_knee").replace("JOINT TMP", "JOINT r_knee")
    with pytest.raises(MotionFormatError) as error:
        bvh.bvh_to_motion(bvh.parse_bvh(swapped), "x.bvh")
    assert str(error.value) == "x.bvh: joint r_knee has the wrong parent for SMPL-24"


@pytest.mark.survivor
def test_written_hierarchy_is_indented_by_depth_with_end_sites_at_the_leaves(tmp_path):
    offsets = SMPL24.offsets.copy()
    offsets[J["l_knee"]] = [-4e-7, -0.4, 3e-7]  # rounds to zero: written as 0.000000, never -0.000000
    motion = Motion.rest(2, skeleton=SMPL24.with_offsets(offsets))
    text = smpl_text(motion)
    assert "-0.000000" not in text.split("MOTION")[0]
    assert "\t\tOFFSET 0.000000 -0.400000 0.000000\n" in text
    depth = {}
    for j, p in enumerate(SMPL24.parents):
        depth[j] = 0 if p < 0 else depth[p] + 1
    lines = text.split("\n")
    for j, name in enumerate(SMPL24.names):
        keyword = "ROOT" if j == 0 else "JOINT"
        assert "\t" * depth[j] + f"{keyword} {name}" in lines, name
    sites = [lines[k - 1].strip() for k, line in enumerate(lines) if line.strip() == "End Site"]
    assert len(sites) == 5
    tips = {}
    for k, line in enumerate(lines):
        if line.strip() == "End Site":
            owner = next(lines[m].split()[1] for m in range(k, 0, -1) if lines[m].strip().startswith(("JOINT", "ROOT"))
                         and lines[m].count("\t") == line.count("\t") - 1)
            tips[owner] = lines[k + 2].split()[1:]
    assert tips == {"head": ["0.000000", "0.100000", "0.000000"], "l_hand": ["0.080000", "0.000000", "0.000000"],
                    "r_hand": ["-0.080000", "0.000000", "0.000000"], "l_foot": ["0.000000", "0.000000", "0.060000"],
                    "r_foot": ["0.000000", "0.000000", "0.060000"]}
    rows = text.split("Frame Time: 0.03333333\n")[1].strip().split("\n")
    assert len(rows) == 2
    for row in rows:
        values = row.split(" ")
        assert len(values) == 3 + 72 and all(len(v.split(".")[1]) == 6 and "e" not in v for v in values)


@pytest.mark.survivor
def test_bvh_writer_refusals():
    with pytest.raises(MotionFormatError) as error:
        bvh.write_bvh(Motion.rest(1), io.BytesIO(), units="mm")
    assert str(error.value) == "unknown BVH units 'mm' (use m or cm)"
    parents = list(SMPL24.parents)
    parents[J["l_hand"]] = J["l_elbow"]
    other = SMPL24.__class__(SMPL24.names, tuple(parents), SMPL24.offsets)
    with pytest.raises(MotionFormatError) as error:
        bvh.write_bvh(Motion.rest(1, skeleton=other), io.BytesIO())
    assert str(error.value) == "BVH export supports the SMPL-24 skeleton only"


@pytest.mark.survivor
def test_a_bvh_without_channels_is_named_as_such():
    text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION\nFrames: 1\nFrame Time: 0.5\n\n"
    with pytest.raises(MotionFormatError, match=r"^x.bvh: no joint has CHANNELS, so its 1 frames hold no motion$"):
        bvh.parse_bvh(text, "x.bvh")


# -- BVH ---------------------------------------------------------------------------------------
@pytest.mark.survivor
def test_bvh_leaves_not_named_as_in_smpl_get_the_default_end_site():
    """bvh._write_hierarchy mutants 4, 6-9: an SMPL-24 tree with other joint names is written
    (only the parents are checked); its five leaves get the default End Site (0, 0.05, 0)."""
    skeleton = Skeleton(tuple(f"bone{j}" for j in range(24)), SMPL24.parents, SMPL24.offsets)
    buffer = io.BytesIO()
    write_bvh(still(2, skeleton=skeleton), buffer)
    lines = buffer.getvalue().decode().split("\n")
    sites = [lines[k + 2].strip() for k, line in enumerate(lines) if line.strip() == "End Site"]
    assert sites == ["OFFSET 0.000000 0.050000 0.000000"] * 5
    buffer = io.BytesIO()
    write_bvh(still(2, skeleton=skeleton), buffer, units="cm")
    assert buffer.getvalue().decode().count("OFFSET 0.000000 5.000000 0.000000") == 5


@pytest.mark.survivor
def test_end_site_at_the_end_of_the_hierarchy_is_unclosed_braces_not_a_short_file():
    """bvh._parse_hierarchy mutant 79 (two tokens taken after "End"): "End Site" with nothing after
    it is an unclosed End Site; the word "Site" alone is taken."""
    text = ("HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\nEnd Site\n"
            "MOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n")
    with pytest.raises(MotionFormatError) as raised:
        parse_bvh(text, "cut.bvh")
    assert str(raised.value) == "cut.bvh: hierarchy is truncated (unclosed braces)"


@pytest.mark.survivor
def test_end_site_without_braces_still_takes_its_offset():
    """bvh._parse_hierarchy mutant 79: the token after "End Site" is not swallowed."""
    text = ("HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n"
            "End Site OFFSET 1 2 3 }\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n")
    data = parse_bvh(text, "loose.bvh")
    np.testing.assert_array_equal(data.joints[0].end_site, [1.0, 2.0, 3.0])


@pytest.mark.survivor
def test_detect_scale_of_no_joints_is_metres():
    """bvh.detect_scale mutant 3: no joints, no extent (not numpy's empty-reduction error)."""
    assert detect_scale(np.zeros((0, 3))) == 1.0
    assert detect_scale(np.array([[5.0, 500.0, 7.0]])) == 1.0  # one joint: no extent either


# -- BVH ------------------------------------------------------------------------------------------
def long_bvh_text(frames: int) -> str:
    handle = io.BytesIO()
    write_bvh(hostile_dance(frames), handle)
    return handle.getvalue().decode()


@pytest.mark.hardening
def test_reading_a_bvh_takes_memory_near_the_motions_size(tmp_path):
    """Per frame, reading 4x the frames may cost about 4x the memory (linear), and a few times
    the text plus the motion's values, not a Python object per number."""
    small, large = long_bvh_text(500), long_bvh_text(2000)
    (tmp_path / "large.bvh").write_text(large)
    parse_small, parse_large = peak_bytes(parse_bvh, small), peak_bytes(parse_bvh, large)
    assert parse_large < 5 * parse_small
    assert parse_large < 3 * len(large) + 3 * 2000 * 75 * 8
    longer = long_bvh_text(16000)  # long enough that the rotations' per-block work is amortised
    (tmp_path / "longer.bvh").write_text(longer)
    quaternion_bytes = 16000 * 24 * 4 * 8
    assert peak_bytes(read_motion, tmp_path / "longer.bvh") < 4 * len(longer) + 4 * quaternion_bytes + (48 << 20)


@pytest.mark.hardening
def test_a_bvh_is_written_a_chunk_of_frames_at_a_time(tmp_path, monkeypatch):
    """Issue 48, item 14 for every writer: the BVH writer held a long dance's rotation matrices and
    its whole text at once. Written a chunk at a time, it holds about what the NPZ writer holds, and
    its curves stay continuous across the chunks' seams."""
    import choreo.formats.bvh as bvh
    from choreo.formats.npz import write_npz

    motion = hostile_dance(6000)
    with open(tmp_path / "whole.bvh", "wb") as out:
        write_bvh(motion, out)
    monkeypatch.setattr(bvh, "frame_chunks", lambda frames: [slice(0, frames)])  # as it was: all at once
    with open(tmp_path / "once.bvh", "wb") as out:
        at_once = peak_bytes(write_bvh, motion, out)
    monkeypatch.setattr(bvh, "frame_chunks", lambda frames: (slice(s, s + 256) for s in range(0, frames, 256)))
    with open(tmp_path / "dance.bvh", "wb") as out, open(tmp_path / "dance.npz", "wb") as npz:
        streamed = peak_bytes(write_bvh, motion, out)
        stored = peak_bytes(write_npz, motion, npz)
    assert (tmp_path / "dance.bvh").read_bytes() == (tmp_path / "whole.bvh").read_bytes()
    assert streamed < stored and streamed < at_once / 3  # measured: 5.5, 21 and 24 MB


# -- root motion: a root bone above the pelvis ---------------------------------------------------
def test_a_root_motion_file_moves_the_pelvis_under_a_floor_level_root_bone(tmp_path):
    dancer = wandering_dance(4, 90)
    path = tmp_path / "root.bvh"
    write_motion(dancer, path, root_motion=True)
    data = read_bvh_raw(path)
    names = [joint.name for joint in data.joints]
    assert names[:2] == ["root", "pelvis"] and len(names) == 25 and data.joints[1].parent == 0
    assert len(data.joints[0].channels) == len(data.joints[1].channels) == 6
    assert all(len(joint.channels) == 3 for joint in data.joints[2:])
    positions, _ = file_forward_kinematics(data)  # a literal reading of the file, position channels and all
    ours = dancer.joint_positions()
    for j, name in enumerate(SMPL24.names):
        assert np.abs(positions[names.index(name)] - ours[:, j]).max() < 1e-4, name
    floor = np.median(ours[..., 1].min(axis=1))
    assert np.abs(positions[0][:, 1] - floor).max() < 1e-5
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the pelvis's position channels are read, not ignored
        back = read_motion(path)
    assert back.skeleton.same_topology(SMPL24) and back.num_frames == 90
    assert np.abs(back.joint_positions() - ours).max() < 1e-4
    np.testing.assert_allclose(back.skeleton.offsets[1:], dancer.skeleton.offsets[1:], atol=1e-6)


def test_joints_choreo_cannot_place_are_refused_unless_they_stand_above_the_pelvis(dance):
    text = smpl_text(dance)  # a joint without channels below the left foot: not a root bone
    extra = text.replace("\tEnd Site", "\tJOINT hat\n\t{\n\tOFFSET 0 0.1 0\n\t}\n\tEnd Site", 1)
    with pytest.raises(MotionFormatError) as error:
        bvh.bvh_to_motion(bvh.parse_bvh(extra), "x.bvh")
    assert str(error.value).startswith("x.bvh: skeleton is not SMPL-24 (found 25 joints: ")
    above = "HIERARCHY\nROOT stage\n{\nOFFSET 0 0 0\n" + text.replace("HIERARCHY\nROOT", "JOINT", 1).replace("MOTION", "}\nMOTION", 1)
    np.testing.assert_allclose(bvh.bvh_to_motion(bvh.parse_bvh(above)).joint_positions(), dance.joint_positions(), atol=1e-5)


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("old, new, message", [
    ("CHANNELS 3", "CHANNELS " + "9" * 5000, "bad channel count '" + "9" * 40 + "'"),
    ("JOINT l_hip", "JOINT l_hip " + "x" * 5000, "unexpected '" + "x" * 40 + "' in HIERARCHY"),
])
def test_a_huge_token_in_the_hierarchy_is_cut_in_the_refusal(dance, old, new, message):
    """Fuzzing (tests/fuzz/test_inputs.py after the root-motion seeds): a channel count of 5,000
    nines made a refusal of 5,000 characters (counted as an internal error: one line, but not short)."""
    with pytest.raises(MotionFormatError) as raised:
        bvh.parse_bvh(smpl_text(dance).replace(old, new, 1), "x.bvh")
    assert str(raised.value).endswith(message) and len(str(raised.value)) < 120


def with_positions_on_l_hip(text: str) -> str:
    """``text`` (choreo's SMPL-24 BVH) with position channels on l_hip, the first joint below the
    pelvis: its three values come after the pelvis's six in every frame row."""
    head, motion = text.split("MOTION\n")
    head = head.replace("CHANNELS 3", "CHANNELS 6 Xposition Yposition Zposition", 1)
    lines = motion.splitlines()
    rows = [" ".join(line.split()[:6] + ["0.1", "0.2", "0.3"] + line.split()[6:]) for line in lines[2:]]
    return head + "MOTION\n" + "\n".join(lines[:2] + rows) + "\n"


@pytest.mark.hardening
def test_position_channels_below_the_root_are_one_note_in_choreos_words(tmp_path, dance, capsys):
    """Round five, item 10: position channels on a joint other than the root printed Python's raw
    UserWarning, its source file, line number and the source line; now one ``note:`` line."""
    from tests.helpers import run_cli

    path = tmp_path / "pos.bvh"
    path.write_text(with_positions_on_l_hip(smpl_text(dance)))
    code, _, err = run_cli(capsys, "convert", path, tmp_path / "out.npz")
    assert code == 0, err
    lines = err.splitlines()
    assert lines[0] == "note: BVH position channels on non-root joints are ignored (bone offsets are used)"
    assert len(lines) == 2 and lines[1].startswith("wrote ") and "Warning" not in err and "bvh.py" not in err
    with pytest.warns(UserWarning):  # from Python, still a warning
        read_motion(path)


def stacked_above(text: str, joints: int, channels: bool = False) -> str:
    """``text`` (choreo's SMPL-24 BVH) under ``joints`` joints stacked above its pelvis, each at no
    offset and turned by nothing (``channels``: three rotation channels of zeros)."""
    head, motion = text.split("MOTION\n")
    declared = "CHANNELS 3 Zrotation Xrotation Yrotation\n" if channels else ""
    opening = "".join(f"{'ROOT' if k == 0 else 'JOINT'} s{k}\n{{\nOFFSET 0 0 0\n{declared}" for k in range(joints))
    lines = motion.splitlines()
    zeros = "0 " * (3 * joints) if channels else ""
    return ("HIERARCHY\n" + opening + "JOINT" + head[len("HIERARCHY\nROOT"):] + "}\n" * joints + "MOTION\n"
            + "\n".join(lines[:2] + [zeros + line for line in lines[2:]]) + "\n")


@pytest.mark.hardening
def test_thousands_of_joints_stacked_above_the_pelvis_are_refused_at_once(tmp_path, capsys):
    """Round five, item 7: joints above the pelvis are composed into it at every frame, each with
    its own (T, 3, 3) rotations: 5,000 of them without channels in a 476 kB file peaked at 780 MB,
    100,000 (4.7 MB) at 14.5 GB after 52 s. More than MAX_JOINTS_ABOVE (32) are refused, exit 2,
    before anything per frame, as unnamed joints below the pelvis are; 32 still read."""
    import time

    from tests.conftest import wandering_dance
    from tests.helpers import assert_one_line_error, run_cli

    dancer = wandering_dance(3, 300, 30.0)
    text = smpl_text(dancer)
    path = tmp_path / "stacked.bvh"
    for joints, channels in ((5000, False), (2000, True)):
        path.write_text(stacked_above(text, joints, channels))
        started = time.perf_counter()
        code, _, err = run_cli(capsys, "convert", path, tmp_path / "out.npz")
        assert_one_line_error(code, err)
        assert f"{joints} joints above pelvis (choreo composes at most 32" in err and not (tmp_path / "out.npz").exists()
        assert time.perf_counter() - started < 10
    path.write_text(stacked_above(text, bvh.MAX_JOINTS_ABOVE, channels=True))
    np.testing.assert_allclose(read_motion(path).joint_positions(), dancer.joint_positions(), atol=1e-5)
    rig = io.BytesIO()
    write_bvh_rig(dancer, rig, "mixamo")  # the Mixamo reader checks the same
    path.write_text(stacked_above(rig.getvalue().decode(), 100))
    with pytest.raises(MotionFormatError, match="100 joints above mixamorig:Hips"):
        read_bvh_rig(path)
