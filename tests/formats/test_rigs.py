"""Retargeting onto Mixamo's rig: its rest pose is a T-pose, and the dance survives the round trip.

Round trip: retarget, write BVH on the rig, read the file back onto SMPL-24, compare joint
positions to the original's: exactly (bone lengths kept), or bone by bone after bone-length
normalisation (the rig's own lengths).
"""

import io

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from choreo.errors import MotionFormatError, ParameterError
from choreo.formats import (
    bvh,
    read_bvh_raw,
    rigs,
    write_bvh,
)
from choreo.formats.rigs import (
    MIXAMO,
    Rig,
    get_rig,
    read_bvh_rig,
    retarget,
    rig_end_sites,
    rig_motion,
    shortest_arc,
    write_bvh_rig,
)
from choreo.motion import Motion
from choreo.skeleton import SMPL24
from tests.conftest import wandering_dance
from tests.formats.helpers import J, file_forward_kinematics, save

FRAMES, FPS = 40, 30.0
MIXAMO_TREE = {  # bone: parent, Mixamo's standard humanoid without fingers
    "Hips": None, "Spine": "Hips", "Spine1": "Spine", "Spine2": "Spine1", "Neck": "Spine2", "Head": "Neck",
    "LeftShoulder": "Spine2", "LeftArm": "LeftShoulder", "LeftForeArm": "LeftArm", "LeftHand": "LeftForeArm",
    "RightShoulder": "Spine2", "RightArm": "RightShoulder", "RightForeArm": "RightArm", "RightHand": "RightForeArm",
    "LeftUpLeg": "Hips", "LeftLeg": "LeftUpLeg", "LeftFoot": "LeftLeg", "LeftToeBase": "LeftFoot",
    "RightUpLeg": "Hips", "RightLeg": "RightUpLeg", "RightFoot": "RightLeg", "RightToeBase": "RightFoot",
}  # fmt: skip


@pytest.fixture(scope="module")
def motion():
    return wandering_dance(1, FRAMES, FPS)


def written(motion, tmp_path, **options):
    path = tmp_path / "mixamo.bvh"
    with open(path, "wb") as handle:
        write_bvh_rig(motion, handle, "mixamo", **options)
    return path


RIG_ROOT = ("HIERARCHY\nROOT mixamorig:Hips\n{\n\tOFFSET 0.000000 0.000000 0.000000\n"
            "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n")


def hips_under(head: str, above: str, hips_offset: str = "0.000000 0.000000 0.000000") -> str:
    """A rig file's hierarchy with its hips a JOINT (rotations only) below ``above``, the opening
    lines of joints the rig does not name; the caller closes their braces."""
    assert RIG_ROOT in head
    return head.replace(RIG_ROOT, f"HIERARCHY\n{above}JOINT mixamorig:Hips\n{{\n\tOFFSET {hips_offset}\n"
                                  "\tCHANNELS 3 Zrotation Xrotation Yrotation\n", 1)


def bone(name):
    return MIXAMO.bones.index(f"mixamorig:{name}")


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# -- the rig ---------------------------------------------------------------------------------
def test_mixamo_names_and_hierarchy():
    parents = {name.split(":")[1]: (None if p < 0 else MIXAMO.bones[p].split(":")[1])
               for name, p in zip(MIXAMO.bones, MIXAMO.parents)}
    assert parents == MIXAMO_TREE
    assert all(name.startswith("mixamorig:") for name in MIXAMO.bones)
    assert get_rig("Mixamo") is MIXAMO and get_rig("smpl") is None and get_rig(None) is None
    with pytest.raises(ParameterError):
        get_rig("unreal")


