"""Format readers and writers pinned where mutation testing found them unguarded.

Every expected value here comes from an independent source: a hand-written file with a known
answer, a literal loop, numpy/scipy, or Mixamo's published bone names. The rig table is built by
calling ``rigs._mixamo()`` itself (the module-level MIXAMO is built once at import).
"""

import io
import json
import pickle
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import wandering_dance
from scipy.spatial.transform import Rotation

from choreo.errors import InputError, MotionFormatError, OutputError, ParameterError
from choreo.formats import aistpp, bvh, json_format, npy, npz, registry, rigs, safe_arrays, safe_pickle, smpl_params
from choreo.formats.fbx import NO_BLENDER
from choreo.formats.rigs import MIXAMO, Rig, get_rig, read_bvh_rig, write_bvh_rig
from choreo.formats.safe_pickle import UnsafePickle
from choreo.motion import Motion
from choreo.skeleton import SMPL24

J = {name: j for j, name in enumerate(SMPL24.names)}


@pytest.fixture(scope="module")
def dance():
    return wandering_dance(3, 6, 30.0)


# -- the Mixamo rig table ----------------------------------------------------------------------
# Mixamo's standard humanoid (https://www.mixamo.com, "mixamorig:" prefix), fingers left out:
# bone -> (parent, the SMPL-24 joint at the bone's head, the SMPL joint its rest direction aims at)
MIXAMO_BONES = {
    "Hips": (None, "pelvis", None), "Spine": ("Hips", "spine1", "spine2"), "Spine1": ("Spine", "spine2", "spine3"),
    "Spine2": ("Spine1", "spine3", "neck"), "Neck": ("Spine2", "neck", "head"), "Head": ("Neck", "head", None),
}  # fmt: skip
# each limb chain as (bone, parent, head joint, aim joint), "{S}" the side and "{s}" its initial;
# both arms come before both legs, as in the table
LIMBS = (
    (("{S}Shoulder", "Spine2", "{s}_collar", "{s}_shoulder"), ("{S}Arm", "{S}Shoulder", "{s}_shoulder", "{s}_elbow"),
     ("{S}ForeArm", "{S}Arm", "{s}_elbow", "{s}_wrist"), ("{S}Hand", "{S}ForeArm", "{s}_wrist", "{s}_hand")),
    (("{S}UpLeg", "Hips", "{s}_hip", "{s}_knee"), ("{S}Leg", "{S}UpLeg", "{s}_knee", "{s}_ankle"),
     ("{S}Foot", "{S}Leg", "{s}_ankle", "{s}_foot"), ("{S}ToeBase", "{S}Foot", "{s}_foot", None)),
)  # fmt: skip
for _chain in LIMBS:
    for _side in ("Left", "Right"):
        for _bone, _parent, _joint, _aim in _chain:
            _fill = lambda text: None if text is None else text.format(S=_side, s=_side[0].lower())  # noqa: E731
            MIXAMO_BONES[_fill(_bone)] = (_fill(_parent), _fill(_joint), _fill(_aim))


def test_mixamo_table_names_tree_joints_and_aims():
    rig = rigs._mixamo()
    assert rig.name == "mixamo"
    assert list(rig.bones) == [f"mixamorig:{b}" for b in MIXAMO_BONES]
    names = list(MIXAMO_BONES)
    for b, (bone, (parent, joint, aim)) in enumerate(MIXAMO_BONES.items()):
        assert rig.parents[b] == (-1 if parent is None else names.index(parent)), bone
        assert rig.smpl_joints[b] == J[joint], bone
        assert rig.aims[b] == (-1 if aim is None else J[aim]), bone
    tips = {names[b]: tuple(v) for b, v in rig.end_sites.items()}
    assert set(tips) == {"Head", "LeftHand", "RightHand", "LeftToeBase", "RightToeBase"}


def test_mixamo_template_is_a_mirrored_t_pose_of_a_human_size():
    rig = rigs._mixamo()
    names = list(MIXAMO_BONES)
    offsets = rig.offsets
    assert offsets.shape == (22, 3) and offsets.dtype == np.float64
    np.testing.assert_array_equal(offsets[0], 0.0)
    lengths = np.linalg.norm(offsets[1:], axis=1)
    assert (lengths > 0.05).all() and (lengths < 0.45).all()  # no bone shorter than 5 cm or longer than 45 cm
    for left in [n for n in names if n.startswith("Left")]:
        right = "Right" + left[4:]
        np.testing.assert_array_equal(offsets[names.index(right)], offsets[names.index(left)] * [-1, 1, 1])
    for part in ("Arm", "ForeArm", "Hand"):  # arms straight out to the character's left (+X)
        o = offsets[names.index("Left" + part)]
        assert o[0] > 0.1 and o[1] == 0.0 and o[2] == 0.0
    for part in ("Leg", "Foot"):  # legs straight down
        o = offsets[names.index("Left" + part)]
        assert o[1] < -0.3 and o[0] == 0.0 and o[2] == 0.0
    for part in ("Spine1", "Spine2", "Neck"):
        o = offsets[names.index(part)]
        assert o[1] > 0.1 and o[0] == 0.0 and o[2] == 0.0
    spine, head, shoulder = offsets[names.index("Spine")], offsets[names.index("Head")], offsets[names.index("LeftShoulder")]
    assert spine[0] == 0.0 and spine[1] > 0.05 and 0 <= spine[2] < 0.05
    assert head[0] == 0.0 and head[1] > 0.05 and 0 < head[2] < 0.05
    assert shoulder[0] > 0.04 and shoulder[1] > 0.04 and 0 <= shoulder[2] < 0.05
    hip, toe = offsets[names.index("LeftUpLeg")], offsets[names.index("LeftToeBase")]
    assert hip[0] > 0.05 and hip[1] < -0.03 and -0.05 < hip[2] <= 0  # hips out to the side, a little down
    assert toe[0] == 0.0 and toe[1] < -0.05 and toe[2] > 0.05  # ball of the foot: down and forward
    tips = {names[b]: np.asarray(v) for b, v in rig.end_sites.items()}
    np.testing.assert_array_equal(tips["LeftHand"], -tips["RightHand"] * [1, -1, -1])
    np.testing.assert_array_equal(tips["LeftToeBase"], tips["RightToeBase"])
    assert tips["Head"][1] > 0.1 and tips["Head"][0] == 0.0 and tips["Head"][2] == 0.0  # the crown, straight up
    assert tips["LeftHand"][0] > 0.05 and tips["LeftHand"][1] == 0.0 and tips["LeftHand"][2] == 0.0
    assert tips["LeftToeBase"][2] > 0.05 and tips["LeftToeBase"][0] == 0.0 and tips["LeftToeBase"][1] == 0.0
    # a 1.8 m character, by a literal walk down the tree: crown to the toe tips
    positions = {}
    for b, name in enumerate(names):
        parent = MIXAMO_BONES[name][0]
        positions[name] = (positions[parent] if parent else np.zeros(3)) + offsets[b]
    top = positions["Head"][1] + tips["Head"][1]
    bottom = positions["LeftToeBase"][1] + tips["LeftToeBase"][1]
    assert 1.65 < top - bottom < 1.9


# -- Rig's own checks and rig lookup -------------------------------------------------------------
def two_bone_rig(**changes):
    fields = dict(name="two", bones=("root", "waist"), parents=(-1, 0), offsets=[0, 0, 0, 0, 1, 0],
                  smpl_joints=(0, 3), aims=(3, -1), end_sites={1: (0.0, 0.1, 0.0)})
    fields.update(changes)
    return Rig(**fields)


