"""BVH (Biovision Hierarchy) for the SMPL-24 skeleton.

What we write, and what Blender's importer (default settings) turns into a human-sized dancer:
- axes: Y up, +Z forward (the direction the body faces in the rest pose), +X the body's left,
  right-handed; Blender's importer converts Y-up files to its Z-up world itself;
- units: metres by default (Blender units are metres, so scale 1.0 gives a 1.7 m figure);
  ``units="cm"`` writes centimetres, as many mocap tools expect;
- channels: root ``Xposition Yposition Zposition Zrotation Xrotation Yrotation``, every other
  joint ``Zrotation Xrotation Yrotation``; angles in degrees, intrinsic, so the joint's local
  rotation is Rz @ Rx @ Ry; the rest pose is the SMPL template (all rotations zero).
The reader accepts any well-formed BVH (any channel order per joint, End Sites) and maps joints
named as in SMPL (pelvis, l_hip, ... ; also L_Hip, left_hip, m_avg_L_Hip) onto SMPL-24 in whatever
order the file lists them. Units are detected from the skeleton's size (see :func:`detect_scale`).
"""

from __future__ import annotations

import io
import itertools
import re
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ChoreoNote, MotionFormatError
from ..motion import Motion, source_name
from ..motion.delivery import with_root_bone
from ..motion.motion import frame_chunks
from ..skeleton import (SMPL24, Skeleton, continuous_euler, elementary_rotation, euler_to_matrix, matrix_to_euler,
                        matrix_to_quaternion, quaternion_to_matrix)
from .joints import END_SITES, check_joint_names

ROTATION_ORDER = "ZXY"
UNIT_SCALE = {"m": 1.0, "cm": 100.0}
# Joints a file may stack above the dance's root (a root bone, an exporter's armature, a wrapper or
# two): each is composed in at every frame, and a chain of thousands held gigabytes (5,000 joints
# without channels in a 476 kB file took 780 MB); more is refused, as joints below it are.
MAX_JOINTS_ABOVE = 32
ROOT_TIP = (0.0, 0.0, 0.2)  # a root bone's End Site for Blender (write_tree's root_tip): ahead, on the floor


@dataclass
class BvhJoint:
    name: str
    parent: int
    offset: np.ndarray
    channels: list[str] = field(default_factory=list)
    end_site: np.ndarray | None = None


@dataclass
class BvhData:
    """A parsed BVH file, before any mapping onto a known skeleton."""

    joints: list[BvhJoint]
    frame_time: float
    values: np.ndarray  # (T, total channels) as in the file

    def channel_slices(self) -> list[slice]:
        slices, start = [], 0
        for joint in self.joints:
            slices.append(slice(start, start + len(joint.channels)))
            start += len(joint.channels)
        return slices


# -- writing ---------------------------------------------------------------------------------
def write_bvh(motion: Motion, handle, units: str = "m", root_motion: bool = False, root_tip: bool = False) -> None:
    """Write ``motion`` (SMPL-24 topology) as BVH text to a binary handle; ``root_motion``: under a
    floor-level root bone (choreo.motion.delivery.with_root_bone); ``root_tip``: see :func:`write_tree`."""
    if len(motion.skeleton.names) != 24 or motion.skeleton.parents != SMPL24.parents:
        raise MotionFormatError("BVH export supports the SMPL-24 skeleton only")
    write_tree(motion, handle, units, root_motion=root_motion, root_tip=root_tip)


def write_tree(motion: Motion, handle, units: str = "m", end_sites: dict | None = None, root_motion: bool = False,
               root_tip: bool = False) -> None:
    """Write ``motion`` on its own skeleton as BVH text: the root with position channels (and, with
    ``root_motion``, a root bone above it, the dance's root then moving relative to the bone).
    ``root_tip`` gives the root bone an End Site ahead of it, for Blender alone (the FBX path): its
    importer then points the bone forward, not up at the hips, and its FBX importer does not fuse
    the hips to a bone ending where they start (a fused bone loses its position keys)."""
    if units not in UNIT_SCALE:
        raise MotionFormatError(f"unknown BVH units {units!r} (use m or cm)")
    check_joint_names(motion.skeleton.names, "BVH")
    positions = {0: motion.root_positions}
    if root_motion:
        motion, hips = with_root_bone(motion)
        positions[1] = hips
        end_sites = _leaf_tips(motion.skeleton) if end_sites is None else {j + 1: tip for j, tip in end_sites.items()}
        end_sites = {0: ROOT_TIP, **end_sites} if root_tip else end_sites
    scale = UNIT_SCALE[units]
    text = io.StringIO()
    _write_hierarchy(text, motion.skeleton, scale, end_sites, translated=tuple(positions))
    handle.write(text.getvalue().encode())
    _write_frames(handle, motion, scale, {j: p for j, p in positions.items() if j})


