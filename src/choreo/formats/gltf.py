"""glTF 2.0 binary (.glb): the SMPL-24 skeleton as a skin, a simple skinned body, the dance as its animation.

What we write, so that three.js, Godot, Blender and the Khronos validator read it as we mean it:
- axes and units as glTF defines them, which are already choreo's: Y up, +Z forward (where the
  body faces), +X the body's left, right-handed, metres;
- nodes 0-23: the SMPL-24 joints, named as in SMPL, each translated by its rest offset from its
  parent (node 0, the pelvis, is a scene root: its translation is the root's world position);
  with root motion, node 0 is a root bone at floor level and the joints follow it (the pelvis,
  node 1, then moves relative to it);
- the next node: the body, one mesh skinned to those joints: a tapered eight-sided spindle per bone, each
  vertex rigidly bound (weight 1) to the bone's parent joint; the bind pose is the rest pose
  standing on the floor;
- one animation, "dance": every joint's local rotation (quaternions x, y, z, w, LINEAR) and the
  pelvis's translation (and the root bone's), keyed at every frame, i / fps seconds.
:func:`read_glb` reads such files back (joints found by name; one key per frame; nodes above the
pelvis, such as a root bone, composed into it).
"""

from __future__ import annotations

import json
import os
import struct
from pathlib import Path

import numpy as np

from ..errors import MotionFormatError, ParameterError
from ..fileio import json_safe
from ..motion import Motion, source_name
from ..motion.delivery import ROOT_BONE, with_root_bone
from ..motion.motion import file_metadata
from ..skeleton import SMPL24, matrix_to_quaternion, quaternion_to_matrix
from .joints import END_SITES, check_joint_names

BODY_SIDES = 8  # a spindle's cross-section: enough to read as a limb, few enough to stay small
BONE_RADIUS = 0.035  # metres at a bone's thickest point; thin bones (hands, feet) get less
BODY_COLOUR = (0.85, 0.55, 0.35, 1.0)
ANIMATION_NAME = "dance"
# JSON objects a glb may hold: choreo's hold 175, a rigged character with dozens of clips a few
# thousand. pygltflib decodes each slowly (a forged file of 100,000 channels on one accessor: 20 s).
MAX_JSON_OBJECTS = 20_000
GLB_HEADER, JSON_CHUNK = 20, 0x4E4F534A


def _gltf():
    """pygltflib, imported late so that choreo runs without it until a glb is asked for."""
    try:
        import pygltflib
    except ImportError:
        raise MotionFormatError("glTF needs the pygltflib package (pip install pygltflib)") from None
    return pygltflib


# -- writing ---------------------------------------------------------------------------------
def write_glb(motion: Motion, handle, root_motion: bool = False) -> None:
    """Write ``motion`` (SMPL-24 topology) as a binary glTF to a binary handle; ``root_motion``:
    under a floor-level root bone (choreo.motion.delivery.with_root_bone), a joint of the skin."""
    if len(motion.skeleton.names) != 24 or motion.skeleton.parents != SMPL24.parents:
        raise MotionFormatError("glTF export supports the SMPL-24 skeleton only")
    check_joint_names(motion.skeleton.names, "glTF")
    translations = {0: motion.root_positions}
    if root_motion:
        motion, translations[1] = with_root_bone(motion)
        translations[0] = motion.root_positions
    gl = _gltf()
    buffer = _BufferBuilder(gl)
    skeleton = motion.skeleton
    count = skeleton.num_joints
    floor_height = -skeleton.rest_positions()[:, 1].min()
    bind_positions = skeleton.rest_positions() + [0.0, floor_height, 0.0]
    nodes = _joint_nodes(gl, skeleton, floor_height)
    mesh = _body_mesh(gl, buffer, skeleton, bind_positions)
    inverse_bind = np.tile(np.eye(4), (count, 1, 1))
    inverse_bind[:, :3, 3] = -bind_positions
    # glTF matrices are column-major: the transpose of numpy's row-major layout
    skin = gl.Skin(name="SMPL-24", joints=list(range(count)), skeleton=0,
                   inverseBindMatrices=buffer.add(inverse_bind.transpose(0, 2, 1).reshape(count, 16), "MAT4"))
    nodes.append(gl.Node(name="body", mesh=0, skin=0))
    animations = [_animation(gl, buffer, motion, translations)] if motion.num_frames else []
    document = gl.GLTF2(
        asset=gl.Asset(version="2.0", generator="choreo"),
        scene=0, scenes=[gl.Scene(name="dancer", nodes=[0, count])],
        nodes=nodes, meshes=[mesh], skins=[skin], animations=animations,
        materials=[gl.Material(name="body", pbrMetallicRoughness=gl.PbrMetallicRoughness(
            baseColorFactor=list(BODY_COLOUR), metallicFactor=0.0, roughnessFactor=0.8))],
        accessors=buffer.accessors, bufferViews=buffer.views, buffers=[gl.Buffer(byteLength=len(buffer.data))],
        extras={"fps": float(motion.fps), "metadata": _json_metadata(motion.metadata)},
    )
    document.set_binary_blob(bytes(buffer.data))
    handle.write(b"".join(document.save_to_bytes()))