def test_a_rig_keeps_its_offsets_as_a_float_table():
    rig = two_bone_rig()
    assert isinstance(rig.offsets, np.ndarray) and rig.offsets.dtype == np.float64 and rig.offsets.shape == (2, 3)
    np.testing.assert_array_equal(rig.offsets, [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    assert rig.bone_of(3) == 1 and rig.children(0) == [1]


@pytest.mark.parametrize("changes", [
    dict(parents=(-1,)), dict(smpl_joints=(0,)), dict(aims=(3,)), dict(parents=(-1, 0, 1)), dict(aims=(3, -1, -1)),
])
def test_a_rig_needs_one_of_everything_per_bone(changes):
    with pytest.raises(ValueError, match="^a rig needs one parent, SMPL joint and aim per bone$"):
        two_bone_rig(**changes)


@pytest.mark.parametrize("changes", [dict(smpl_joints=(0, 4)), dict(smpl_joints=(3, 6))])
def test_a_rig_bone_must_carry_its_parents_child_joint(changes):
    with pytest.raises(ValueError, match=r"^(waist|root): its SMPL joint's parent is not its parent's joint$"):
        two_bone_rig(**changes)


def test_rig_lookup_by_any_case():
    assert get_rig("MIXAMO") is MIXAMO and get_rig("mixamo") is MIXAMO
    assert get_rig("SMPL") is None and get_rig("Smpl") is None
    rig = two_bone_rig()
    assert get_rig(rig) is rig
    with pytest.raises(ParameterError, match=r"^unknown rig 'unreal' \(known: smpl, mixamo\)$"):
        get_rig("unreal")


# -- reading a BVH on the Mixamo rig --------------------------------------------------------------
def rig_text(motion, **options) -> str:
    buffer = io.BytesIO()
    write_bvh_rig(motion, buffer, "mixamo", **options)
    return buffer.getvalue().decode()


def save(tmp_path, text, name="rig.bvh"):
    path = tmp_path / name
    path.write_text(text)
    return path


def without_end_site(text: str, bone: str) -> str:
    """The file with ``bone``'s End Site block (4 lines) removed."""
    lines = text.split("\n")
    start = next(k for k, line in enumerate(lines) if line.strip() == f"JOINT {bone}")
    site = next(k for k in range(start, len(lines)) if lines[k].strip() == "End Site")
    return "\n".join(lines[:site] + lines[site + 4:])


def test_rig_file_reads_back_every_joint_in_metres_and_centimetres(dance, tmp_path):
    expected = dance.joint_positions()
    metres = save(tmp_path, rig_text(dance), "m.bvh")
    cm = save(tmp_path, rig_text(dance, units="cm"), "cm.bvh")
    for path, units, factor in ((metres, "auto", 1.0), (metres, "m", 1.0), (cm, "auto", 1.0), (cm, "cm", 1.0),
                                (cm, "m", 100.0)):
        back = read_bvh_rig(path, "mixamo", units=units)
        np.testing.assert_allclose(back.joint_positions(), expected * factor, atol=1e-4 * factor)
        assert back.fps == 30.0 and back.num_frames == 6
        assert back.metadata == {"source": path.name, "rig": "mixamo"}
        np.testing.assert_allclose(back.skeleton.offsets[1:], dance.skeleton.offsets[1:] * factor, atol=1e-5 * factor)


def test_rig_file_without_hand_tips_takes_smpls_template_hands(dance, tmp_path):
    text = without_end_site(without_end_site(rig_text(dance), "mixamorig:LeftHand"), "mixamorig:RightHand")
    back = read_bvh_rig(save(tmp_path, text), MIXAMO)
    offsets = dance.skeleton.offsets.copy()
    offsets[[J["l_hand"], J["r_hand"]]] = SMPL24.offsets[[J["l_hand"], J["r_hand"]]]
    np.testing.assert_allclose(back.skeleton.offsets, offsets, atol=1e-5)
    np.testing.assert_allclose(back.joint_positions(), dance.with_skeleton(SMPL24.with_offsets(offsets)).joint_positions(),
                               atol=1e-4)


def test_rig_file_may_wrap_the_hips_in_a_root_it_does_not_name(dance, tmp_path):
    """An exporter's extra root (no rotation, no offset) carrying the hips' positions changes nothing."""
    text = rig_text(dance)
    head, motion_part = text.split("MOTION", 1)
    head = head.replace("HIERARCHY\nROOT mixamorig:Hips\n{\n\tOFFSET 0.000000 0.000000 0.000000\n"
                        "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n",
                        "HIERARCHY\nROOT Armature\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n"
                        "JOINT mixamorig:Hips\n{\n\tOFFSET 0.000000 0.000000 0.000000\n"
                        "\tCHANNELS 3 Zrotation Xrotation Yrotation\n", 1)
    assert head.count("Armature") == 1
    back = read_bvh_rig(save(tmp_path, head + "}\nMOTION" + motion_part), "mixamo")
    np.testing.assert_allclose(back.joint_positions(), dance.joint_positions(), atol=1e-4)


def test_rig_file_keeps_a_turned_and_offset_root_above_the_hips(dance, tmp_path):
    """A Blender-style "Armature" above the hips, offset and turned (here 90 degrees about x, a
    change of up axis, then a yaw that changes per frame), is composed in: every joint lands where
    the file's own forward kinematics puts it (it used to be dropped, up to 1.3 m off)."""
    text = rig_text(dance)
    head, motion_part = text.split("MOTION", 1)
    head = head.replace("HIERARCHY\nROOT mixamorig:Hips\n{\n\tOFFSET 0.000000 0.000000 0.000000\n"
                        "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n",
                        "HIERARCHY\nROOT Armature\n{\nOFFSET 0.5 0 -0.25\n"
                        "CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n"
                        "JOINT mixamorig:Hips\n{\n\tOFFSET 0.1 0.2 0.3\n"
                        "\tCHANNELS 3 Zrotation Xrotation Yrotation\n", 1) + "}\n"
    lines = motion_part.split("\n")
    rows = [k for k, line in enumerate(lines) if line and line[0] in "-0123456789"]
    for n, k in enumerate(rows):
        values = lines[k].split()
        lines[k] = " ".join(values[:3] + ["90", f"{10 * n}", "0"] + values[3:])
    data = bvh.read_bvh_raw(save(tmp_path, head + "MOTION" + "\n".join(lines)))
    positions, _ = file_forward_kinematics(data)
    back = read_bvh_rig(tmp_path / "rig.bvh", "mixamo", units="m").joint_positions()
    names = [joint.name for joint in data.joints]
    for b, bone in enumerate(MIXAMO.bones):
        np.testing.assert_allclose(back[:, MIXAMO.smpl_joints[b]], positions[names.index(bone)], atol=1e-4)


def test_rig_file_bone_names_need_no_prefix_and_no_case(dance, tmp_path):
    text = rig_text(dance).replace("mixamorig:", "").replace("LeftForeArm", "leftforearm").replace("Hips", "HIPS")
    back = read_bvh_rig(save(tmp_path, text), "mixamo")
    np.testing.assert_allclose(back.joint_positions(), dance.joint_positions(), atol=1e-4)


def test_rig_file_first_joint_of_a_name_is_the_bone(dance, tmp_path):
    """A second joint with a bone's name (an extra leaf) is ignored: the first one listed is the bone."""
    text = rig_text(dance)
    lines = text.split("\n")
    at = next(k for k, line in enumerate(lines) if line.strip() == "JOINT mixamorig:RightToeBase")
    pad = lines[at][: len(lines[at]) - len(lines[at].lstrip())]
    extra = [f"{pad}JOINT mixamorig:Head", f"{pad}{{", f"{pad}\tOFFSET 0 0.1 0", f"{pad}\tCHANNELS 0", f"{pad}}}"]
    head, rest = "\n".join(lines[:at] + extra + lines[at:]).split("MOTION", 1)
    back = read_bvh_rig(save(tmp_path, head + "MOTION" + rest), "mixamo")
    np.testing.assert_allclose(back.joint_positions(), dance.joint_positions(), atol=1e-4)


def test_rig_file_errors_name_the_file_and_the_bone(dance, tmp_path):
    text = rig_text(dance)
    missing = save(tmp_path, text.replace("mixamorig:LeftFoot", "mixamorig:LeftPaw"), "missing.bvh")
    with pytest.raises(MotionFormatError, match=f"^{missing}: not a mixamo skeleton \\(no joint named mixamorig:LeftFoot\\)$"):
        read_bvh_rig(missing)
    # two bones swapped in name: each now hangs under the wrong parent
    swapped = save(tmp_path, text.replace("mixamorig:LeftLeg", "TMP").replace("mixamorig:LeftFoot", "mixamorig:LeftLeg")
                   .replace("TMP", "mixamorig:LeftFoot"), "swapped.bvh")
    with pytest.raises(MotionFormatError, match=f"^{swapped}: joint mixamorig:LeftLeg has the wrong parent for a mixamo rig$"):
        read_bvh_rig(swapped)
    head, _ = text.split("MOTION", 1)
    empty = save(tmp_path, head + "MOTION\nFrames: 0\nFrame Time: 0.033333\n", "empty.bvh")
    with pytest.raises(MotionFormatError, match=f"^{empty}: no frames$"):
        read_bvh_rig(empty)


def test_rig_file_frame_rates(dance, tmp_path):
    text = rig_text(dance[:1])
    head, rest = text.split("Frame Time:", 1)
    row = rest.split("\n", 1)[1]
    for frame_time, fps in (("0.03333333", 30.0), ("0.03", 100.0 / 3.0), ("0.01666667", 60.0)):
        back = read_bvh_rig(save(tmp_path, f"{head}Frame Time: {frame_time}\n{row}"), "mixamo")
        assert back.num_frames == 1
        assert back.fps == pytest.approx(fps, abs=1e-9)
        assert (back.fps == round(back.fps)) == (fps == round(fps))


def file_forward_kinematics(data):
    """World positions of every joint and End Site of a parsed BVH, by a literal walk with scipy's rotations."""
    frames = len(data.values)
    starts = np.cumsum([0] + [len(j.channels) for j in data.joints])
    positions, tips, world = {}, {}, {}
    for j, joint in enumerate(data.joints):
        values = data.values[:, starts[j]:starts[j + 1]]
        axes = "".join(c[0].upper() for c in joint.channels if c.endswith("rotation"))
        angles = values[:, [k for k, c in enumerate(joint.channels) if c.endswith("rotation")]]
        local = Rotation.from_euler(axes, angles, degrees=True).as_matrix() if axes else np.tile(np.eye(3), (frames, 1, 1))
        if joint.parent < 0:
            base = np.tile(joint.offset, (frames, 1))
            for k, c in enumerate(joint.channels):
                if c.endswith("position"):
                    base[:, "xyz".index(c[0])] += values[:, k]
            world[j], positions[j] = local, base
        else:
            p = joint.parent
            positions[j] = positions[p] + world[p] @ joint.offset
            world[j] = world[p] @ local
        if joint.end_site is not None:
            tips[j] = positions[j] + world[j] @ joint.end_site
    return positions, tips


def test_rig_file_in_any_rest_pose_keeps_the_files_joint_positions(dance, tmp_path):
    """Offsets and End Sites turned off the T-pose (an A-pose rig): every SMPL joint lands where the file puts it."""
    rng = np.random.default_rng(7)
    lines = rig_text(dance).split("\n")
    for k, line in enumerate(lines):
        if line.strip().startswith("OFFSET") and k > 3:
            vector = np.array([float(v) for v in line.split()[1:]])
            turned = Rotation.from_rotvec(rng.normal(scale=0.3, size=3)).apply(vector)
            lines[k] = line[: line.index("OFFSET")] + "OFFSET " + " ".join(f"{v:.6f}" for v in turned)
    path = save(tmp_path, "\n".join(lines))
    data = bvh.read_bvh_raw(path)
    positions, tips = file_forward_kinematics(data)
    back = read_bvh_rig(path).joint_positions()
    names = [j.name for j in data.joints]
    for b, bone in enumerate(MIXAMO.bones):
        np.testing.assert_allclose(back[:, MIXAMO.smpl_joints[b]], positions[names.index(bone)], atol=1e-6)
    for side in ("Left", "Right"):
        hand = names.index(f"mixamorig:{side}Hand")
        np.testing.assert_allclose(back[:, J[f"{side[0].lower()}_hand"]], tips[hand], atol=1e-6)
    # the rotations are re-expressed against SMPL's rest directions: every bone an aimed-at joint ends
    # (the file's own direction, End Sites included) rests along the SMPL template's direction
    offsets = read_bvh_rig(path).skeleton.offsets
    for aim in sorted(set(MIXAMO.aims) - {-1}):
        np.testing.assert_allclose(offsets[aim] / np.linalg.norm(offsets[aim]),
                                   SMPL24.offsets[aim] / np.linalg.norm(SMPL24.offsets[aim]), atol=1e-6)


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


def test_zero_frames_and_the_frame_time_limits_are_accepted():
    data = bvh.parse_bvh(bvh_text(rows=[]))
    assert data.values.shape == (0, 9)
    for frame_time in ("0.001", "1.0", "1e-3"):
        assert bvh.parse_bvh(bvh_text(frame_time=frame_time)).frame_time == float(frame_time)


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


def test_parse_errors_name_bvh_by_default():
    with pytest.raises(MotionFormatError, match="^BVH: no MOTION section"):
        bvh.parse_bvh("HIERARCHY\n")


@pytest.mark.parametrize("text, message", BROKEN_FILES)
def test_a_broken_bvh_is_refused_with_its_line(text, message):
    with pytest.raises(MotionFormatError) as error:
        bvh.parse_bvh(text, "dance.bvh")
    assert str(error.value) == message


def test_undecodable_bvh_names_the_file(tmp_path):
    path = tmp_path / "latin.bvh"
    path.write_bytes(bvh_text().replace("chest", "br\xfcst").encode("latin-1"))
    with pytest.raises(MotionFormatError) as error:
        bvh.read_bvh_raw(path)
    assert str(error.value) == f"{path} is not a BVH text file"


# -- local rotations from any channel layout --------------------------------------------------------
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


@pytest.mark.parametrize("names, listed", [
    (list("abcdef"), "a, b, c, d, e, f"), (list("abcdefg"), "a, b, c, d, e, f, ..."), (["pelvis"], "pelvis"),
])
def test_other_skeletons_are_named_in_the_refusal(names, listed):
    with pytest.raises(MotionFormatError) as error:
        bvh.bvh_to_motion(bvh.parse_bvh(chain_text(names)), "dance.bvh")
    assert str(error.value) == f"dance.bvh: skeleton is not SMPL-24 (found {len(names)} joints: {listed})"


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


# -- joint-position .npy ------------------------------------------------------------------------------


def test_npy_positions_read_as_float64_in_either_layout(tmp_path):
    positions = np.arange(2 * 72, dtype=np.float32).reshape(2, 72) / 7.0
    np.save(tmp_path / "flat.npy", positions)
    back = npy.read_npy_joint_positions(tmp_path / "flat.npy")
    assert back.dtype == np.float64 and back.shape == (2, 24, 3)
    for t in range(2):
        for j in range(24):
            for k in range(3):
                assert back[t, j, k] == np.float32(positions[t, 3 * j + k])
    np.save(tmp_path / "one.npy", np.ones((1, 24, 3), dtype=np.int16))
    np.testing.assert_array_equal(npy.read_npy_joint_positions(tmp_path / "one.npy"), np.ones((1, 24, 3)))


@pytest.mark.parametrize("array, message", [
    (np.zeros((5, 3)), "expected joint positions of shape (T, 24, 3), got (5, 3)"),
    (np.zeros((2, 73)), "expected joint positions of shape (T, 24, 3), got (2, 73)"),
    (np.zeros((0, 24, 3)), "empty, NaN or infinite joint positions"),
    (np.full((1, 24, 3), np.inf), "empty, NaN or infinite joint positions"),
    (np.zeros((1, 24, 3), dtype=bool), "holds bool values, not joint positions"),
])
def test_npy_positions_refusals(tmp_path, array, message):
    path = tmp_path / "bad.npy"
    np.save(path, array)
    with pytest.raises(MotionFormatError) as error:
        npy.read_npy_joint_positions(path)
    assert str(error.value) == f"{path}: {message}"


def test_npy_unreadable_path_names_the_error(tmp_path):
    with pytest.raises(MotionFormatError) as error:
        npy.read_npy_joint_positions(tmp_path)
    assert str(error.value) == f"{tmp_path}: not a readable .npy array (IsADirectoryError)"


def test_npy_writer_stores_float32_positions(dance):
    buffer = io.BytesIO()
    npy.write_npy(dance, buffer)
    buffer.seek(0)
    stored = np.load(buffer)
    assert stored.dtype == np.float32
    np.testing.assert_allclose(stored, dance.joint_positions(), atol=1e-6)


# -- SMPL parameters --------------------------------------------------------------------------------------
def test_smpl_params_numbers_and_their_refusals():
    assert smpl_params.as_float_array(np.array([1, 2]), "k", "n").dtype == np.float64
    assert smpl_params.as_float_array([1, 2], "k", "n").dtype == np.float64
    assert smpl_params.first_number(np.array([[60, 2]]), "fps", "n") == 60.0
    for call, message in (
        (lambda: smpl_params.as_float_array(np.array(["a"]), "k", "n"), "n: k holds <U1 values, not numbers"),
        (lambda: smpl_params.as_float_array([[1, 2], [3]], "k", "n"), "n: k is not an array of numbers"),
        (lambda: smpl_params.first_number(np.zeros(0), "fps", "n"), "n: fps is empty"),
    ):
        with pytest.raises(MotionFormatError) as error:
            call()
        assert str(error.value) == message


def smpl_arrays(frames=2):
    rng = np.random.default_rng(5)
    return rng.normal(scale=0.3, size=(frames, 72)), rng.normal(size=(frames, 3)) + [0, 1, 0]


def test_smpl_params_become_a_motion_with_trans_over_scaling():
    poses, trans = smpl_arrays()
    motion = smpl_params.smpl_params_to_motion(poses, trans, None, 60.0, "n.pkl")
    np.testing.assert_allclose(motion.root_positions, trans, atol=1e-12)
    assert motion.metadata == {"source": "n.pkl"} and motion.fps == 60.0
    np.testing.assert_allclose(motion.rotation_matrices()[:, 5], Rotation.from_rotvec(poses[:, 15:18]).as_matrix(), atol=1e-9)
    scaled = smpl_params.smpl_params_to_motion(poses, trans * 95.0, np.array([95.0]), 1.0, "n.pkl")
    np.testing.assert_allclose(scaled.root_positions, trans, atol=1e-12)
    assert scaled.fps == 1.0
    one = smpl_params.smpl_params_to_motion(poses[:1], trans[:1], 1.0, 30.0, "n.pkl")
    assert one.num_frames == 1


@pytest.mark.parametrize("change, message", [
    (dict(poses=np.array([["a"] * 72])), "n.pkl: smpl_poses holds <U1 values, not numbers"),
    (dict(trans=np.array([["a"] * 3] * 2)), "n.pkl: smpl_trans holds <U1 values, not numbers"),
    (dict(scaling=np.zeros(0)), "n.pkl: smpl_scaling is empty"),
    (dict(trans=np.zeros((2, 2))), "n.pkl: smpl_trans must have shape (2, 3), got (2, 2)"),
    (dict(poses=np.zeros((0, 72)), trans=np.zeros((0, 3))), "n.pkl: no frames"),
    (dict(scaling=np.array([np.nan])), "n.pkl: NaN, infinite or non-positive values in SMPL parameters"),
    (dict(scaling=np.array([0.0])), "n.pkl: NaN, infinite or non-positive values in SMPL parameters"),
    (dict(fps=np.inf), "n.pkl: bad frame rate inf"),
    (dict(fps=0.0), "n.pkl: bad frame rate 0.0"),
])
def test_smpl_params_refusals(change, message):
    poses, trans = smpl_arrays()
    args = dict(poses=poses, trans=trans, scaling=None, fps=30.0)
    args.update(change)
    with pytest.raises(MotionFormatError) as error:
        smpl_params.smpl_params_to_motion(args["poses"], args["trans"], args["scaling"], args["fps"], "n.pkl")
    assert str(error.value) == message


def test_motion_to_smpl_params_in_float32_with_scaled_trans(dance):
    params = smpl_params.motion_to_smpl_params(dance, scaling=2.0)
    assert {k: v.dtype for k, v in params.items()} == {"smpl_poses": np.float32, "smpl_trans": np.float32,
                                                       "smpl_scaling": np.float32}
    np.testing.assert_allclose(params["smpl_trans"], dance.root_positions * 2.0, rtol=1e-6)
    np.testing.assert_array_equal(params["smpl_scaling"], [2.0])
    other = dance.skeleton.__class__(dance.skeleton.names[::-1], tuple(range(-1, 23)), dance.skeleton.offsets)
    with pytest.raises(MotionFormatError) as error:
        smpl_params.motion_to_smpl_params(Motion.rest(1, skeleton=other))
    assert str(error.value) == "SMPL parameters need the SMPL-24 skeleton"


def test_aistpp_pickle_keeps_the_scaling_asked(dance):
    buffer = io.BytesIO()
    aistpp.write_aistpp_pkl(dance, buffer, scaling=95.0)
    stored = pickle.loads(buffer.getvalue())
    np.testing.assert_allclose(stored["smpl_trans"], dance.root_positions * 95.0, rtol=1e-6)
    np.testing.assert_array_equal(stored["smpl_scaling"], [95.0])
    assert stored["smpl_trans"].dtype == np.float64


# -- JSON ---------------------------------------------------------------------------------------------------
def precise_motion():
    axis_angle = np.zeros((1, 24, 3))
    axis_angle[0, 0] = [0.123456789, 0.0, 0.0]
    offsets = SMPL24.offsets.copy()
    offsets[1] = [0.12345678, -0.087654321, 0.0]
    return Motion.from_axis_angle([[1.23456789, 0.98765432, -0.11111111]], axis_angle,
                                  skeleton=SMPL24.with_offsets(offsets), metadata={"where": Path("/x/y")})


def test_json_document_fields_and_their_precision():
    motion = precise_motion()
    buffer = io.BytesIO()
    json_format.write_json(motion, buffer)
    document = json.loads(buffer.getvalue())
    assert document["format"] == "choreo-motion" and document["version"] == 1
    assert document["metadata"] == {"where": "/x/y"}
    assert document["offsets"][1] == [0.123457, -0.087654, 0.0]
    assert document["root_positions"] == [[1.234568, 0.987654, -0.111111]]
    assert document["rotations"][0][0] == [0.1234568, 0.0, 0.0]
    positions = np.array(document["joint_positions"])
    assert positions.shape == (1, 24, 3)
    np.testing.assert_allclose(positions, motion.joint_positions(), atol=5.1e-6)
    assert np.abs(positions * 1e5 - np.round(positions * 1e5)).max() < 1e-6  # 5 decimals


def test_json_reads_its_skeleton_and_metadata(tmp_path):
    motion = precise_motion()
    path = tmp_path / "m.json"
    with open(path, "wb") as handle:
        json_format.write_json(motion, handle)
    back = json_format.read_json(path)
    assert back.metadata == {"where": "/x/y", "source": "m.json"}  # like every reader, the file it came from, by name
    np.testing.assert_allclose(back.skeleton.offsets[1], [0.123457, -0.087654, 0.0])
    np.testing.assert_allclose(back.joint_positions(), motion.joint_positions(), atol=1e-5)


@pytest.mark.parametrize("document, message", [
    ({"version": 1}, "not a choreo motion JSON (format field missing)"),
    ({"format": "choreo-motion", "fps": 30}, "malformed motion JSON (KeyError)"),
])
def test_json_refusals(tmp_path, document, message):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(document))
    with pytest.raises(MotionFormatError) as error:
        json_format.read_json(path)
    assert str(error.value) == f"{path}: {message}"


# -- NPZ ------------------------------------------------------------------------------------------------------
def test_npz_written_keys_and_types(dance):
    motion = dance.replace(metadata={"where": Path("/x")})
    buffer = io.BytesIO()
    npz.write_npz(motion, buffer)
    buffer.seek(0)
    stored = dict(np.load(buffer))
    assert stored["joint_positions"].dtype == np.float32 and stored["offsets"].dtype == np.float64
    np.testing.assert_array_equal(stored["offsets"], dance.skeleton.offsets)
    assert json.loads(str(stored["metadata"])) == {"where": "/x"}


def save_npz(tmp_path, **arrays):
    path = tmp_path / "m.npz"
    np.savez(path, **arrays)
    return path


def test_npz_reads_offsets_fps_metadata_and_stored_positions(tmp_path):
    poses, trans = smpl_arrays()
    offsets = SMPL24.offsets * 1.1
    positions = np.arange(2 * 24 * 3, dtype=np.float32).reshape(2, 24, 3)
    path = save_npz(tmp_path, smpl_poses=poses, smpl_trans=trans, fps=np.array([25.0]), offsets=offsets,
                    joint_positions=positions, metadata=np.array('{"genre": "pop"}'))
    motion = npz.read_npz(path)
    np.testing.assert_allclose(motion.skeleton.offsets, offsets)
    assert motion.fps == 25.0 and motion.metadata == {"genre": "pop", "source": path.name}
    stored = npz.read_npz_joint_positions(path)
    assert stored.dtype == np.float64
    np.testing.assert_array_equal(stored, positions)


@pytest.mark.parametrize("offsets", [SMPL24.offsets[:23] * 1.1, np.full((24, 3), np.nan), np.full((24, 3), "a")])
def test_npz_damaged_offsets_fall_back_to_the_template(tmp_path, offsets):
    poses, trans = smpl_arrays()
    motion = npz.read_npz(save_npz(tmp_path, smpl_poses=poses, smpl_trans=trans, offsets=offsets))
    np.testing.assert_array_equal(motion.skeleton.offsets, SMPL24.offsets)
    assert motion.fps == 30.0


@pytest.mark.parametrize("arrays, message", [
    (dict(smpl_poses=np.zeros((1, 72))), "NPZ lacks the smpl_poses and smpl_trans arrays"),
    (dict(smpl_trans=np.zeros((1, 3))), "NPZ lacks the smpl_poses and smpl_trans arrays"),
    (dict(smpl_poses=np.zeros((1, 72)), smpl_trans=np.zeros((1, 3)), fps=np.zeros(0)), "fps is empty"),
    (dict(smpl_poses=np.zeros((1, 72)), smpl_trans=np.zeros((1, 2))), "smpl_trans must have shape (1, 3), got (1, 2)"),
])
def test_npz_refusals_name_the_file(tmp_path, arrays, message):
    path = save_npz(tmp_path, **arrays)
    with pytest.raises(MotionFormatError) as error:
        npz.read_npz(path)
    assert str(error.value) == f"{path}: {message}"


# -- the pickle stand-ins, called as the unpickler would call them ------------------------------------------


def refused(call, message):
    with pytest.raises(UnsafePickle) as error:
        call()
    assert str(error.value) == message


def dtype_state(order="<"):
    return (3, order, None, None, None, -1, -1, 0)  # numpy's own dtype state for a plain number


def test_dtype_record_byte_orders():
    record = safe_pickle._DTypeRecord("f8")
    assert record.byteorder == "=" and record.resolve() == np.dtype("=f8")
    for order, expected in (("<", "<f8"), (">", ">f8"), ("|", "=f8"), ("=", "=f8")):
        record = safe_pickle._DTypeRecord("f8", False, True)
        record.__setstate__(dtype_state(order))
        assert record.byteorder == order and record.resolve() == np.dtype(expected)
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__(dtype_state("!")), "bad byte order '!'")
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__([3, "<", None, None, None, -1, -1, 0]),
            "structured or sub-array dtypes are not allowed")
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__((3, "<", None, ("x",), None, -1, -1, 0)),
            "structured or sub-array dtypes are not allowed")
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__((3, "<", (np.float64, (2,)), None, None, -1, -1, 0)),
            "structured or sub-array dtypes are not allowed")
    refused(lambda: safe_pickle._DTypeRecord("O8"), "dtype 'O8' is not a plain numeric type")


