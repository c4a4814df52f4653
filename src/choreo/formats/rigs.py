"""Retargeting SMPL-24 dances onto other rigs (Mixamo's), and reading them back.

A rig here is a tree of bones, each carrying one SMPL-24 joint, with its own names and its own rest
pose. Mixamo's rest pose is a T-pose (Y up, facing +Z, +X the character's left, as choreo's): arms
straight out along +-X, legs straight down -Y, spine straight up. SMPL's rest pose is not: its
collar bones rise about 20 degrees, its arms droop a few degrees, its neck leans forward.

How the dance is carried over (world joint directions are preserved exactly):
- every bone b gets a constant *rest correction* D_b, a world-space rotation that turns the rig's
  rest direction of the bone b aims along (its main child, or its hand tip) into the SMPL rest
  direction of the same bone; it is the shortest arc between the two directions, so it adds no twist
  about the bone. Bones that branch or end where both rests agree (the hips, the head, the toes) keep
  SMPL's axes (D_b = identity), so the dancer's facing and the head's and toes' orientations carry
  over as they are;
- world orientations map as G'_b = G_b D_b, so local rotations map as
  L'_b = D_parent^T L_b D_b, and the rig's rest offsets are m_b = D_parent^T o_b (SMPL's offsets
  turned into the T-pose). Then G'_parent m_b = G_parent o_b: every bone points where SMPL's did;
- bone lengths are the dance's own by default (joint positions are then exactly SMPL's), or the
  rig's template lengths with ``lengths="rig"`` (the root's path scaled by the ratio of hip heights).
  Bone *directions* are the same either way.
Joints the rig has no bone for (SMPL's ``l_hand``/``r_hand``, the hand tips) become End Sites.

Reading a rig's BVH back (:func:`read_bvh_rig`) does the inverse onto the SMPL-24 template's rest
directions, so the result is an ordinary SMPL-24 Motion with the same joint positions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import MotionFormatError, ParameterError
from ..motion import Motion, source_name
from ..motion.motion import frame_chunks
from ..skeleton import SMPL24, Skeleton, matrix_to_quaternion, quaternion_to_matrix
from .bvh import UNIT_SCALE, _local_rotations, above, check_joints_above, detect_scale, in_world, read_bvh_raw, write_tree
from .joints import END_SITES

LENGTHS = ("motion", "rig")


@dataclass(frozen=True, eq=False)
class Rig:
    """A target skeleton: bone names and tree, its T-pose rest, and which SMPL-24 joint each bone carries.

    ``offsets`` are template rest offsets in metres (Y up, +Z forward), parents before children;
    their directions define the rig's rest pose, their lengths are used with ``lengths="rig"``.
    ``aims[b]`` is the SMPL-24 joint whose direction from bone b's joint fixes b's rest correction
    (-1: none, b keeps SMPL's axes); when no rig bone carries that joint, ``end_sites[b]`` gives its
    rest direction. ``end_sites`` are template tips past the leaf bones, as BVH End Sites.
    """

    name: str
    bones: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray = field(repr=False)
    smpl_joints: tuple[int, ...]
    aims: tuple[int, ...]
    end_sites: dict[int, tuple[float, float, float]] = field(repr=False)

    def __post_init__(self):
        object.__setattr__(self, "offsets", np.asarray(self.offsets, dtype=np.float64).reshape(len(self.bones), 3))
        if not len(self.bones) == len(self.parents) == len(self.smpl_joints) == len(self.aims):
            raise ValueError("a rig needs one parent, SMPL joint and aim per bone")
        for b, p in enumerate(self.parents):
            expected = -1 if p < 0 else self.smpl_joints[p]
            if SMPL24.parents[self.smpl_joints[b]] != expected:
                raise ValueError(f"{self.bones[b]}: its SMPL joint's parent is not its parent's joint")

    @property
    def skeleton(self) -> Skeleton:
        """The rig as a Skeleton with its template offsets (for forward kinematics)."""
        return Skeleton(self.bones, self.parents, self.offsets)

    def children(self, bone: int) -> list[int]:
        return [b for b, p in enumerate(self.parents) if p == bone]

    def bone_of(self, smpl_joint: int) -> int | None:
        return self.smpl_joints.index(smpl_joint) if smpl_joint in self.smpl_joints else None


def _mixamo() -> Rig:
    """Mixamo's standard humanoid (fingers and the *_End tips omitted), in typical proportions.

    The template lengths are rounded, approximate Mixamo proportions (a 1.8 m character), not
    measured from a particular Mixamo file; directions are the T-pose.
    """
    J = {name: j for j, name in enumerate(SMPL24.names)}
    table = [  # bone, parent, SMPL joint, template offset (m), aim (SMPL joint or None)
        ("Hips", None, "pelvis", (0.0, 0.0, 0.0), None),
        ("Spine", "Hips", "spine1", (0.0, 0.099, 0.012), "spine2"),
        ("Spine1", "Spine", "spine2", (0.0, 0.117, 0.0), "spine3"),
        ("Spine2", "Spine1", "spine3", (0.0, 0.134, 0.0), "neck"),
        ("Neck", "Spine2", "neck", (0.0, 0.150, 0.0), "head"),
        ("Head", "Neck", "head", (0.0, 0.103, 0.031), None),
    ]
    for side, sign in (("Left", 1.0), ("Right", -1.0)):
        s = side[0].lower()
        table += [
            (f"{side}Shoulder", "Spine2", f"{s}_collar", (sign * 0.061, 0.091, 0.008), f"{s}_shoulder"),
            (f"{side}Arm", f"{side}Shoulder", f"{s}_shoulder", (sign * 0.129, 0.0, 0.0), f"{s}_elbow"),
            (f"{side}ForeArm", f"{side}Arm", f"{s}_elbow", (sign * 0.274, 0.0, 0.0), f"{s}_wrist"),
            (f"{side}Hand", f"{side}ForeArm", f"{s}_wrist", (sign * 0.276, 0.0, 0.0), f"{s}_hand"),
        ]
    for side, sign in (("Left", 1.0), ("Right", -1.0)):
        s = side[0].lower()
        table += [
            (f"{side}UpLeg", "Hips", f"{s}_hip", (sign * 0.091, -0.067, -0.002), f"{s}_knee"),
            (f"{side}Leg", f"{side}UpLeg", f"{s}_knee", (0.0, -0.406, 0.0), f"{s}_ankle"),
            (f"{side}Foot", f"{side}Leg", f"{s}_ankle", (0.0, -0.420, 0.0), f"{s}_foot"),
            (f"{side}ToeBase", f"{side}Foot", f"{s}_foot", (0.0, -0.089, 0.107), None),
        ]
    names = [f"mixamorig:{row[0]}" for row in table]
    parents = tuple(-1 if row[1] is None else names.index(f"mixamorig:{row[1]}") for row in table)
    end_sites = {names.index("mixamorig:Head"): (0.0, 0.18, 0.0),
                 names.index("mixamorig:LeftHand"): (0.09, 0.0, 0.0),
                 names.index("mixamorig:RightHand"): (-0.09, 0.0, 0.0),
                 names.index("mixamorig:LeftToeBase"): (0.0, 0.0, 0.08),
                 names.index("mixamorig:RightToeBase"): (0.0, 0.0, 0.08)}
    return Rig("mixamo", tuple(names), parents, np.array([row[3] for row in table]),
               tuple(J[row[2]] for row in table), tuple(-1 if row[4] is None else J[row[4]] for row in table),
               end_sites)


MIXAMO = _mixamo()
RIGS = {"mixamo": MIXAMO}


def get_rig(name: str | Rig | None) -> Rig | None:
    """A rig by name (None or "smpl": no retargeting); unknown names are a ParameterError."""
    if name is None or isinstance(name, Rig):
        return name
    key = name.lower()
    if key == "smpl":
        return None
    if key not in RIGS:
        raise ParameterError(f"unknown rig {name!r} (known: smpl, {', '.join(RIGS)})")
    return RIGS[key]


# -- rest-pose corrections ---------------------------------------------------------------------
def shortest_arc(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3) rotation taking direction a onto direction b about their common normal (no twist).

    A zero vector (a bone of no length) has no direction to turn: the identity, not NaN.
    """
    norm_a, norm_b = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if not (norm_a > 1e-12 and norm_b > 1e-12):
        return np.eye(3)
    a, b = a / norm_a, b / norm_b
    axis = np.cross(a, b)
    s, c = np.linalg.norm(axis), float(np.dot(a, b))
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        # opposite directions: half a turn about any axis perpendicular to a
        helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        axis = np.cross(a, helper)
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    k = axis / s
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def _smpl_tip(smpl_offsets: np.ndarray, joint: int) -> np.ndarray:
    """SMPL offset past joint ``joint`` when the rig has no bone for its child: the child's offset, or the BVH End Site."""
    children = SMPL24.children(joint)
    if children:
        return smpl_offsets[children[0]]
    return np.array(END_SITES.get(SMPL24.names[joint], (0.0, 0.05, 0.0)))


def rest_corrections(smpl_offsets: np.ndarray, rig: Rig, rig_offsets: np.ndarray | None = None,
                     rig_end_sites: dict | None = None) -> np.ndarray:
    """(B, 3, 3) world rotations D_b taking each rig bone's rest direction onto SMPL's.

    ``rig_offsets``/``rig_end_sites`` default to the rig's template (the T-pose); reading a file
    back passes the file's own.
    """
    rig_offsets = rig.offsets if rig_offsets is None else rig_offsets
    rig_end_sites = rig.end_sites if rig_end_sites is None else rig_end_sites
    corrections = np.tile(np.eye(3), (len(rig.bones), 1, 1))
    for b, aim in enumerate(rig.aims):
        if aim < 0:
            continue
        child = rig.bone_of(aim)
        rig_direction = rig_offsets[child] if child is not None else np.asarray(rig_end_sites[b], dtype=float)
        corrections[b] = shortest_arc(rig_direction, smpl_offsets[aim])
    return corrections


# -- retargeting -----------------------------------------------------------------------------
class Retargeted(NamedTuple):
    """A dance on a rig: what a writer needs."""

    root_positions: np.ndarray  # (T, 3) metres
    local_rotations: np.ndarray  # (T, B, 3, 3), the rig's bones, rest = identity
    offsets: np.ndarray  # (B, 3) rest offsets (T-pose), metres


def _rig_rest(skeleton: Skeleton, rig: Rig, lengths: str) -> tuple[np.ndarray, np.ndarray, dict, float]:
    """Corrections, rest offsets, end sites and the root's scale for ``skeleton`` on ``rig``."""
    if lengths not in LENGTHS:
        raise ParameterError(f"unknown lengths {lengths!r} (use {' or '.join(LENGTHS)})")
    if not skeleton.same_topology(SMPL24):
        raise MotionFormatError("retargeting needs a motion on the SMPL-24 skeleton")
    corrections = rest_corrections(skeleton.offsets, rig)
    offsets = np.zeros((len(rig.bones), 3))
    for b, p in enumerate(rig.parents):
        if p >= 0:
            offsets[b] = corrections[p].T @ skeleton.offsets[rig.smpl_joints[b]]
    end_sites = {b: corrections[b].T @ _smpl_tip(skeleton.offsets, rig.smpl_joints[b]) for b in rig.end_sites}
    root_scale = 1.0
    if lengths == "rig":
        hip_height = _hip_height(rig.parents, offsets, end_sites)
        offsets = _with_lengths(offsets, rig.offsets)
        end_sites = {b: _with_lengths(v[None], np.asarray(rig.end_sites[b])[None])[0] for b, v in end_sites.items()}
        if not (np.isfinite(hip_height) and hip_height > 1e-6):  # the root path is divided by it
            raise MotionFormatError("the motion's legs have no length (the hips are not above the feet): "
                                    "cannot scale its root path to the rig's")
        root_scale = _hip_height(rig.parents, offsets, end_sites) / hip_height
    return corrections, offsets, end_sites, root_scale


def _with_lengths(vectors: np.ndarray, templates: np.ndarray) -> np.ndarray:
    """``vectors``' directions with ``templates``' lengths."""
    norms = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return vectors / np.maximum(norms, 1e-12) * np.linalg.norm(templates, axis=-1, keepdims=True)


def _hip_height(parents, offsets: np.ndarray, end_sites: dict) -> float:
    """Height of the root above the lowest joint or tip in the rest pose: how far the root's path scales."""
    positions = np.zeros_like(offsets)
    for b, p in enumerate(parents):
        if p >= 0:
            positions[b] = positions[p] + offsets[b]
    tips = [positions[b] + tip for b, tip in end_sites.items()]
    return float(-np.min(np.concatenate([positions, np.array(tips).reshape(-1, 3)])[:, 1]))


def retarget(motion: Motion, rig: Rig | str, lengths: str = "motion") -> Retargeted:
    """Carry an SMPL-24 ``motion`` onto ``rig``: root path, local rotations (rig rest = identity), rest offsets.

    World bone directions are SMPL's at every frame; with ``lengths="motion"`` so are joint positions.
    """
    rig = get_rig(rig)
    if rig is None:
        raise ParameterError("retarget needs a rig other than SMPL-24")
    corrections, offsets, _, root_scale = _rig_rest(motion.skeleton, rig, lengths)
    local = np.empty((motion.num_frames, len(rig.bones), 3, 3))
    for chunk in frame_chunks(motion.num_frames):
        local[chunk] = _rig_local(motion.rotations[chunk], rig, corrections)
    return Retargeted(motion.root_positions * root_scale, local, offsets)


def _rig_local(rotations: np.ndarray, rig: Rig, corrections: np.ndarray) -> np.ndarray:
    """(T, B, 3, 3) the rig's local rotations (rest = identity) for (T, 24, 4) SMPL-24 ones."""
    local = quaternion_to_matrix(rotations[:, list(rig.smpl_joints)])  # (T, B, 3, 3)
    parent_corrections = np.stack([np.eye(3) if p < 0 else corrections[p] for p in rig.parents])
    return np.swapaxes(parent_corrections, -1, -2) @ local @ corrections


def rig_end_sites(motion: Motion, rig: Rig | str, lengths: str = "motion") -> dict[int, np.ndarray]:
    """Rest End Site offsets of the rig's leaf bones (hand tips where SMPL has them), metres."""
    return _rig_rest(motion.skeleton, get_rig(rig), lengths)[2]


def rig_motion(motion: Motion, rig: Rig | str, lengths: str = "motion") -> Motion:
    """The retargeted dance as a Motion on the rig's skeleton (names, tree, T-pose offsets)."""
    rig = get_rig(rig)
    corrections, offsets, _, root_scale = _rig_rest(motion.skeleton, rig, lengths)
    quaternions = np.empty((motion.num_frames, len(rig.bones), 4))
    for chunk in frame_chunks(motion.num_frames):  # a long dance's matrices at once would take gigabytes
        quaternions[chunk] = matrix_to_quaternion(_rig_local(motion.rotations[chunk], rig, corrections))
    skeleton = Skeleton(rig.bones, rig.parents, offsets)
    return Motion(motion.root_positions * root_scale, quaternions, fps=motion.fps, skeleton=skeleton,
                  metadata={**motion.metadata, "rig": rig.name})


# -- BVH on a rig --------------------------------------------------------------------------------
def write_bvh_rig(motion: Motion, handle, rig: Rig | str = "mixamo", units: str = "m", lengths: str = "motion",
                  root_motion: bool = False, root_tip: bool = False) -> None:
    """Write an SMPL-24 ``motion`` retargeted onto ``rig`` as BVH text (rig names, T-pose offsets) to
    a binary handle; ``root_motion``: under a floor-level root bone (``root_tip``: bvh.write_tree's)."""
    if units not in UNIT_SCALE:
        raise MotionFormatError(f"unknown BVH units {units!r} (use m or cm)")
    rig = get_rig(rig)
    write_tree(rig_motion(motion, rig, lengths), handle, units, rig_end_sites(motion, rig, lengths), root_motion, root_tip)


def _match_bones(data, rig: Rig, name: str) -> list[int]:
    """File joint index of every rig bone (names with or without the rig's prefix, any case); checks the tree."""
    def key(text: str) -> str:
        return text.lower().split(":")[-1]

    by_key = {}
    for j, joint in enumerate(data.joints):
        by_key.setdefault(key(joint.name), j)
    missing = [bone for bone in rig.bones if key(bone) not in by_key]
    if missing:
        raise MotionFormatError(f"{name}: not a {rig.name} skeleton (no joint named {missing[0]})")
    index = [by_key[key(bone)] for bone in rig.bones]
    for b, p in enumerate(rig.parents):
        if (data.joints[index[b]].parent if p >= 0 else -1) != (index[p] if p >= 0 else -1):
            raise MotionFormatError(f"{name}: joint {rig.bones[b]} has the wrong parent for a {rig.name} rig")
    return index


def read_bvh_rig(path: str | Path, rig: Rig | str = "mixamo", units: str = "auto") -> Motion:
    """Read a BVH on ``rig`` (as :func:`write_bvh_rig` writes, or any with the rig's bone names) as an SMPL-24 Motion.

    Rotations are re-expressed against the SMPL-24 template's rest directions (the inverse of the
    rest correction), so joint positions are the file's; SMPL's hand tips come from the hands' End
    Sites (or the template's, when the file has none). Joints the rig does not name are ignored, but
    the transforms of those above the hips are composed into the hips'.
    """
    rig = get_rig(rig)
    data = read_bvh_raw(path)
    index = _match_bones(data, rig, str(path))
    check_joints_above(data, index[0], str(path))
    if len(data.values) == 0:
        raise MotionFormatError(f"{path}: no frames")
    rotmats_file, root = _local_rotations(data, translated=[index[0], *above(data, index[0])])
    rotmats_file, root = in_world(data, rotmats_file, root, index[0])
    local = rotmats_file[:, index]
    offsets = np.array([data.joints[j].offset for j in index])
    offsets[0] = 0.0
    end_sites = {b: data.joints[index[b]].end_site for b in rig.end_sites if data.joints[index[b]].end_site is not None}
    scale = detect_scale(Skeleton(rig.bones, rig.parents, offsets).rest_positions()) if units == "auto" \
        else 1.0 / UNIT_SCALE[units]
    offsets, root = offsets * scale, root * scale
    end_sites = {b: v * scale for b, v in end_sites.items()}
    template_tips = {b: np.asarray(rig.end_sites[b]) for b in rig.end_sites}
    corrections = rest_corrections(SMPL24.offsets, rig, offsets, {**template_tips, **end_sites})
    smpl_offsets = SMPL24.offsets.copy()
    smpl_local = np.broadcast_to(np.eye(3), (len(local), 24, 3, 3)).copy()
    for b, p in enumerate(rig.parents):
        parent_correction = np.eye(3) if p < 0 else corrections[p]
        smpl_local[:, rig.smpl_joints[b]] = parent_correction @ local[:, b] @ corrections[b].T
        if p >= 0:
            smpl_offsets[rig.smpl_joints[b]] = parent_correction @ offsets[b]
    for b in rig.end_sites:  # SMPL joints past the rig's leaves that the rig has no bone for (hand tips)
        for child in SMPL24.children(rig.smpl_joints[b]):
            tip = end_sites.get(b)
            smpl_offsets[child] = corrections[b] @ tip if tip is not None else SMPL24.offsets[child]
    fps = 1.0 / data.frame_time
    fps = round(fps) if abs(fps - round(fps)) < 1e-3 else fps
    return Motion.from_rotation_matrices(root, smpl_local, fps=float(fps), skeleton=SMPL24.with_offsets(smpl_offsets),
                                         metadata={"source": source_name(path), "rig": rig.name})
