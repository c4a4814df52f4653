"""Retargeting onto Mixamo's rig: its rest pose is a T-pose, and the dance survives the round trip.

Round trip: retarget, write BVH on the rig, read the file back onto SMPL-24, compare joint
positions to the original's: exactly (bone lengths kept), or bone by bone after bone-length
normalisation (the rig's own lengths).
"""

import io

import numpy as np
import pytest
from conftest import wandering_dance

from choreo.errors import MotionFormatError, ParameterError
from choreo.formats import read_bvh_raw, write_bvh
from choreo.formats.rigs import (MIXAMO, get_rig, read_bvh_rig, retarget, rig_end_sites, rig_motion, shortest_arc,
                                 write_bvh_rig)
from choreo.motion import Motion
from choreo.skeleton import SMPL24

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