def array_record(shape, dtype, fortran, raw):
    record = safe_pickle._ArrayRecord()
    record.__setstate__((1, shape, dtype, fortran, raw))
    return record.array


def test_array_records_rebuild_c_and_fortran_arrays():
    values = np.arange(6, dtype="<i4")
    dtype = safe_pickle._DTypeRecord("i4")
    np.testing.assert_array_equal(array_record((2, 3), dtype, False, values.tobytes()), [[0, 1, 2], [3, 4, 5]])
    np.testing.assert_array_equal(array_record((2, 3), dtype, True, values.tobytes()), [[0, 2, 4], [1, 3, 5]])
    assert array_record((0,), dtype, False, b"").shape == (0,)
    np.testing.assert_array_equal(array_record((2,), dtype, False, np.array([1, 2], "<i4").tobytes().decode("latin1")), [1, 2])
    refused(lambda: array_record((2,), "i4", False, b"\0" * 8), "array without a plain dtype")
    refused(lambda: safe_pickle._ArrayRecord().__setstate__([1, (2,), dtype, False, b"\0" * 8]), "unexpected array state")
    refused(lambda: array_record((2,), dtype, False, 12345), "array data is not raw bytes")
    refused(lambda: array_record((-1,), dtype, False, b""), "bad array shape (-1,)")
    refused(lambda: array_record([2], dtype, False, b"\0" * 8), "bad array shape [2]")
    refused(lambda: array_record((3,), dtype, False, b"\0" * 8), "array of shape (3,) does not match its 8 bytes")


