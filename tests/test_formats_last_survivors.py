"""The last format mutants a whole mutation run (3,464 killed, 150 survived) left alive, pinned.

Each test names the mutants it kills. Expected values are literals or independent computations
(hand-written BVH text, a literal forward-kinematics walk with scipy's rotations, hand-packed
GLB edits); docs/mutation.md says why the other survivors cannot be told from the original.
"""

import io
import json
import pickle

import numpy as np
import pytest

from choreo.errors import MotionFormatError, ParameterError
from choreo.formats import bvh, registry, rigs, safe_pickle
from choreo.formats.bvh import detect_scale, parse_bvh, write_bvh
from choreo.formats.gltf import read_glb, write_glb
from choreo.formats.json_format import read_json, write_json
from choreo.formats.npz import write_npz
from choreo.formats.rigs import MIXAMO, read_bvh_rig, shortest_arc, write_bvh_rig
from choreo.formats.safe_pickle import UnsafePickle, load_numpy_pickle
from choreo.motion import Motion
from choreo.skeleton import SMPL24, Skeleton
from tests.test_format_survivors import file_forward_kinematics
from tests.test_gltf_fbx_survivors import join_glb, split_glb


def small_dance(frames: int = 4, seed: int = 5, fps: float = 30.0) -> Motion:
    rng = np.random.default_rng(seed)
    axis_angle = rng.normal(scale=0.4, size=(frames, 24, 3))
    root = rng.normal(scale=0.1, size=(frames, 3)) + [0.0, 0.95, 0.0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps, skeleton=SMPL24)


def still(frames: int, fps=30.0, skeleton=SMPL24) -> Motion:
    rotations = np.zeros((frames, 24, 4))
    rotations[..., 0] = 1.0
    return Motion(np.tile([0.0, 0.9, 0.0], (frames, 1)), rotations, fps=fps, skeleton=skeleton)


# -- BVH ---------------------------------------------------------------------------------------
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


def test_end_site_at_the_end_of_the_hierarchy_is_unclosed_braces_not_a_short_file():
    """bvh._parse_hierarchy mutant 79 (two tokens taken after "End"): "End Site" with nothing after
    it is an unclosed End Site; the word "Site" alone is taken."""
    text = ("HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\nEnd Site\n"
            "MOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n")
    with pytest.raises(MotionFormatError) as raised:
        parse_bvh(text, "cut.bvh")
    assert str(raised.value) == "cut.bvh: hierarchy is truncated (unclosed braces)"


def test_end_site_without_braces_still_takes_its_offset():
    """bvh._parse_hierarchy mutant 79: the token after "End Site" is not swallowed."""
    text = ("HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n"
            "End Site OFFSET 1 2 3 }\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n")
    data = parse_bvh(text, "loose.bvh")
    np.testing.assert_array_equal(data.joints[0].end_site, [1.0, 2.0, 3.0])


def test_detect_scale_of_no_joints_is_metres():
    """bvh.detect_scale mutant 3: no joints, no extent (not numpy's empty-reduction error)."""
    assert detect_scale(np.zeros((0, 3))) == 1.0
    assert detect_scale(np.array([[5.0, 500.0, 7.0]])) == 1.0  # one joint: no extent either


# -- registry ----------------------------------------------------------------------------------
def test_rig_writer_for_fbx_is_given_the_rig(monkeypatch):
    """registry._writer mutant 18: the FBX writer receives the rig (its own default is SMPL-24)."""
    calls = []

    def fake_fbx(motion, handle, rig=None):
        calls.append(rig)
        handle.write(b"fbx")
    monkeypatch.setitem(registry.RIG_WRITERS, "fbx", fake_fbx)
    handle = io.BytesIO()
    registry._writer(registry.FORMATS["fbx"], "mixamo")(still(1), handle)
    assert calls == [MIXAMO] and handle.getvalue() == b"fbx"


def test_write_motions_refuses_the_rig_before_touching_any_path(tmp_path):
    """registry.write_motions mutants 3 and 6: the rig is checked for every path up front, so a
    rig the format cannot carry is the error even where the output folder is missing."""
    missing = tmp_path / "no-such-folder" / "dance.npz"
    with pytest.raises(ParameterError) as raised:
        registry.write_motions(still(1), [str(missing)], rig="mixamo")
    assert str(raised.value) == "--rig mixamo applies to .bvh and .fbx outputs, not .npz"