def _json_metadata(metadata: dict) -> dict:
    """``metadata`` as strict JSON values, which is all pygltflib writes: NaN and infinities (that an
    NPZ's or a JSON's metadata may hold) become null, anything else not JSON its text."""
    return json.loads(json.dumps(json_safe(metadata), default=str), parse_constant=lambda constant: None)


class _BufferBuilder:
    """Packs arrays into the one binary buffer a glb carries, each in its own 4-byte aligned view."""

    def __init__(self, gl):
        self.gl = gl
        self.data = bytearray()
        self.views: list = []
        self.accessors: list = []

    def add(self, array: np.ndarray, kind: str, target: int | None = None, bounds: bool = False) -> int:
        """Append ``array`` (float32 unless it is unsigned bytes) and return its accessor's index."""
        gl = self.gl
        array = np.ascontiguousarray(array if array.dtype == np.uint8 else array.astype(np.float32))
        component = gl.UNSIGNED_BYTE if array.dtype == np.uint8 else gl.FLOAT
        self.data.extend(b"\0" * (-len(self.data) % 4))
        self.views.append(gl.BufferView(buffer=0, byteOffset=len(self.data), byteLength=array.nbytes, target=target))
        self.data.extend(array.tobytes())
        flat = array.reshape(len(array), -1)
        accessor = gl.Accessor(bufferView=len(self.views) - 1, componentType=component, count=len(array), type=kind)
        if bounds:  # required on positions and animation inputs
            accessor.min = flat.min(axis=0).astype(float).tolist()
            accessor.max = flat.max(axis=0).astype(float).tolist()
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def _joint_nodes(gl, skeleton, floor_height: float) -> list:
    """One node per joint, children listed, at rest (identity rotations) standing on the floor."""
    nodes = []
    for j, name in enumerate(skeleton.names):
        translation = [0.0, float(floor_height), 0.0] if j == 0 else skeleton.offsets[j].tolist()
        nodes.append(gl.Node(name=name, translation=translation, children=skeleton.children(j) or None))
    return nodes