def test_frombuffer_scalar_codec_and_reconstruct_stand_ins():
    dtype = safe_pickle._DTypeRecord("f4")
    record = safe_pickle._frombuffer(np.array([1.5, 2.5], "=f4").tobytes(), dtype, (2,), "C")
    np.testing.assert_array_equal(record.array, [1.5, 2.5])
    refused(lambda: safe_pickle._frombuffer(b"", "f4", (0,), "C"), "array without a plain dtype")
    refused(lambda: safe_pickle._frombuffer(b"", dtype, (0,), "K"), "array without a plain dtype")
    assert safe_pickle._scalar(dtype, np.array([2.5], "=f4").tobytes()) == 2.5
    refused(lambda: safe_pickle._scalar("f4", b"\0" * 4), "scalar without a plain dtype")
    refused(lambda: safe_pickle._scalar(dtype, b"\0" * 8), "scalar of the wrong size")
    assert safe_pickle._encode("\xe9", "latin1") == b"\xe9" and safe_pickle._encode("\xff", "latin-1") == b"\xff"
    refused(lambda: safe_pickle._encode("\xe9", "utf-8"), "unexpected codec call")
    refused(lambda: safe_pickle._encode(b"x", "latin1"), "unexpected codec call")
    refused(lambda: safe_pickle._reconstruct(list, (0,), b"b"), "only numpy arrays may be reconstructed")
    assert isinstance(safe_pickle._reconstruct(safe_pickle._NdarrayMarker, (0,), b"b"), safe_pickle._ArrayRecord)