@pytest.mark.parametrize("which", ["template", "retargeted"])
def test_rest_pose_is_a_t_pose(motion, which):
    """Arms straight out along +-X, legs straight down -Y, spine straight up, in the template and in what we write."""
    offsets = MIXAMO.offsets if which == "template" else retarget(motion, MIXAMO).offsets
    tips = MIXAMO.end_sites if which == "template" else rig_end_sites(motion, MIXAMO)
    for side, sign in (("Left", 1.0), ("Right", -1.0)):
        for name in ("Arm", "ForeArm", "Hand"):
            np.testing.assert_allclose(unit(offsets[bone(side + name)]), [sign, 0.0, 0.0], atol=1e-9)
        np.testing.assert_allclose(unit(np.asarray(tips[bone(side + "Hand")])), [sign, 0.0, 0.0], atol=1e-9)
        for name in ("Leg", "Foot"):
            np.testing.assert_allclose(unit(offsets[bone(side + name)]), [0.0, -1.0, 0.0], atol=1e-9)
        toe = offsets[bone(side + "ToeBase")]
        assert toe[2] > 0 and toe[1] < 0 and abs(toe[0]) < 1e-9  # forward and down to the ball of the foot
        shoulder = offsets[bone(side + "Shoulder")]
        assert sign * shoulder[0] > 0.04  # collar bones go out to their side
    for name in ("Spine1", "Spine2", "Neck"):
        np.testing.assert_allclose(unit(offsets[bone(name)]), [0.0, 1.0, 0.0], atol=1e-9)


def test_rest_corrections_are_twist_free_turns():
    a, b = np.array([0.0, 1.0, 0.0]), np.array([0.3, 0.9, -0.2])
    rotation = shortest_arc(a, b)
    np.testing.assert_allclose(rotation @ a, unit(b), atol=1e-12)
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(rotation @ np.cross(a, b), np.cross(a, b), atol=1e-12)  # the turn's axis stays
    np.testing.assert_allclose(shortest_arc(a, -a) @ a, -a, atol=1e-12)


def test_smpl_rest_shows_as_smpl_rest_on_the_t_posed_rig():
    """SMPL's rest (arms a little down, collars up) is a pose on the rig, not the rig's rest: the correction is real."""
    rest = Motion.rest(1)
    on_rig = rig_motion(rest, MIXAMO)
    np.testing.assert_allclose(on_rig.joint_positions()[0], rest.joint_positions()[0][list(MIXAMO.smpl_joints)],
                               atol=1e-12)
    collar = on_rig.rotation_matrices()[0, bone("LeftShoulder")]
    assert np.degrees(np.arccos((np.trace(collar) - 1) / 2)) > 10  # SMPL's collars rise; Mixamo's are level


# -- the round trip ----------------------------------------------------------------------------
def test_round_trip_keeps_every_joint_position(motion, tmp_path):
    path = written(motion, tmp_path)
    raw = read_bvh_raw(path)
    assert [joint.name for joint in raw.joints] == list(MIXAMO.bones)  # bone order is the rig's (depth first)
    back = read_bvh_rig(path)
    assert back.num_frames == FRAMES and back.fps == FPS and back.skeleton.same_topology(SMPL24)
    error = np.abs(back.joint_positions() - motion.joint_positions()).max()
    assert error < 1e-4  # 0.1 mm: the file's 6 decimals; hand tips come back from the End Sites
    np.testing.assert_allclose(back.skeleton.bone_lengths(), motion.skeleton.bone_lengths(), atol=1e-5)


def test_round_trip_on_the_rigs_own_lengths_keeps_every_bone_direction(motion, tmp_path):
    """With Mixamo's lengths, bones point where SMPL's do: rebuilt with SMPL's lengths, joints are within 1 cm."""
    path = written(motion, tmp_path, lengths="rig")
    back = read_bvh_rig(path)
    np.testing.assert_allclose(read_bvh_raw(path).joints[bone("LeftForeArm")].offset,
                               MIXAMO.offsets[bone("LeftForeArm")], atol=1e-6)  # the rig's lengths were written
    ours, theirs = motion.joint_positions(), back.joint_positions()
    scale = np.linalg.norm(theirs[:, 1:] - theirs[:, [SMPL24.parents[j] for j in range(1, 24)]], axis=-1) / \
        motion.skeleton.bone_lengths()[1:]
    assert np.ptp(scale) > 0.2  # the lengths did change, bone by bone
    rebuilt = np.zeros_like(ours)
    root_scale = np.linalg.norm(theirs[:, 0] - theirs[0, 0], axis=-1)[1:] / np.linalg.norm(ours[:, 0] - ours[0, 0], axis=-1)[1:]
    rebuilt[:, 0] = theirs[:, 0] / float(np.median(root_scale))
    for j in range(1, 24):
        p = SMPL24.parents[j]
        rebuilt[:, j] = rebuilt[:, p] + unit(theirs[:, j] - theirs[:, p]) * motion.skeleton.bone_lengths()[j]
    assert np.abs(rebuilt - ours).max() < 0.01