def _leaf_tips(skeleton: Skeleton) -> dict:
    """An End Site per leaf: END_SITES by name, a short bone up otherwise."""
    return {j: END_SITES.get(skeleton.names[j], (0.0, 0.05, 0.0))
            for j in range(len(skeleton.names)) if not skeleton.children(j)}


def _write_hierarchy(out: io.StringIO, skeleton: Skeleton, scale: float, end_sites: dict | None = None,
                     translated: tuple[int, ...] = (0,)) -> None:
    """The HIERARCHY block, children depth first; ``end_sites`` maps a joint index to its End Site
    offset (default: every leaf, from END_SITES by name). Retargeted rigs pass their own. The
    ``translated`` joints get position channels (the root, and a dance's root under a root bone)."""
    end_sites = _leaf_tips(skeleton) if end_sites is None else end_sites
    out.write("HIERARCHY\n")
    rotation_channels = " ".join(f"{axis}rotation" for axis in ROTATION_ORDER)

    def vector(values) -> str:
        rounded = np.round(np.asarray(values, dtype=np.float64) * scale, 6) + 0.0  # + 0.0: no "-0.000000"
        return " ".join(f"{v:.6f}" for v in rounded)

    def write_joint(j: int, depth: int) -> None:
        pad = "\t" * depth
        keyword = "ROOT" if skeleton.parents[j] < 0 else "JOINT"
        out.write(f"{pad}{keyword} {skeleton.names[j]}\n{pad}{{\n")
        out.write(f"{pad}\tOFFSET {vector(skeleton.offsets[j])}\n")
        if j in translated:
            out.write(f"{pad}\tCHANNELS 6 Xposition Yposition Zposition {rotation_channels}\n")
        else:
            out.write(f"{pad}\tCHANNELS 3 {rotation_channels}\n")
        if j in end_sites:  # before any child: where Blender's importer takes a tip for a joint that has both
            out.write(f"{pad}\tEnd Site\n{pad}\t{{\n{pad}\t\tOFFSET {vector(end_sites[j])}\n{pad}\t}}\n")
        for child in skeleton.children(j):
            write_joint(child, depth + 1)
        out.write(f"{pad}}}\n")

    write_joint(0, 0)


def _depth_first_order(skeleton: Skeleton) -> list[int]:
    order, stack = [], [0]
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(skeleton.children(j)))
    return order


def _write_frames(handle, motion: Motion, scale: float, translations: dict[int, np.ndarray] | None = None) -> None:
    """The MOTION block to a binary handle, a chunk of frames at a time: a long dance's rotation
    matrices and text at once would hold gigabytes (the curves stay continuous across chunks).
    ``translations``: (T, 3) positions of joints other than the root that have position channels,
    in their parent's frame (a position channel stands for the offset, as Blender reads it)."""
    order = _depth_first_order(motion.skeleton)  # channels follow the hierarchy's listing order
    translations = translations or {}
    handle.write(f"MOTION\nFrames: {motion.num_frames}\nFrame Time: {1.0 / motion.fps:.8f}\n".encode())
    previous = None
    for frames in frame_chunks(motion.num_frames):
        solved = matrix_to_euler(quaternion_to_matrix(motion.rotations[frames]), ROTATION_ORDER)
        angles = continuous_euler(solved, previous)  # (T, J, 3) radians
        previous = angles[-1]
        degrees = np.degrees(angles)
        columns = [motion.root_positions[frames] * scale]
        for j in order:
            columns += [translations[j][frames] * scale] if j in translations else []
            columns.append(degrees[:, j])
        values = np.concatenate(columns, axis=1)
        text = io.StringIO()
        np.savetxt(text, values, fmt="%.6f", delimiter=" ")
        handle.write(text.getvalue().encode())


# -- reading ---------------------------------------------------------------------------------
def _tokens_with_lines(text: str):
    for number, line in enumerate(text.splitlines(), start=1):
        for token in line.split():
            yield token, number