# -- npz ---------------------------------------------------------------------------------------
def test_npz_stores_an_integer_frame_rate_as_float64():
    """npz.write_npz mutants 7 and 9: a Motion keeps fps=30 as given (an int); the file's fps is float64."""
    buffer = io.BytesIO()
    write_npz(still(2, fps=30), buffer)
    buffer.seek(0)
    with np.load(buffer, allow_pickle=False) as archive:
        fps = archive["fps"]
    assert fps.dtype == np.float64 and fps.shape == () and float(fps) == 30.0


# -- rigs --------------------------------------------------------------------------------------
def test_hip_height_counts_tips_below_the_joints():
    """rigs._hip_height mutants 9 and 11: height of the root above the lowest joint or End Site tip."""
    parents = (-1, 0)
    offsets = np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    assert rigs._hip_height(parents, offsets, {1: np.array([0.0, -0.25, 0.0])}) == 1.25
    assert rigs._hip_height(parents, offsets, {0: np.array([0.0, 0.5, 0.0])}) == 1.0  # a tip above: the joint


def test_shortest_arc_turns_by_a_tiny_angle_exactly():
    """rigs.shortest_arc mutant 19: a cross product of norm exactly 1e-12 is a rotation, not the identity."""
    a, b = np.array([1.0, 0.0, 0.0]), np.array([1.0, 1e-12, 0.0])
    turn = shortest_arc(a, b)
    np.testing.assert_array_equal(turn @ a, b)
    assert turn[1, 0] == 1e-12 and turn[0, 1] == -1e-12


def half_turn(axis) -> np.ndarray:
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return 2.0 * np.outer(k, k) - np.eye(3)


@pytest.mark.parametrize("a, axis", [
    ((0.96, 0.0, 0.28), (-0.28, 0.0, 0.96)),            # |x| >= 0.9: about a x (0, 1, 0)
    ((0.9, 0.3, np.sqrt(0.1)), (-np.sqrt(0.1), 0.0, 0.9)),  # |x| exactly 0.9: still the y helper
    ((0.0, 0.6, 0.8), (0.0, 0.8, -0.6)),                # otherwise about a x (1, 0, 0)
])
def test_shortest_arc_half_turn_axis_follows_the_helper_rule(a, axis):
    """rigs.shortest_arc mutants 34, 37, 39: opposite directions turn half a turn about a x helper,
    the helper being the x axis unless a's x is 0.9 or more in size, then the y axis."""
    a = np.array(a)
    assert np.linalg.norm(a) == 1.0
    turn = shortest_arc(a, -a)
    np.testing.assert_allclose(turn, half_turn(axis), atol=1e-15)
    np.testing.assert_allclose(turn @ a, -a, atol=1e-15)


def rig_text(motion: Motion) -> str:
    buffer = io.BytesIO()
    write_bvh_rig(motion, buffer, "mixamo")
    return buffer.getvalue().decode()


def test_rig_bone_names_match_ignoring_ascii_case_only(tmp_path):
    """rigs._match_bones mutant 2 (names upper-cased instead of lower-cased): a dotless i is not an i."""
    path = tmp_path / "dotless.bvh"
    text = rig_text(small_dance()).replace("mixamorig:Hips", "mixamorig:H\u0131ps")
    path.write_text(text, encoding="utf-8")
    with pytest.raises(MotionFormatError) as raised:
        read_bvh_rig(path, "mixamo")
    assert str(raised.value) == f"{path}: not a mixamo skeleton (no joint named mixamorig:Hips)"