def test_encode_refuses_the_default_codec():
    refused(lambda: safe_pickle._encode("abc"), "unexpected codec call")


def test_unpickler_names_what_it_refuses():
    unpickler = safe_pickle._StandInUnpickler(io.BytesIO(b""))
    assert unpickler.find_class("numpy", "dtype") is safe_pickle._DTypeRecord
    refused(lambda: unpickler.find_class("os", "system"), "refusing to load os.system")
    refused(lambda: unpickler.find_class("os\n", "system"), "refusing to load 'os\\n.system'")


def test_materialiser_counts_and_refuses():
    build = safe_pickle._Materialiser()
    shared = [1, 2]
    value, size = build._build({"a": shared, "b": (shared, 3)}, 0)
    assert value == {"a": [1, 2], "b": ([1, 2], 3)} and isinstance(value["b"], tuple) and isinstance(value["a"], list)
    assert value["a"] is value["b"][0]  # a shared list is built once
    assert size == 1 + 3 + (1 + 3 + 1)  # a literal count: every container and item of the unfolded tree
    assert build.total == 3 + 3 + 5 + 9  # every built node, shared ones again each time they are reached
    assert safe_pickle._Materialiser()._build(safe_pickle._ArrayRecord.of(np.zeros(2)), 0)[1] == 1
    assert safe_pickle._Materialiser().total == 0
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._ArrayRecord()), "array without data")
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._DTypeRecord("f8")), "stray numpy object")
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._NdarrayMarker), "stray numpy object")
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._NdarrayMarker()), "stray numpy object")