def read_bvh_raw(path: str | Path) -> BvhData:
    """Parse any BVH file into joints, channels and per-frame values; raises MotionFormatError."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="strict")
    except UnicodeDecodeError:
        raise MotionFormatError(f"{path} is not a BVH text file") from None
    return parse_bvh(text, str(path))


def parse_bvh(text: str, name: str = "BVH") -> BvhData:
    head, sep, motion_part = text.partition("MOTION")
    if not sep:
        raise MotionFormatError(f"{name}: no MOTION section (truncated or not a BVH file)")
    joints = _parse_hierarchy(head, name)
    frame_count, frame_time, first = _parse_motion_header(motion_part, name)
    num_channels = sum(len(j.channels) for j in joints)
    if num_channels == 0 and frame_count:  # its frame rows would be empty lines: nothing can move
        raise MotionFormatError(f"{name}: no joint has CHANNELS, so its {frame_count} frames hold no motion")
    rows = _FrameRows(motion_part, first, text.count("\n", 0, len(head)) + 1, name)
    values = rows.values(frame_count, num_channels)
    if not np.isfinite(values).all():
        bad = int(np.argwhere(~np.isfinite(values))[0, 0])
        raise MotionFormatError(f"{name}: line {rows.line_of(bad)} contains NaN or infinite values")
    return BvhData(joints, frame_time, values)


class _FrameRows:
    """The non-blank lines after a MOTION header, parsed by numpy in one pass: a Python float or
    string per value would take many times the motion's size (an hour at 120 fps, gigabytes)."""

    ROW = re.compile(r"^[ \t\r\f\v]*\S[^\n]*", re.MULTILINE)  # anchored: linear on a line of blanks

    def __init__(self, part: str, first: int, line_offset: int, name: str):
        self.part, self.first, self.line_offset, self.name = part, first, line_offset, name

    def lines(self):
        return (match for match in self.ROW.finditer(self.part, self.first))

    def line_of(self, row: int) -> int:
        """The file's line number of frame row ``row`` (1-based, as editors count)."""
        match = next(itertools.islice(self.lines(), row, None))
        return self.line_offset + self.part.count("\n", 0, match.start())

    def values(self, frame_count: int, num_channels: int) -> np.ndarray:
        """(frame_count, num_channels) float64; a short, ragged or non-numeric block is refused."""
        if frame_count == 0:
            return np.zeros((0, num_channels))
        rows = (match.group() for match in itertools.islice(self.lines(), min(frame_count, sys.maxsize)))
        try:
            values = np.loadtxt(rows, dtype=np.float64, comments=None, ndmin=2)
        except ValueError:
            raise self._first_bad_row(frame_count, num_channels) from None
        if len(values) < frame_count:
            raise MotionFormatError(f"{self.name}: truncated, {len(values)} of {frame_count} frames present")
        if values.shape[1] != num_channels:
            raise MotionFormatError(f"{self.name}: frames have {values.shape[1]} values, expected {num_channels}")
        return values

    def _first_bad_row(self, frame_count: int, num_channels: int) -> MotionFormatError:
        """The one-line error for the first row numpy could not take, found one row at a time."""
        for match in itertools.islice(self.lines(), min(frame_count, sys.maxsize)):
            line = self.line_offset + self.part.count("\n", 0, match.start())
            parts = match.group().split()
            if len(parts) != num_channels:
                return MotionFormatError(f"{self.name}: line {line} has {len(parts)} values, expected {num_channels}")
            try:
                [float(p) for p in parts]
            except ValueError:
                return MotionFormatError(f"{self.name}: line {line} has a non-numeric value")
        return MotionFormatError(f"{self.name}: malformed frame data")