def _bone_segments(skeleton, bind_positions: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """(start, end, joint that carries it) per body part: each bone, plus a head, hands and feet past the leaves."""
    segments = [(bind_positions[p], bind_positions[j], p) for j, p in enumerate(skeleton.parents)
                if p >= 0 and skeleton.names[p] != ROOT_BONE]  # a root bone is no part of the body
    for j, name in enumerate(skeleton.names):
        if not skeleton.children(j):
            tip = np.array(END_SITES.get(name, (0.0, 0.05, 0.0)))
            segments.append((bind_positions[j], bind_positions[j] + tip * (1.6 if name == "head" else 1.0), j))
    return segments


def _spindle(start: np.ndarray, end: np.ndarray, radius: float) -> np.ndarray:
    """(N, 3, 3) triangles of a double cone around start-end, widest a third of the way along."""
    axis = end - start
    length = float(np.linalg.norm(axis))
    # a bone of no length (a BVH with zero offsets) has no direction: any will do for a point-sized spindle
    direction = axis / length if length > 1e-6 else np.array([0.0, 1.0, 0.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(direction[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(direction, helper)
    u /= np.linalg.norm(u)
    v = np.cross(direction, u)
    angles = np.linspace(0.0, 2 * np.pi, BODY_SIDES, endpoint=False)
    ring = start + axis / 3 + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
    triangles = []
    for k in range(BODY_SIDES):
        a, b = ring[k], ring[(k + 1) % BODY_SIDES]
        triangles.append((start, b, a))  # counter-clockwise seen from outside, as glTF wants front faces
        triangles.append((end, a, b))
    return np.array(triangles)


def _body_mesh(gl, buffer: _BufferBuilder, skeleton, bind_positions: np.ndarray):
    """One primitive of flat-shaded spindles, each vertex bound with weight 1 to its segment's joint."""
    triangles, owners = [], []
    for start, end, joint in _bone_segments(skeleton, bind_positions):
        length = float(np.linalg.norm(end - start))
        spindle = _spindle(start, end, min(BONE_RADIUS, 0.25 * length + 0.01))
        triangles.append(spindle)
        owners.append(np.full(len(spindle) * 3, joint))
    triangles = np.concatenate(triangles)
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-12)
    positions = triangles.reshape(-1, 3)
    joints = np.zeros((len(positions), 4), dtype=np.uint8)
    joints[:, 0] = np.concatenate(owners)
    weights = np.zeros((len(positions), 4))
    weights[:, 0] = 1.0
    attributes = gl.Attributes(
        POSITION=buffer.add(positions, "VEC3", gl.ARRAY_BUFFER, bounds=True),
        NORMAL=buffer.add(np.repeat(normals, 3, axis=0), "VEC3", gl.ARRAY_BUFFER),
        JOINTS_0=buffer.add(joints, "VEC4", gl.ARRAY_BUFFER),
        WEIGHTS_0=buffer.add(weights, "VEC4", gl.ARRAY_BUFFER),
    )
    return gl.Mesh(name="body", primitives=[gl.Primitive(attributes=attributes, material=0)])


def _continuous(quaternions: np.ndarray) -> np.ndarray:
    """Flip signs so consecutive keys lie in one hemisphere: interpolation then takes the short way."""
    out = quaternions.copy()
    for t in range(1, len(out)):
        flip = np.sum(out[t] * out[t - 1], axis=-1) < 0
        out[t, flip] *= -1
    return out


def _animation(gl, buffer: _BufferBuilder, motion: Motion, translations: dict[int, np.ndarray]):
    """The dance: one time input shared by a rotation channel per joint and a translation channel
    per moving joint (the pelvis; a root bone and the pelvis under it)."""
    times = buffer.add(np.arange(motion.num_frames) / motion.fps, "SCALAR", bounds=True)
    quaternions = _continuous(motion.rotations[..., [1, 2, 3, 0]])  # (w, x, y, z) -> glTF's (x, y, z, w)
    quaternions = quaternions.astype(np.float32)
    quaternions /= np.linalg.norm(quaternions, axis=-1, keepdims=True)  # unit in float32, as validators check
    samplers, channels = [], []
    for j, positions in translations.items():
        samplers.append(gl.AnimationSampler(input=times, output=buffer.add(positions, "VEC3"), interpolation="LINEAR"))
        channels.append(gl.AnimationChannel(sampler=len(samplers) - 1,
                                            target=gl.AnimationChannelTarget(node=j, path="translation")))
    for j in range(motion.num_joints):
        samplers.append(gl.AnimationSampler(input=times, output=buffer.add(quaternions[:, j], "VEC4"),
                                            interpolation="LINEAR"))
        channels.append(gl.AnimationChannel(sampler=len(samplers) - 1,
                                            target=gl.AnimationChannelTarget(node=j, path="rotation")))
    return gl.Animation(name=ANIMATION_NAME, samplers=samplers, channels=channels)


# -- reading ---------------------------------------------------------------------------------
def _accessor_array(gl, document, index: int) -> np.ndarray:
    """An accessor's values as float64 (count, components): tightly packed float or ubyte data only."""
    accessor = document.accessors[index]
    if accessor.sparse is not None:  # its values would replace some of the view's: read without, silently wrong
        raise MotionFormatError("sparse glb accessors are not supported by choreo's reader")
    view = document.bufferViews[accessor.bufferView]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}.get(accessor.type)
    dtype = {gl.FLOAT: np.float32, gl.UNSIGNED_BYTE: np.uint8}.get(accessor.componentType)
    if width is None or dtype is None or (view.byteStride or 0) not in (0, width * np.dtype(dtype).itemsize):
        raise MotionFormatError("glTF accessor layout not supported by choreo's reader")
    start = _byte_count(view.byteOffset) + _byte_count(accessor.byteOffset)
    size = _byte_count(accessor.count) * width * np.dtype(dtype).itemsize
    blob = document.binary_blob()
    if start + size > min(len(blob), _byte_count(view.byteOffset) + _byte_count(view.byteLength)):
        raise MotionFormatError(f"glb accessor {index} reaches past its buffer view or the binary chunk")
    data = np.frombuffer(blob, dtype=dtype, count=accessor.count * width, offset=start)
    return data.reshape(accessor.count, width).astype(np.float64)


def _byte_count(value) -> int:
    """A count, offset or length from the JSON chunk: absent is 0; anything but a plain
    non-negative integer (2^64, -1, 1.5, text) is damage, refused before numpy sees it."""
    if value is None:
        return 0
    if type(value) is not int or value < 0:
        raise MotionFormatError(f"glb count or offset {str(value)[:40]} is not a byte count")
    return value


def _cached_accessors(gl, document):
    """:func:`_accessor_array` converting each accessor once per read: a file may point any number
    of channels at one accessor (100,000 on one would otherwise convert it 100,000 times)."""
    arrays: dict = {}

    def accessor_array(index: int) -> np.ndarray:
        if index not in arrays:
            arrays[index] = _accessor_array(gl, document, index)
        return arrays[index]

    return accessor_array


def read_glb(path: str | Path) -> Motion:
    """Read a glb whose first animation keys SMPL-named joints at every frame (as :func:`write_glb` writes)."""
    _check_object_count(path)
    gl = _gltf()
    try:
        document = gl.GLTF2().load_binary(str(path))
    except Exception as error:  # pygltflib raises assorted errors on damaged files
        raise MotionFormatError(f"{path}: not a readable glb ({error})") from None
    try:
        return _motion_of(gl, document, path)
    except (IndexError, KeyError, TypeError, ValueError, AttributeError, OverflowError) as error:  # indices and sizes a damaged file got wrong
        raise MotionFormatError(f"{path}: damaged glb ({type(error).__name__}: {str(error)[:100]})") from None
    except ParameterError as error:  # values a motion cannot have (a key spacing outside 1-1000 fps)
        raise MotionFormatError(f"{path}: {error}") from None


def _node_tracks(document, keyed: dict, frames: int):
    """``track(node, path)``: (frames, 3 or 4) a node's translation or rotation (x, y, z, w) at
    every frame, its keys where it is keyed at every frame, else its static value."""
    def track(node: int, path: str) -> np.ndarray:
        values = keyed.get((node, path))
        if values is not None and len(values) == frames:
            return values
        static = getattr(document.nodes[node], path)
        default = [0.0, 0.0, 0.0] if path == "translation" else [0.0, 0.0, 0.0, 1.0]
        return np.tile(np.asarray(static if static else default, dtype=np.float64), (frames, 1))

    return track


def _check_object_count(path) -> None:
    """Refuse a glb whose JSON chunk reaches past the file's end (a forged length of gigabytes would
    be allocated before anything is read), or holds more objects than any dance needs, counted on
    the plain JSON before pygltflib builds a dataclass for each; other damage is left to
    pygltflib's own refusal."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(GLB_HEADER)
            if len(head) < GLB_HEADER or head[:4] != b"glTF" or struct.unpack_from("<I", head, 16)[0] != JSON_CHUNK:
                return
            length = struct.unpack_from("<I", head, 12)[0]
            if GLB_HEADER + length > os.fstat(handle.fileno()).st_size:
                raise MotionFormatError(f"{path}: damaged glb (its JSON chunk reaches past the end of the file)")
            pending = [json.loads(handle.read(length))]
    except (OSError, ValueError, RecursionError):
        return
    count = 0
    while pending:
        item = pending.pop()
        if isinstance(item, dict):
            count += 1
            pending.extend(item.values())
        elif isinstance(item, list):
            pending.extend(item)
        if count > MAX_JSON_OBJECTS:
            raise MotionFormatError(f"{path}: glb holds more than {MAX_JSON_OBJECTS:,} JSON objects: not a dance choreo reads")


def _motion_of(gl, document, path) -> Motion:
    """The dance in a loaded glb document; structural damage surfaces as Python errors, mapped above."""
    if document is None or not document.animations or document.binary_blob() is None:
        raise MotionFormatError(f"{path}: glb has no animation to read")
    by_name = {node.name: i for i, node in enumerate(document.nodes)}
    missing = [name for name in SMPL24.names if name not in by_name]
    if missing:
        raise MotionFormatError(f"{path}: skeleton is not SMPL-24 (no node named {missing[0]})")
    node_of = [by_name[name] for name in SMPL24.names]
    offsets = np.array([document.nodes[n].translation or [0.0, 0.0, 0.0] for n in node_of], dtype=np.float64)
    offsets[0] = 0.0
    animation = document.animations[0]
    accessor_array = _cached_accessors(gl, document)
    times, keyed = None, {}
    for channel in animation.channels:
        sampler = animation.samplers[channel.sampler]
        times = accessor_array(sampler.input)[:, 0] if times is None else times
        if channel.target.path in ("rotation", "translation"):
            keyed[channel.target.node, channel.target.path] = accessor_array(sampler.output)
    if times is None or len(times) == 0:
        raise MotionFormatError(f"{path}: the animation has no keys")
    frames = len(times)
    quaternions = np.zeros((frames, 24, 4))
    quaternions[..., 0] = 1.0
    for j, node in enumerate(node_of):
        values = keyed.get((node, "rotation"))
        if values is not None and len(values) != frames:
            raise MotionFormatError(f"{path}: joint {SMPL24.names[j]} is not keyed at every frame")
        if values is not None:
            quaternions[:, j] = values[:, [3, 0, 1, 2]]  # glTF's (x, y, z, w) back to (w, x, y, z)
    track = _node_tracks(document, keyed, frames)
    root = track(node_of[0], "translation")
    parent_of = {child: n for n, node in enumerate(document.nodes) for child in node.children or []}
    above, seen = node_of[0], {node_of[0]}
    while above in parent_of:  # a root bone, an exporter's armature: composed in
        above = parent_of[above]
        if above in seen:
            raise MotionFormatError(f"{path}: damaged glb (its node tree has a loop)")
        seen.add(above)
        turn = track(above, "rotation")[:, [3, 0, 1, 2]]
        turn = quaternion_to_matrix(turn / np.linalg.norm(turn, axis=-1, keepdims=True))
        root = track(above, "translation") + np.einsum("tij,tj->ti", turn, root)
        pelvis = quaternions[:, 0] / np.linalg.norm(quaternions[:, 0], axis=-1, keepdims=True)
        quaternions[:, 0] = matrix_to_quaternion(turn @ quaternion_to_matrix(pelvis))
    extras = document.extras if isinstance(document.extras, dict) else {}
    stored = extras.get("fps") if isinstance(extras.get("fps"), (int, float)) else None
    if frames > 1 and times[-1] > times[0]:
        fps = (frames - 1) / (times[-1] - times[0])
        fps = float(round(fps)) if abs(fps - round(fps)) < 1e-3 else float(fps)
        if stored is not None and abs(stored - fps) < 1e-3 * fps:
            fps = float(stored)  # exact, where the float32 key times are not
    else:  # one key says nothing about the rate: ours is in the extras
        fps = float(stored) if stored is not None else 30.0
    metadata = {**file_metadata(extras.get("metadata")), "source": source_name(path)}  # as NPZ: the name read
    return Motion(root, quaternions, fps=fps, skeleton=SMPL24.with_offsets(offsets), metadata=metadata)