def chain(items, wraps):
    """A list of ``items`` ones inside ``wraps`` single-item lists: every list is reached once, and
    the total the materialiser counts (container sizes) is (items + 1) + (items + 2) + ... + (items + 1 + wraps)."""
    value = [1] * items
    for _ in range(wraps):
        value = [value]
    return value


def test_materialiser_limits_on_one_tree_and_on_the_total(monkeypatch):
    monkeypatch.setattr(safe_pickle, "MAX_OBJECTS", 100)
    message = "pickle unfolds into more than 100 values"
    assert len(safe_pickle._Materialiser()([0] * 99)) == 99  # 100 nodes: at the limit
    refused(lambda: safe_pickle._Materialiser()([0] * 100), message)
    assert sum(range(4, 29)) == 400 and sum(range(4, 30)) == 429
    assert safe_pickle._Materialiser()(chain(3, 24)) == chain(3, 24)  # a total of exactly 400 = 4 x 100
    refused(lambda: safe_pickle._Materialiser()(chain(3, 25)), message)  # 429


def test_pickled_python2_text_and_errors_name_their_cause(tmp_path):
    path = tmp_path / "p.pkl"
    path.write_bytes(pickle.dumps({"name": "caf\xe9"}, protocol=2))
    assert safe_pickle.load_numpy_pickle(path) == {"name": "caf\xe9"}
    path.write_bytes(b"\x80\x02U\x04caf\xe9q\x00.")  # a Python 2 str (bytes) read as latin-1 text
    assert safe_pickle.load_numpy_pickle(path) == "caf\xe9"
    path.write_bytes(b"\x80\x02]q\x00h\x01.")  # a memo GET of an index never PUT
    refused(lambda: safe_pickle.load_numpy_pickle(path), "unreadable pickle (UnpicklingError)")


def test_first_number_names_its_key_and_file():
    with pytest.raises(MotionFormatError) as error:
        smpl_params.first_number(np.array(["a"]), "fps", "n.npz")
    assert str(error.value) == "n.npz: fps holds <U1 values, not numbers"


# -- the registry: formats by name or extension, readers, writers, rigs ------------------------------------


def test_format_names_and_extensions():
    assert registry._format_for("a.txt", ".BVH", InputError) is registry.FORMATS["bvh"]
    assert registry._format_for("a.txt", "Npz", InputError) is registry.FORMATS["npz"]
    for path, format, message in (
        ("a.bvh", "abc", "unknown motion format 'abc' (supported: bvh, npz, pkl, json, npy, glb, fbx)"),
        ("folder/noext", None, "folder/noext: unknown motion file type '(none)' "
                               "(supported: .bvh, .npz, .pkl, .json, .npy, .glb, .fbx)"),
        ("a.txt", None, "a.txt: unknown motion file type '.txt' (supported: .bvh, .npz, .pkl, .json, .npy, .glb, .fbx)"),
    ):
        with pytest.raises(OutputError) as error:
            registry._format_for(path, format, OutputError)
        assert str(error.value) == message


def test_reading_refuses_missing_folders_empty_and_write_only_files(tmp_path):
    (tmp_path / "empty.bvh").write_bytes(b"")
    (tmp_path / "x.npy").write_bytes(b"x")
    (tmp_path / "x.fbx").write_bytes(b"x")
    for read in (registry.read_motion, registry.read_joint_positions):
        for name, kind, message in (("none.bvh", InputError, "{}: no such file"),
                                    ("", InputError, "{} is a folder, expected a motion file"),
                                    ("empty.bvh", MotionFormatError, "{} is empty"),
                                    ("x.fbx", InputError, "{}: choreo writes .fbx files but does not read them")):
            path = tmp_path / name if name else tmp_path
            with pytest.raises(kind) as error:
                read(path, format="bvh" if not name else None)
            assert str(error.value) == message.format(path)
    with pytest.raises(InputError) as error:
        registry.read_motion(tmp_path / "x.npy")
    assert str(error.value) == f"{tmp_path / 'x.npy'}: a .npy file holds joint positions only, not a rotation-based motion"
    with pytest.raises(InputError):
        registry.read_joint_positions(tmp_path / "x.weird")


def test_an_explicit_format_overrides_the_extension(dance, tmp_path):
    path = tmp_path / "dance.txt"
    with open(path, "wb") as handle:
        json_format.write_json(dance, handle)
    np.testing.assert_allclose(registry.read_motion(path, format="json").joint_positions(), dance.joint_positions(), atol=1e-5)
    positions, fps = registry.read_joint_positions(path, format="json")
    np.testing.assert_allclose(positions, dance.joint_positions(), atol=1e-5)
    assert fps == 30.0


def test_piped_motion_in_a_format_named_only_by_the_caller(dance, monkeypatch):
    """A protocol-1 pickle starts with no signature the sniffer knows: the format must come from the caller."""
    buffer = io.BytesIO()
    arrays = {k: v.astype(np.float64) for k, v in smpl_params.motion_to_smpl_params(dance).items()}
    pickle.dump(arrays, buffer, protocol=1)
    data = buffer.getvalue()
    assert not data.startswith((b"\x80", b"{", b"PK", b"HIERARCHY"))
    for read in (registry.read_motion, registry.read_joint_positions):
        monkeypatch.setattr("sys.stdin", type("Stdin", (), {"buffer": io.BytesIO(data)})())
        result = read("-", format="pkl")
        positions = result.joint_positions() if isinstance(result, Motion) else result[0]
        np.testing.assert_allclose(positions, dance.with_skeleton(SMPL24).joint_positions(), atol=1e-5)