def _parse_hierarchy(head: str, name: str) -> list[BvhJoint]:
    tokens = list(_tokens_with_lines(head))
    if not tokens or tokens[0][0] != "HIERARCHY":
        raise MotionFormatError(f"{name}: not a BVH file (no HIERARCHY header)")
    joints: list[BvhJoint] = []
    stack: list[int] = []  # open joints; -1 marks an open End Site
    i = 1

    def take(count: int) -> list[tuple[str, int]]:
        nonlocal i
        if i + count > len(tokens):
            raise MotionFormatError(f"{name}: hierarchy ends unexpectedly (truncated file?)")
        out = tokens[i: i + count]
        i += count
        return out

    def floats(items, line) -> np.ndarray:
        try:
            values = np.array([float(t) for t, _ in items])
        except ValueError:
            raise MotionFormatError(f"{name}: line {line}: expected numbers") from None
        if not np.isfinite(values).all():
            raise MotionFormatError(f"{name}: line {line}: NaN or infinite offset")
        return values

    while i < len(tokens):
        token, line = tokens[i]
        i += 1
        if token in ("ROOT", "JOINT"):
            (joint_name, _), = take(1)
            if token == "ROOT" and joints:
                raise MotionFormatError(f"{name}: line {line}: more than one ROOT is not supported")
            parent = stack[-1] if stack else -1
            if token == "JOINT" and parent < 0:
                raise MotionFormatError(f"{name}: line {line}: JOINT outside a ROOT")
            joints.append(BvhJoint(joint_name, parent, np.zeros(3)))
            stack.append(len(joints) - 1)
        elif token == "End":
            take(1)  # "Site"
            stack.append(-1)
        elif token == "{":
            continue
        elif token == "}":
            if not stack:
                raise MotionFormatError(f"{name}: line {line}: unbalanced braces")
            stack.pop()
        elif token == "OFFSET":
            offset = floats(take(3), line)
            if not stack:
                raise MotionFormatError(f"{name}: line {line}: OFFSET outside a joint")
            if stack[-1] == -1:
                joints[stack[-2]].end_site = offset
            else:
                joints[stack[-1]].offset = offset
        elif token == "CHANNELS":
            (count_text, _), = take(1)
            try:
                count = int(count_text)
            except ValueError:
                raise MotionFormatError(f"{name}: line {line}: bad channel count {count_text[:40]!r}") from None
            if not 0 <= count <= 6:  # a joint has at most 3 position and 3 rotation channels
                raise MotionFormatError(f"{name}: line {line}: CHANNELS {count} (a joint has 0 to 6)")
            channels = [t.lower() for t, _ in take(count)]
            valid = {f"{axis}{kind}" for axis in "xyz" for kind in ("position", "rotation")}
            if any(c not in valid for c in channels) or not stack or stack[-1] < 0:
                raise MotionFormatError(f"{name}: line {line}: bad CHANNELS declaration")
            joints[stack[-1]].channels = channels
        else:
            raise MotionFormatError(f"{name}: line {line}: unexpected {token[:40]!r} in HIERARCHY")
    if stack:
        raise MotionFormatError(f"{name}: hierarchy is truncated (unclosed braces)")
    if not joints:
        raise MotionFormatError(f"{name}: hierarchy has no joints")
    return joints


def _parse_motion_header(part: str, name: str) -> tuple[int, float, int]:
    """Frames, frame time and where the frame rows start in ``part`` (the text after MOTION)."""
    header = [match for match, _ in zip(_FrameRows.ROW.finditer(part), range(2))]
    if len(header) < 2:
        raise MotionFormatError(f"{name}: MOTION section is truncated")
    frames_match = re.match(r"\s*Frames:\s*(\d+)\s*$", header[0].group())
    time_match = re.match(r"\s*Frame\s+Time:\s*([0-9.eE+-]+)\s*$", header[1].group())
    if not frames_match or not time_match:
        raise MotionFormatError(f"{name}: MOTION section lacks 'Frames:' and 'Frame Time:' lines")
    try:
        frame_time = float(time_match.group(1))
    except ValueError:
        raise MotionFormatError(f"{name}: bad Frame Time {time_match.group(1)[:40]!r}") from None
    if not np.isfinite(frame_time) or not 1e-3 <= frame_time <= 1.0:  # 1 to 1000 fps, as a Motion allows
        raise MotionFormatError(f"{name}: Frame Time {time_match.group(1)} is not between 0.001 and 1 s")
    return int(frames_match.group(1)), frame_time, header[1].end()


# -- mapping onto SMPL-24 --------------------------------------------------------------------
def _normalise_joint_name(name: str) -> str:
    name = name.lower()
    for prefix in ("m_avg_", "f_avg_", "smpl_", "mixamorig:"):
        if name.startswith(prefix):
            name = name[len(prefix):]
    name = re.sub(r"^left[_ ]?", "l_", name)
    name = re.sub(r"^right[_ ]?", "r_", name)
    return re.sub(r"[^a-z0-9]", "", name)


SMPL_NAME_INDEX = {_normalise_joint_name(n): i for i, n in enumerate(SMPL24.names)}