def test_reader_refuses_other_skeletons_and_writer_other_rigs(motion, tmp_path):
    smpl_file = tmp_path / "smpl.bvh"
    with open(smpl_file, "wb") as handle:
        write_bvh(motion, handle)
    with pytest.raises(MotionFormatError, match="mixamo"):
        read_bvh_rig(smpl_file)
    with pytest.raises(ParameterError):
        write_bvh_rig(motion, io.BytesIO(), "nonesuch")
    with pytest.raises(ParameterError):
        write_bvh_rig(motion, io.BytesIO(), "mixamo", lengths="cubits")


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


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
def test_a_rig_keeps_its_offsets_as_a_float_table():
    rig = two_bone_rig()
    assert isinstance(rig.offsets, np.ndarray) and rig.offsets.dtype == np.float64 and rig.offsets.shape == (2, 3)
    np.testing.assert_array_equal(rig.offsets, [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    assert rig.bone_of(3) == 1 and rig.children(0) == [1]


@pytest.mark.survivor
@pytest.mark.parametrize("changes", [
    dict(parents=(-1,)), dict(smpl_joints=(0,)), dict(aims=(3,)), dict(parents=(-1, 0, 1)), dict(aims=(3, -1, -1)),
])
def test_a_rig_needs_one_of_everything_per_bone(changes):
    with pytest.raises(ValueError, match="^a rig needs one parent, SMPL joint and aim per bone$"):
        two_bone_rig(**changes)


@pytest.mark.survivor
@pytest.mark.parametrize("changes", [dict(smpl_joints=(0, 4)), dict(smpl_joints=(3, 6))])
def test_a_rig_bone_must_carry_its_parents_child_joint(changes):
    with pytest.raises(ValueError, match=r"^(waist|root): its SMPL joint's parent is not its parent's joint$"):
        two_bone_rig(**changes)


@pytest.mark.survivor
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


def without_end_site(text: str, bone: str) -> str:
    """The file with ``bone``'s End Site block (4 lines) removed."""
    lines = text.split("\n")
    start = next(k for k, line in enumerate(lines) if line.strip() == f"JOINT {bone}")
    site = next(k for k in range(start, len(lines)) if lines[k].strip() == "End Site")
    return "\n".join(lines[:site] + lines[site + 4:])


@pytest.mark.survivor
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


@pytest.mark.survivor
def test_rig_file_without_hand_tips_takes_smpls_template_hands(dance, tmp_path):
    text = without_end_site(without_end_site(rig_text(dance), "mixamorig:LeftHand"), "mixamorig:RightHand")
    back = read_bvh_rig(save(tmp_path, text), MIXAMO)
    offsets = dance.skeleton.offsets.copy()
    offsets[[J["l_hand"], J["r_hand"]]] = SMPL24.offsets[[J["l_hand"], J["r_hand"]]]
    np.testing.assert_allclose(back.skeleton.offsets, offsets, atol=1e-5)
    np.testing.assert_allclose(back.joint_positions(), dance.with_skeleton(SMPL24.with_offsets(offsets)).joint_positions(),
                               atol=1e-4)


@pytest.mark.survivor
def test_rig_file_may_wrap_the_hips_in_a_root_it_does_not_name(dance, tmp_path):
    """An exporter's extra root (no rotation, no offset) carrying the hips' positions changes nothing."""
    text = rig_text(dance)
    head, motion_part = text.split("MOTION", 1)
    head = hips_under(head, "ROOT Armature\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n")
    assert head.count("Armature") == 1
    back = read_bvh_rig(save(tmp_path, head + "}\nMOTION" + motion_part), "mixamo")
    np.testing.assert_allclose(back.joint_positions(), dance.joint_positions(), atol=1e-4)


@pytest.mark.survivor
def test_rig_file_keeps_a_turned_and_offset_root_above_the_hips(dance, tmp_path):
    """A Blender-style "Armature" above the hips, offset and turned (here 90 degrees about x, a
    change of up axis, then a yaw that changes per frame), is composed in: every joint lands where
    the file's own forward kinematics puts it (it used to be dropped, up to 1.3 m off)."""
    text = rig_text(dance)
    head, motion_part = text.split("MOTION", 1)
    head = hips_under(head, "ROOT Armature\n{\nOFFSET 0.5 0 -0.25\n"
                      "CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n", "0.1 0.2 0.3") + "}\n"
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


@pytest.mark.survivor
def test_rig_file_bone_names_need_no_prefix_and_no_case(dance, tmp_path):
    text = rig_text(dance).replace("mixamorig:", "").replace("LeftForeArm", "leftforearm").replace("Hips", "HIPS")
    back = read_bvh_rig(save(tmp_path, text), "mixamo")
    np.testing.assert_allclose(back.joint_positions(), dance.joint_positions(), atol=1e-4)


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
def test_rig_file_frame_rates(dance, tmp_path):
    text = rig_text(dance[:1])
    head, rest = text.split("Frame Time:", 1)
    row = rest.split("\n", 1)[1]
    for frame_time, fps in (("0.03333333", 30.0), ("0.03", 100.0 / 3.0), ("0.01666667", 60.0)):
        back = read_bvh_rig(save(tmp_path, f"{head}Frame Time: {frame_time}\n{row}"), "mixamo")
        assert back.num_frames == 1
        assert back.fps == pytest.approx(fps, abs=1e-9)
        assert (back.fps == round(back.fps)) == (fps == round(fps))


@pytest.mark.survivor
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


def rest_of_file(data):
    """Rest positions of every joint and End Site of a parsed BVH (all rotations zero), by a literal walk."""
    points, at = [], {}
    for j, joint in enumerate(data.joints):
        at[j] = (at[joint.parent] if joint.parent >= 0 else np.zeros(3)) + (joint.offset if joint.parent >= 0 else 0.0)
        points.append(at[j])
        if joint.end_site is not None:
            points.append(at[j] + joint.end_site)
    return np.array(points)


@pytest.mark.survivor
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


# -- retargeting helpers ------------------------------------------------------------------------------------------
@pytest.mark.survivor
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


@pytest.mark.survivor
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


def small_dance(frames: int = 4, seed: int = 5, fps: float = 30.0) -> Motion:
    rng = np.random.default_rng(seed)
    axis_angle = rng.normal(scale=0.4, size=(frames, 24, 3))
    root = rng.normal(scale=0.1, size=(frames, 3)) + [0.0, 0.95, 0.0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps, skeleton=SMPL24)


# -- rigs --------------------------------------------------------------------------------------
@pytest.mark.survivor
def test_hip_height_counts_tips_below_the_joints():
    """rigs._hip_height mutants 9 and 11: height of the root above the lowest joint or End Site tip."""
    parents = (-1, 0)
    offsets = np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    assert rigs._hip_height(parents, offsets, {1: np.array([0.0, -0.25, 0.0])}) == 1.25
    assert rigs._hip_height(parents, offsets, {0: np.array([0.0, 0.5, 0.0])}) == 1.0  # a tip above: the joint


@pytest.mark.survivor
def test_shortest_arc_turns_by_a_tiny_angle_exactly():
    """rigs.shortest_arc mutant 19: a cross product of norm exactly 1e-12 is a rotation, not the identity."""
    a, b = np.array([1.0, 0.0, 0.0]), np.array([1.0, 1e-12, 0.0])
    turn = shortest_arc(a, b)
    np.testing.assert_array_equal(turn @ a, b)
    assert turn[1, 0] == 1e-12 and turn[0, 1] == -1e-12


def half_turn(axis) -> np.ndarray:
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return 2.0 * np.outer(k, k) - np.eye(3)


@pytest.mark.survivor
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


def rig_file_text(motion: Motion) -> str:
    buffer = io.BytesIO()
    write_bvh_rig(motion, buffer, "mixamo")
    return buffer.getvalue().decode()


@pytest.mark.survivor
def test_rig_bone_names_match_ignoring_ascii_case_only(tmp_path):
    """rigs._match_bones mutant 2 (names upper-cased instead of lower-cased): a dotless i is not an i."""
    path = tmp_path / "dotless.bvh"
    text = rig_file_text(small_dance()).replace("mixamorig:Hips", "mixamorig:H\u0131ps")
    path.write_text(text, encoding="utf-8")
    with pytest.raises(MotionFormatError) as raised:
        read_bvh_rig(path, "mixamo")
    assert str(raised.value) == f"{path}: not a mixamo skeleton (no joint named mixamorig:Hips)"


@pytest.mark.survivor
def test_rig_file_composes_two_joints_above_the_hips(tmp_path):
    """bvh.in_world (was rigs._hips_in_world) mutants 12 and 15: with two unnamed joints above the hips (a turned root
    and a turned, offset child), both transforms are composed in, the file's root first."""
    dance = small_dance(frames=3)
    head, motion_part = rig_file_text(dance).split("MOTION", 1)
    head = hips_under(head, "ROOT Armature\n{\nOFFSET 0.5 0 -0.25\n"
                      "CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n"
                      "JOINT Rig\n{\nOFFSET 0.2 -0.1 0.4\nCHANNELS 3 Zrotation Xrotation Yrotation\n",
                      "0.1 0.2 0.3") + "}\n}\n"
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


def test_root_motion_on_the_rig_puts_a_root_bone_above_the_hips(motion, tmp_path):
    path = written(motion, tmp_path, root_motion=True)
    raw = read_bvh_raw(path)
    assert [joint.name for joint in raw.joints] == ["root", *MIXAMO.bones]
    assert raw.joints[1].parent == 0 and len(raw.joints[1].channels) == 6
    positions, _ = file_forward_kinematics(raw)
    ours = motion.joint_positions()
    for b, name in enumerate(MIXAMO.bones, start=1):
        assert np.abs(positions[b] - ours[:, MIXAMO.smpl_joints[b - 1]]).max() < 1e-4, name
    assert np.ptp(positions[0][:, 1]) < 1e-9  # the root bone keeps to the floor
    back = read_bvh_rig(path)
    assert np.abs(back.joint_positions() - ours).max() < 1e-4


@pytest.mark.hardening
def test_the_mixamo_bvh_is_written_a_chunk_of_frames_at_a_time(tmp_path, monkeypatch):
    """Round five, item 8: the Mixamo BVH writer retargeted the whole dance at once (its rotation
    matrices, twice, and their products): a 10-minute dance at 240 fps took 1.51 GB. Retargeted a
    chunk of frames at a time, it holds about what the plain writer holds, byte for byte as before."""
    import choreo.formats.bvh as bvh
    import choreo.formats.rigs as rigs
    from choreo.formats.bvh import write_bvh
    from tests.formats.hostile import hostile_dance, peak_bytes

    motion = hostile_dance(3000)
    whole = [slice(0, 3000)]
    for module in (bvh, rigs):  # as it was: every frame at once
        monkeypatch.setattr(module, "frame_chunks", lambda frames: whole)
    with open(tmp_path / "once.bvh", "wb") as out:
        at_once = peak_bytes(write_bvh_rig, motion, out, "mixamo")
    for module in (bvh, rigs):
        monkeypatch.setattr(module, "frame_chunks", lambda frames: (slice(s, s + 128) for s in range(0, frames, 128)))
    with open(tmp_path / "dance.bvh", "wb") as out, open(tmp_path / "plain.bvh", "wb") as plain:
        streamed = peak_bytes(write_bvh_rig, motion, out, "mixamo")
        smpl = peak_bytes(write_bvh, motion, plain)
    assert (tmp_path / "dance.bvh").read_bytes() == (tmp_path / "once.bvh").read_bytes()
    assert streamed < at_once / 3 and streamed < 2 * smpl