def test_npz_joint_positions_prefer_the_stored_ones(tmp_path):
    poses, trans = smpl_arrays()
    stored = np.arange(2 * 24 * 3, dtype=np.float32).reshape(2, 24, 3)
    path = save_npz(tmp_path, smpl_poses=poses, smpl_trans=trans, joint_positions=stored, fps=np.array(50.0))
    positions, fps = registry.read_joint_positions(path)
    np.testing.assert_array_equal(positions, stored)
    assert fps == 50.0
    bare = tmp_path / "bare.npz"
    np.savez(bare, smpl_poses=poses, smpl_trans=trans)
    positions, _ = registry.read_joint_positions(bare)
    expected = smpl_params.smpl_params_to_motion(poses, trans, None, 30.0, "x").joint_positions()
    np.testing.assert_allclose(positions, expected, atol=1e-12)
    wrong = tmp_path / "wrong.npz"
    np.savez(wrong, smpl_poses=poses, smpl_trans=trans, joint_positions=stored[:1])
    positions, _ = registry.read_joint_positions(wrong)
    np.testing.assert_allclose(positions, expected, atol=1e-12)


def test_output_checks_stdout_rigs_and_blender(monkeypatch):
    with pytest.raises(OutputError) as error:
        registry.check_output_format("-")
    assert str(error.value) == "writing to stdout (-) needs an explicit --format"
    with pytest.raises(ParameterError) as error:
        registry.check_output_format("x.npz", rig="mixamo")
    assert str(error.value) == "--rig mixamo applies to .bvh and .fbx outputs, not .npz"
    monkeypatch.setattr(registry, "blender_command", lambda: None)
    registry.check_output_format("x.bvh")
    with pytest.raises(OutputError) as error:
        registry.check_output_format("x.fbx")
    assert str(error.value) == NO_BLENDER
    monkeypatch.setattr(registry, "blender_command", lambda: ["/opt/blender/blender"])
    registry.check_output_format("x.fbx")


def test_writing_on_a_rig_writes_the_rigs_bones(dance, tmp_path):
    path = tmp_path / "out.bvh"
    assert registry.write_motion(dance, path, rig="mixamo") == str(path)
    names = [j.name for j in bvh.read_bvh_raw(path).joints]
    assert names == list(MIXAMO.bones)
    np.testing.assert_allclose(registry.read_motion(path).joint_positions(), dance.joint_positions(), atol=1e-4)
    many = [str(tmp_path / "a.bvh"), str(tmp_path / "b.json")]
    assert registry.write_motions(dance, many, rig=None) == many
    assert [j.name for j in bvh.read_bvh_raw(many[0]).joints][:2] == ["pelvis", "l_hip"]


# -- safe .npy / .npz loading: hand-made headers ----------------------------------------------------------------
def npy_bytes(descr: str, shape, data: bytes = b"", version=(1, 0)) -> bytes:
    """An .npy file written byte by byte: magic, version, header length, the header dict, data."""
    header = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {tuple(shape)!r}, }}".encode()
    length_bytes = 2 if version == (1, 0) else 4
    total = 6 + 2 + length_bytes + len(header) + 1
    header += b" " * ((-total) % 64) + b"\n"
    return (b"\x93NUMPY" + bytes(version) + len(header).to_bytes(length_bytes, "little") + header + data)


def declared(raw: bytes) -> int:
    return safe_arrays._declared_bytes(io.BytesIO(raw), "w")


def test_declared_bytes_from_hand_made_headers():
    assert declared(npy_bytes("<f4", (3, 4))) == 48
    assert declared(npy_bytes("<f8", (2, 5), version=(2, 0))) == 80
    assert declared(npy_bytes("<f8", (0, 3))) == 0
    assert declared(npy_bytes("|V0", (0,))) == 0
    assert declared(npy_bytes("<f8", (2**40, 2**40))) == 8 * 2**80  # no int64 wrap-around
    for raw, message in (
        (npy_bytes("<f8", (-1, 3)), "w: a negative dimension in its header"),
        (npy_bytes("|V0", (1,)), "w: items of zero bytes (|V0)"),
        (npy_bytes("|V0", (3,)), "w: items of zero bytes (|V0)"),
        (b"\x93NUMPY\x09\x07" + b"\0" * 64, "w: unknown .npy format version 9.7"),
        (b"\x93NUMPY\x02\x00" + (65537).to_bytes(4, "little") + b" " * 64, "w: a 65,537-byte .npy header (damaged or forged)"),
    ):
        with pytest.raises(MotionFormatError) as error:
            declared(raw)
        assert str(error.value) == message
    for raw in (b"\x93NUMPY\x02\x00" + (65536).to_bytes(4, "little") + b" " * 64,
                b"\x93NUMPY\x02\x00" + b"\xff\xff\x00\x00" + b" " * 64,  # 65,535 read little-endian
                b"\x93NUMPY\x01\x00" + b"\x10\x00" + b"{'descr': 1}    "):
        with pytest.raises(MotionFormatError, match=r"^w: not a readable NumPy array \((ValueError|EOFError|OSError)\)$"):
            declared(raw)


def test_text_arrays_are_checked_in_any_byte_order(tmp_path):
    path = tmp_path / "t.npy"
    np.save(path, np.array(["ab", "\U0010ffff"], dtype=">U2"))
    assert list(safe_arrays.load_npy(path)) == ["ab", "\U0010ffff"]
    path.write_bytes(npy_bytes("<U1", (2,), (0x61).to_bytes(4, "little") + (0x110000).to_bytes(4, "little")))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npy(path)
    assert str(error.value) == f"{path}: text with characters beyond Unicode (damaged file)"


def test_npy_size_checks_name_the_file(tmp_path):
    path = tmp_path / "a.npy"
    np.save(path, np.zeros(10))
    assert safe_arrays.load_npy(path, limit=80).shape == (10,)  # exactly at the limit
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npy(path, limit=79)
    assert str(error.value) == f"{path}: declares 80 bytes of data (more than the 79 choreo reads)"
    path.write_bytes(npy_bytes("<f8", (100,), b"\0" * 80))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npy(path)
    assert str(error.value) == f"{path}: declares 800 bytes of data but holds 80 (damaged or forged)"
    path.write_bytes(b"\x93NUMPY\x01\x00\x10\x00{'descr': 1}    ")
    with pytest.raises(MotionFormatError, match=rf"^{path}: not a readable NumPy array \(\w+\)$"):
        safe_arrays.load_npy(path)


def npz_of(path, members: dict, compression=zipfile.ZIP_STORED):
    with zipfile.ZipFile(path, "w", compression) as archive:
        for name, raw in members.items():
            archive.writestr(name, raw)
    return path


def test_npz_member_sizes_against_the_limit(tmp_path):
    member = io.BytesIO()
    np.save(member, np.zeros(1000))
    raw = member.getvalue()
    path = npz_of(tmp_path / "z.npz", {"a.npy": raw})
    size = len(raw)  # the zip directory's uncompressed size of the member
    data = size - 128
    assert data == 8000
    np.testing.assert_array_equal(safe_arrays.load_npz(path, limit=10_000)["a"], np.zeros(1000))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(path, limit=size - 4096)
    assert str(error.value) == f"{path}: a.npy: declares 8,000 bytes of data (more than the {size - 4096:,} choreo reads)"
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(path, limit=size - 4097)
    assert str(error.value) == f"{path}: a.npy: {size:,} bytes uncompressed (more than choreo reads)"