def detect_scale(rest_positions: np.ndarray) -> float:
    """Factor that turns the file's units into metres, judged by the figure's size.

    A human skeleton spans about 1-2 units in metres, 100-200 in centimetres, 1000+ in millimetres.
    """
    extent = float(np.ptp(rest_positions, axis=0).max()) if len(rest_positions) > 1 else 0.0
    if extent > 300.0:
        return 0.001
    if extent > 10.0:
        return 0.01
    return 1.0


def _local_rotations(data: BvhData, warn: bool = True, translated=()) -> tuple[np.ndarray, np.ndarray]:
    """(T, J, 3, 3) local rotations and (T, 3) root positions in file units. Position channels of
    other joints are read by :func:`in_world` for the ``translated`` ones, ignored on the rest."""
    frames = len(data.values)
    rotmats = np.broadcast_to(np.eye(3), (frames, len(data.joints), 3, 3)).copy()
    root = np.tile(data.joints[0].offset, (frames, 1))
    ignored_positions = False
    for j, (joint, channels) in enumerate(zip(data.joints, data.channel_slices())):
        values = data.values[:, channels]
        rotation_axes = [c[0].upper() for c in joint.channels if c.endswith("rotation")]
        rotation_values = np.radians(values[:, [k for k, c in enumerate(joint.channels) if c.endswith("rotation")]])
        if len(rotation_axes) == 3 and len(set(rotation_axes)) == 3:
            rotmats[:, j] = euler_to_matrix(rotation_values, "".join(rotation_axes))
        else:  # unusual files: any number of rotation channels, composed in listed order
            for k, axis in enumerate(rotation_axes):
                rotmats[:, j] = rotmats[:, j] @ elementary_rotation(rotation_values[:, k], axis)
        position_channels = {c[0]: k for k, c in enumerate(joint.channels) if c.endswith("position")}
        if position_channels and j == 0:
            for axis_index, axis in enumerate("xyz"):
                if axis in position_channels:
                    root[:, axis_index] = values[:, position_channels[axis]] + joint.offset[axis_index]
        elif position_channels and j not in translated:
            ignored_positions = True
    if ignored_positions and warn:
        warnings.warn("BVH position channels on non-root joints are ignored (bone offsets are used)", ChoreoNote,
                      stacklevel=2)
    return rotmats, root


def check_joints_above(data: BvhData, joint: int, name: str) -> None:
    """Refuse a file that stacks more than MAX_JOINTS_ABOVE joints above the dance's root ``joint``,
    before anything is computed per frame."""
    count = len(above(data, joint))
    if count > MAX_JOINTS_ABOVE:
        raise MotionFormatError(f"{name}: {count} joints above {data.joints[joint].name[:40]} (choreo composes at most "
                                f"{MAX_JOINTS_ABOVE}: a root bone, an exporter's armature)")


def above(data: BvhData, joint: int) -> list[int]:
    """The file's joints above ``joint``, from its parent up to the file's root."""
    chain = []
    while data.joints[joint].parent >= 0:
        joint = data.joints[joint].parent
        chain.append(joint)
    return chain


def _translation(data: BvhData, joint: int) -> np.ndarray:
    """(T, 3) or (3,): where ``joint`` sits in its parent's frame, in file units: its position
    channels stand for its offset on their axes (as Blender and most tools read them)."""
    offset = np.asarray(data.joints[joint].offset, dtype=np.float64)
    channels = data.joints[joint].channels
    given = {c[0]: k for k, c in enumerate(channels) if c.endswith("position")}
    if not given:
        return offset
    values = data.values[:, data.channel_slices()[joint]]
    return np.stack([values[:, given[axis]] if axis in given else np.full(len(values), offset[a])
                     for a, axis in enumerate("xyz")], axis=-1)


def in_world(data: BvhData, rotations: np.ndarray, root: np.ndarray, joint: int) -> tuple[np.ndarray, np.ndarray]:
    """(T, J, 3, 3) rotations with ``joint``'s own made world, and (T, 3) its world position.

    A dance's root may sit under joints its skeleton does not name: a root bone for game engines'
    root motion, or an exporter's "Armature" (often turned to change the up axis). Their
    transforms are composed into the dance's root, so the dance keeps the file's world pose."""
    chain = [joint, *above(data, joint)]
    if len(chain) == 1:
        return rotations, root
    world, position = rotations[:, chain[-1]], root
    for j in reversed(chain[:-1]):  # from below the file's root down to ``joint``
        translation = np.broadcast_to(_translation(data, j), position.shape)
        position = position + np.einsum("tij,tj->ti", world, translation)
        world = world @ rotations[:, j]
    rotations = rotations.copy()
    rotations[:, joint] = world
    return rotations, position