def test_rig_file_composes_two_joints_above_the_hips(tmp_path):
    """rigs._hips_in_world mutants 12 and 15: with two unnamed joints above the hips (a turned root
    and a turned, offset child), both transforms are composed in, the file's root first."""
    dance = small_dance(frames=3)
    head, motion_part = rig_text(dance).split("MOTION", 1)
    head = head.replace("HIERARCHY\nROOT mixamorig:Hips\n{\n\tOFFSET 0.000000 0.000000 0.000000\n"
                        "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n",
                        "HIERARCHY\nROOT Armature\n{\nOFFSET 0.5 0 -0.25\n"
                        "CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n"
                        "JOINT Rig\n{\nOFFSET 0.2 -0.1 0.4\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
                        "JOINT mixamorig:Hips\n{\n\tOFFSET 0.1 0.2 0.3\n"
                        "\tCHANNELS 3 Zrotation Xrotation Yrotation\n", 1) + "}\n}\n"
    lines = motion_part.split("\n")
    rows = [k for k, line in enumerate(lines) if line and line[0] in "-0123456789"]
    assert len(rows) == 3
    for n, k in enumerate(rows):
        values = lines[k].split()
        armature, rig = ["90", f"{10 * n}", "0"], [f"{25 + 5 * n}", "-30", "15"]
        lines[k] = " ".join(values[:3] + armature + rig + values[3:])
    path = tmp_path / "nested.bvh"
    path.write_text(head + "MOTION" + "\n".join(lines))
    data = bvh.read_bvh_raw(path)
    assert [j.name for j in data.joints[:3]] == ["Armature", "Rig", "mixamorig:Hips"]
    positions, _ = file_forward_kinematics(data)
    back = read_bvh_rig(path, "mixamo", units="m").joint_positions()
    names = [joint.name for joint in data.joints]
    for b, bone in enumerate(MIXAMO.bones):
        np.testing.assert_allclose(back[:, MIXAMO.smpl_joints[b]], positions[names.index(bone)], atol=1e-6)


# -- glTF --------------------------------------------------------------------------------------
def test_glb_keys_a_thousand_seconds_apart_are_a_rate_of_a_thousandth(tmp_path):
    """gltf._motion_of mutant 129: 1 / 1000 s is exactly 1e-3 away from its rounding, 0, and is
    not rounded to it (the bound is strict), so the message gives the keys' own rate."""
    buffer = io.BytesIO()
    write_glb(still(2), buffer)
    document, blob = split_glb(buffer.getvalue())
    del document["extras"]["fps"]
    times = document["accessors"][document["animations"][0]["samplers"][0]["input"]]
    view = document["bufferViews"][times["bufferView"]]
    start = view.get("byteOffset", 0) + times.get("byteOffset", 0)
    blob = bytearray(blob)
    blob[start:start + 8] = np.array([0.0, 1000.0], dtype="<f4").tobytes()
    times["max"] = [1000.0]
    path = tmp_path / "slow.glb"
    path.write_bytes(join_glb(document, bytes(blob)))
    with pytest.raises(MotionFormatError) as raised:
        read_glb(path)
    assert str(raised.value) == f"{path}: fps must be between 1 and 1000, got 0.001"


# -- safe pickle -------------------------------------------------------------------------------
def test_unpickler_running_out_of_stack_is_an_unsafe_pickle(tmp_path, monkeypatch):
    """safe_pickle.load_numpy_pickle mutants 17-19: a RecursionError while unpickling is reported
    as one line. No file found reaches it (Python's unpickler builds nesting without recursion),
    so the stand-in lookup is made to raise it."""
    path = tmp_path / "a.pkl"
    path.write_bytes(pickle.dumps({"smpl_poses": np.zeros((1, 72))}, protocol=4))
    assert load_numpy_pickle(path)["smpl_poses"].shape == (1, 72)  # a good file

    def too_deep(self, module, name):
        raise RecursionError("maximum recursion depth exceeded")
    monkeypatch.setattr(safe_pickle._StandInUnpickler, "find_class", too_deep)
    with pytest.raises(UnsafePickle) as raised:
        load_numpy_pickle(path)
    assert str(raised.value) == "pickle nests too deeply"


# -- JSON (bugs the reading of these survivors found) ------------------------------------------
def motion_document(**changes) -> dict:
    buffer = io.BytesIO()
    write_json(still(2), buffer)
    document = json.loads(buffer.getvalue())
    document.update(changes)
    return document


@pytest.mark.parametrize("changes, message", [
    ({"fps": 10 ** 400}, "malformed motion JSON (OverflowError)"),  # was an internal error
    ({"root_positions": [[10 ** 400, 0, 0]] * 2}, "motion contains NaN or infinite values"),  # numpy reads it as inf
    ({"fps": 0.5}, "fps must be between 1 and 1000, got 0.5"),  # was Motion's message without the file
])
def test_json_values_a_motion_cannot_hold_name_the_file(tmp_path, changes, message):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(motion_document(**changes)))
    with pytest.raises(MotionFormatError) as raised:
        read_json(path)
    assert str(raised.value) == f"{path}: {message}"