def test_npz_damaged_members_are_named(tmp_path):
    forged = npz_of(tmp_path / "f.npz", {"b\nc.npy": npy_bytes("<f8", (100,), b"\0" * 80)})
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(forged)
    assert str(error.value) == f"{forged}: 'b\\nc.npy': declares 800 bytes of data but holds 80 (damaged or forged)"
    broken = npz_of(tmp_path / "h.npz", {"h.npy": b"\x93NUMPY\x01\x00\x10\x00{'descr': 1}    "})
    with pytest.raises(MotionFormatError, match=rf"^{broken}: h.npy: not a readable NumPy array \(\w+\)$"):
        safe_arrays.load_npz(broken)
    text = npz_of(tmp_path / "t.npz", {"t.npy": npy_bytes("<U1", (1,), (0x110000).to_bytes(4, "little"))})
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(text)
    assert str(error.value) == f"{text}: t.npy: text with characters beyond Unicode (damaged file)"
    member = io.BytesIO()
    np.save(member, np.arange(50.0))
    raw = member.getvalue()
    crc = npz_of(tmp_path / "c.npz", {"c.npy": raw})
    archive = bytearray(crc.read_bytes())
    archive[archive.index(raw[-16:]) + 8] ^= 0xFF  # stored data that no longer matches the zip's CRC
    crc.write_bytes(bytes(archive))
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(crc)
    assert str(error.value) == f"{crc}: c.npy: not a readable array (BadZipFile)"
    (tmp_path / "n.npz").write_bytes(b"not a zip")
    with pytest.raises(MotionFormatError) as error:
        safe_arrays.load_npz(tmp_path / "n.npz")
    assert str(error.value) == f"{tmp_path / 'n.npz'}: not a readable NPZ file (BadZipFile)"
    assert safe_arrays.printable("a b") == "a b" and safe_arrays.printable("a\tb") == "'a\\tb'"


def test_empty_bytes_and_the_format_list():
    assert safe_pickle._empty_bytes() == b""
    refused(lambda: safe_pickle._empty_bytes(10), "unexpected bytes() call")
    assert [f.name for f in registry.list_formats()] == ["bvh", "npz", "pkl", "json", "npy", "glb", "fbx"]


def rest_of_file(data):
    """Rest positions of every joint and End Site of a parsed BVH (all rotations zero), by a literal walk."""
    points, at = [], {}
    for j, joint in enumerate(data.joints):
        at[j] = (at[joint.parent] if joint.parent >= 0 else np.zeros(3)) + (joint.offset if joint.parent >= 0 else 0.0)
        points.append(at[j])
        if joint.end_site is not None:
            points.append(at[j] + joint.end_site)
    return np.array(points)


def test_rig_lengths_take_the_templates_bone_lengths_and_scale_the_root_path(dance, tmp_path):
    own = bvh.parse_bvh(rig_text(dance, lengths="motion"))
    rig = bvh.parse_bvh(rig_text(dance, lengths="rig"))
    for b, (a, r) in enumerate(zip(own.joints, rig.joints)):
        assert a.name == r.name == MIXAMO.bones[b]
        if b:
            assert np.linalg.norm(r.offset) == pytest.approx(np.linalg.norm(MIXAMO.offsets[b]), abs=2e-6)
            np.testing.assert_allclose(r.offset / np.linalg.norm(r.offset), a.offset / np.linalg.norm(a.offset), atol=1e-5)
        if b in MIXAMO.end_sites:
            assert np.linalg.norm(r.end_site) == pytest.approx(np.linalg.norm(MIXAMO.end_sites[b]), abs=2e-6)
    ratio = -rest_of_file(rig)[:, 1].min() / -rest_of_file(own)[:, 1].min()
    np.testing.assert_allclose(rig.values[:, :3], own.values[:, :3] * ratio, atol=2e-5)
    np.testing.assert_allclose(rig.values[:, 3:], own.values[:, 3:], atol=2e-5)
    sites = rigs.rig_end_sites(dance, "mixamo", "rig")
    assert sorted(sites) == sorted(MIXAMO.end_sites)
    for b, tip in sites.items():
        np.testing.assert_allclose(tip, rig.joints[b].end_site, atol=1e-6)


def test_pickle_file_size_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(safe_pickle, "MAX_FILE_BYTES", 3 << 20)
    path = tmp_path / "p.pkl"
    data = pickle.dumps({"a": 1}, protocol=2)
    path.write_bytes(data + b"\0" * ((3 << 20) - len(data)))  # exactly at the limit: read up to its STOP
    assert safe_pickle.load_numpy_pickle(path) == {"a": 1}
    path.write_bytes(data + b"\0" * ((3 << 20) - len(data) + 1))
    refused(lambda: safe_pickle.load_numpy_pickle(path), "file is larger than 3 MiB")


# -- retargeting helpers ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("a", [(0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 2.0), (0.6, 0.8, 0.0), (-0.95, 0.1, 0.2),
                               (1.0, 1.0, 0.0), (1.0, 0.0, 1.0), (0.0, 1.0, 1.0)])
def test_shortest_arc_between_opposite_directions_is_a_half_turn(a):
    a = np.asarray(a)
    unit_a = a / np.linalg.norm(a)
    rotation = rigs.shortest_arc(a, -3.0 * a)
    assert np.isfinite(rotation).all()
    np.testing.assert_allclose(rotation @ unit_a, -unit_a, atol=1e-12)
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(rotation) == pytest.approx(1.0, abs=1e-12)
    assert np.trace(rotation) == pytest.approx(-1.0, abs=1e-12)  # a turn of 180 degrees
    np.testing.assert_array_equal(rigs.shortest_arc(a, 2.0 * a), np.eye(3))


def test_retarget_defaults_metadata_and_refusals(dance, tmp_path):
    motion = dance.replace(fps=25.0, metadata={"genre": "pop"})
    on_rig = rigs.rig_motion(motion, "mixamo")
    assert on_rig.fps == 25.0 and on_rig.metadata == {"genre": "pop", "rig": "mixamo"}
    np.testing.assert_allclose(on_rig.joint_positions(), motion.joint_positions()[:, list(MIXAMO.smpl_joints)], atol=1e-9)
    np.testing.assert_allclose(rigs.retarget(motion, MIXAMO).offsets, rigs.retarget(motion, MIXAMO, "motion").offsets)
    sites = rigs.rig_end_sites(motion, "mixamo")
    head, toe = MIXAMO.bones.index("mixamorig:Head"), MIXAMO.bones.index("mixamorig:LeftToeBase")
    np.testing.assert_allclose(sites[head], bvh.END_SITES["head"], atol=1e-12)  # SMPL's own tips, no rotation at the head
    np.testing.assert_allclose(sites[toe], bvh.END_SITES["l_foot"], atol=1e-12)
    buffer = io.BytesIO()
    write_bvh_rig(motion, buffer)  # Mixamo by default
    assert "ROOT mixamorig:Hips" in buffer.getvalue().decode()
    for call, kind, message in (
        (lambda: rigs.retarget(motion, "smpl"), ParameterError, "retarget needs a rig other than SMPL-24"),
        (lambda: rigs.retarget(motion, MIXAMO, "cubits"), ParameterError, "unknown lengths 'cubits' (use motion or rig)"),
        (lambda: rigs.retarget(Motion.rest(1, skeleton=SMPL24.__class__(("a", "b"), (-1, 0), np.zeros((2, 3)))), MIXAMO),
         MotionFormatError, "retargeting needs a motion on the SMPL-24 skeleton"),
        (lambda: write_bvh_rig(motion, io.BytesIO(), units="mm"), MotionFormatError, "unknown BVH units 'mm' (use m or cm)"),
    ):
        with pytest.raises(kind) as error:
            call()
        assert str(error.value) == message


def test_writing_several_files_with_a_format_and_a_rig(dance, tmp_path):
    paths = [str(tmp_path / "a.txt"), str(tmp_path / "b.dat")]
    assert registry.write_motions(dance, paths, format="json") == paths
    np.testing.assert_allclose(json_format.read_json(paths[1]).joint_positions(), dance.joint_positions(), atol=1e-5)
    rigged = [str(tmp_path / "c.bvh")]
    registry.write_motions(dance, rigged, rig="mixamo")
    assert bvh.read_bvh_raw(rigged[0]).joints[0].name == "mixamorig:Hips"


def test_a_bvh_without_channels_is_named_as_such():
    text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION\nFrames: 1\nFrame Time: 0.5\n\n"
    with pytest.raises(MotionFormatError, match=r"^x.bvh: no joint has CHANNELS, so its 1 frames hold no motion$"):
        bvh.parse_bvh(text, "x.bvh")