def _local_quaternions(data: BvhData, dance_root: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(T, J, 4) local rotations and (T, 3) root positions in file units, converted a block of
    frames at a time: the matrices and their intermediates for an hour at 120 fps would take
    gigabytes, the quaternions a few hundred megabytes. ``dance_root``'s is made world, with its
    position (:func:`in_world`)."""
    frames = len(data.values)
    quaternions, root = np.empty((frames, len(data.joints), 4)), np.empty((frames, 3))
    translated = above(data, dance_root)
    for block in frame_chunks(frames):
        part = BvhData(data.joints, data.frame_time, data.values[block])
        rotmats, root[block] = in_world(part, *_local_rotations(part, block.start == 0, translated + [dance_root]), dance_root)
        quaternions[block] = matrix_to_quaternion(rotmats)
    return quaternions, root


def _index_by_tree(data: BvhData) -> dict[int, int] | None:
    """File joint -> SMPL-24 joint when the file holds SMPL-24's tree in the order choreo writes it
    (depth first), whatever the names; None otherwise."""
    order = _depth_first_order(SMPL24)
    if len(data.joints) != len(order):
        return None
    position = {smpl: k for k, smpl in enumerate(order)}
    expected = [-1 if SMPL24.parents[smpl] < 0 else position[SMPL24.parents[smpl]] for smpl in order]
    return dict(enumerate(order)) if [joint.parent for joint in data.joints] == expected else None


def bvh_to_motion(data: BvhData, name: str = "BVH", units: str = "auto") -> Motion:
    """Map a parsed BVH onto SMPL-24 (joint names as in SMPL, any order; or SMPL-24's tree in its
    order under other names, as choreo writes a renamed skeleton); other skeletons fail."""
    index = {}
    for j, joint in enumerate(data.joints):
        key = _normalise_joint_name(joint.name)
        if key in SMPL_NAME_INDEX and SMPL_NAME_INDEX[key] not in index.values():
            index[j] = SMPL_NAME_INDEX[key]
    if len(index) != 24:
        index = _index_by_tree(data) or index
    pelvis = next((j for j, smpl in index.items() if smpl == 0), None)
    if pelvis is not None:
        check_joints_above(data, pelvis, name)
    unnamed = [j for j in range(len(data.joints)) if j not in index]
    if len(index) != 24 or (unnamed and (pelvis is None or sorted(unnamed) != sorted(above(data, pelvis)))):
        listed = ", ".join(j.name for j in data.joints[:6]) + (", ..." if len(data.joints) > 6 else "")
        raise MotionFormatError(
            f"{name}: skeleton is not SMPL-24 (found {len(data.joints)} joints: {listed})")
    joints = sorted(index)  # the file's SMPL joints; any above the pelvis (a root bone) are composed into it
    to_smpl = np.array([index[j] for j in joints])
    for j in joints:
        parent = data.joints[j].parent
        if index.get(parent, -1) != SMPL24.parents[index[j]]:
            raise MotionFormatError(f"{name}: joint {data.joints[j].name} has the wrong parent for SMPL-24")
    quaternions_file, root = _local_quaternions(data, pelvis)
    offsets = np.zeros((24, 3))
    quaternions = np.empty((len(quaternions_file), 24, 4))
    offsets[to_smpl] = np.array([data.joints[j].offset for j in joints])
    offsets[0] = 0.0  # the pelvis's place is in the root's path (its offset and channels added, or composed)
    quaternions[:, to_smpl] = quaternions_file[:, joints]
    del quaternions_file
    skeleton = SMPL24.with_offsets(offsets)
    scale = detect_scale(skeleton.rest_positions()) if units == "auto" else 1.0 / UNIT_SCALE[units]
    skeleton = SMPL24.with_offsets(offsets * scale)
    fps = 1.0 / data.frame_time
    fps = round(fps) if abs(fps - round(fps)) < 1e-3 else fps
    if len(data.values) == 0:
        raise MotionFormatError(f"{name}: no frames")
    return Motion(root * scale, quaternions, fps=float(fps), skeleton=skeleton, metadata={"source": source_name(name)})


def read_bvh(path: str | Path, units: str = "auto") -> Motion:
    """Read a BVH file whose skeleton is SMPL-24 (by joint names) into a Motion in metres."""
    return bvh_to_motion(read_bvh_raw(path), str(path), units)
