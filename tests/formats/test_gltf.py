"""glTF 2.0 binary: the file says what we mean, to our own reading, to Khronos's validator and to Blender.

The joint positions are recomputed here from the glb alone (accessors decoded and nodes composed in
this file, not by choreo's reader or forward kinematics), so a wrong axis, quaternion order, offset
or time base in the writer fails.
The validator test needs node and the npm package ``gltf-validator`` where node finds it (for
example ``npm install --prefix /tmp/gv gltf-validator`` and ``NODE_PATH=/tmp/gv/node_modules``, or
``npm install -g gltf-validator``); the Blender test needs ``blender`` on PATH. Each is skipped otherwise.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

pygltflib = pytest.importorskip("pygltflib")

import struct

from scipy.spatial.transform import Rotation

from choreo.errors import (  # noqa: E402
    MotionFormatError,  # noqa: E402
    )
from choreo.formats import (  # noqa: E402
    gltf,
    read_motion,
    write_motion,
)
from choreo.formats.gltf import read_glb, write_glb  # noqa: E402  # noqa: E402
from choreo.motion import Motion  # noqa: E402  # noqa: E402
from choreo.skeleton import JOINT_NAMES, SMPL24  # noqa: E402  # noqa: E402
from tests.formats.gltf_helpers import join_glb, split_glb, still_glb
from tests.formats.helpers import small_motion, still
from tests.formats.hostile import forged_glb, glb_bytes, glb_chunks, hostile_dance

BLENDER_SCRIPT = Path(__file__).parents[1] / "blender" / "import_glb.py"
FRAMES, FPS = 40, 30.0


@pytest.fixture(scope="module")
def motion():
    """A wandering, turning dance on a performer with their own proportions (not the template's)."""
    rng = np.random.default_rng(0)
    axis_angle = np.cumsum(rng.normal(scale=0.08, size=(FRAMES, 24, 3)), axis=0)
    axis_angle[:, 0, 1] += np.linspace(0, 3 * np.pi, FRAMES)  # turns more than a full circle
    root = np.cumsum(rng.normal(scale=0.02, size=(FRAMES, 3)), axis=0) + [0.3, 0.95, -0.2]
    skeleton = SMPL24.with_offsets(SMPL24.offsets * rng.uniform(0.9, 1.1, size=(24, 1)))
    return Motion.from_axis_angle(root, axis_angle, fps=FPS, skeleton=skeleton, metadata={"seed": 7})


@pytest.fixture(scope="module")
def glb_path(motion, tmp_path_factory):
    path = tmp_path_factory.mktemp("glb") / "dance.glb"
    with open(path, "wb") as handle:
        write_glb(motion, handle)
    return path


@pytest.fixture(scope="module")
def root_motion_glb(motion, tmp_path_factory):
    path = tmp_path_factory.mktemp("glb") / "root.glb"
    with open(path, "wb") as handle:
        write_glb(motion, handle, root_motion=True)
    return path


# -- an independent reading of the file ------------------------------------------------------
def accessor(document, index):
    """Decode one accessor by hand from the glTF JSON and the binary chunk."""
    acc = document.accessors[index]
    view = document.bufferViews[acc.bufferView]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}[acc.type]
    dtype = {5126: "<f4", 5121: "u1", 5123: "<u2"}[acc.componentType]
    offset = (view.byteOffset or 0) + (acc.byteOffset or 0)
    return np.frombuffer(document.binary_blob(), dtype=dtype, count=acc.count * width, offset=offset).reshape(acc.count, width)


def quaternion_matrix(x, y, z, w):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def node_worlds(document, frame=None):
    """(nodes, 4, 4) world matrices at key ``frame`` of the first animation (None: the nodes' own TRS)."""
    local = {}
    for i, node in enumerate(document.nodes):
        local[i] = {"translation": np.array(node.translation or [0, 0, 0], float),
                    "rotation": np.array(node.rotation or [0, 0, 0, 1], float)}
    if frame is not None:
        animation = document.animations[0]
        for channel in animation.channels:
            values = accessor(document, animation.samplers[channel.sampler].output)
            local[channel.target.node][channel.target.path] = values[frame].astype(float)
    parent = {child: i for i, node in enumerate(document.nodes) for child in (node.children or [])}
    worlds = np.zeros((len(document.nodes), 4, 4))
    for i in sorted(local, key=lambda n: depth(n, parent)):
        matrix = np.eye(4)
        matrix[:3, :3] = quaternion_matrix(*local[i]["rotation"])
        matrix[:3, 3] = local[i]["translation"]
        worlds[i] = worlds[parent[i]] @ matrix if i in parent else matrix
    return worlds


def depth(node, parent):
    return 0 if node not in parent else 1 + depth(parent[node], parent)


def load(path):
    return pygltflib.GLTF2().load_binary(str(path))


# -- structure -------------------------------------------------------------------------------
def test_nodes_skin_and_animation_describe_the_smpl_dancer(glb_path):
    document = load(glb_path)
    assert document.asset.version == "2.0"
    assert len(document.nodes) == 24 + 1
    assert [node.name for node in document.nodes[:24]] == list(JOINT_NAMES)
    assert sorted(document.scenes[document.scene].nodes) == [0, 24]
    skin = document.skins[0]
    assert skin.joints == list(range(24)) and document.nodes[24].skin == 0 and document.nodes[24].mesh == 0
    for j, p in enumerate(SMPL24.parents):
        if p >= 0:
            assert j in document.nodes[p].children
    animation = document.animations[0]
    times = accessor(document, animation.samplers[0].input)[:, 0]
    assert len(times) == FRAMES
    np.testing.assert_allclose(times, np.arange(FRAMES) / FPS, atol=1e-6)
    targets = {(c.target.node, c.target.path) for c in animation.channels}
    assert targets == {(0, "translation")} | {(j, "rotation") for j in range(24)}


def test_animated_joint_positions_match_ours_within_a_millimetre(glb_path, motion):
    document = load(glb_path)
    ours = motion.joint_positions()
    for frame in (0, 1, FRAMES // 2, FRAMES - 1):
        theirs = node_worlds(document, frame)[:24, :3, 3]
        assert np.abs(theirs - ours[frame]).max() < 1e-3, frame


def test_body_is_bound_in_the_rest_pose_and_follows_its_bones(glb_path):
    document = load(glb_path)
    rest = node_worlds(document)
    inverse_bind = accessor(document, document.skins[0].inverseBindMatrices).reshape(24, 4, 4).transpose(0, 2, 1)
    np.testing.assert_allclose(rest[:24] @ inverse_bind, np.tile(np.eye(4), (24, 1, 1)), atol=1e-5)
    attributes = document.meshes[0].primitives[0].attributes
    positions = accessor(document, attributes.POSITION).astype(float)
    joints = accessor(document, attributes.JOINTS_0)[:, 0]
    weights = accessor(document, attributes.WEIGHTS_0)
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, atol=1e-6)
    assert positions[:, 1].min() == pytest.approx(0.0, abs=0.03)  # standing on the floor in the bind pose
    assert 1.4 < np.ptp(positions[:, 1]) < 2.1  # human-sized, in metres
    assert len(set(joints.tolist())) >= 20  # nearly every joint carries a body part
    # skinned at a frame, every vertex keeps its distance to the joint it is bound to: rigid parts
    frame = node_worlds(document, FRAMES // 2)
    homogeneous = np.concatenate([positions, np.ones((len(positions), 1))], axis=1)
    skinned = np.einsum("nij,nj->ni", frame[joints] @ inverse_bind[joints], homogeneous)[:, :3]
    before = np.linalg.norm(positions - rest[joints, :3, 3], axis=1)
    after = np.linalg.norm(skinned - frame[joints, :3, 3], axis=1)
    np.testing.assert_allclose(after, before, atol=1e-4)


def test_round_trip_through_our_reader(glb_path, motion):
    back = read_glb(glb_path)
    assert back.num_frames == FRAMES and back.fps == FPS
    assert np.abs(back.joint_positions() - motion.joint_positions()).max() < 1e-4
    np.testing.assert_allclose(back.skeleton.offsets[1:], motion.skeleton.offsets[1:], atol=1e-6)


def test_root_motion_puts_a_floor_level_root_bone_in_the_skin_above_the_pelvis(root_motion_glb, motion):
    document = load(root_motion_glb)
    assert [node.name for node in document.nodes[:25]] == ["root", *JOINT_NAMES] and document.nodes[0].children == [1]
    assert document.skins[0].joints == list(range(25)) and sorted(document.scenes[0].nodes) == [0, 25]
    targets = {(c.target.node, c.target.path) for c in document.animations[0].channels}
    assert targets == {(0, "translation"), (1, "translation")} | {(j, "rotation") for j in range(25)}
    ours = motion.joint_positions()
    floor = np.median(ours[..., 1].min(axis=1))
    for frame in (0, FRAMES // 2, FRAMES - 1):
        worlds = node_worlds(document, frame)
        assert np.abs(worlds[1:25, :3, 3] - ours[frame]).max() < 1e-3, frame
        assert abs(worlds[0, 1, 3] - floor) < 1e-5
    rest = node_worlds(document)  # the bind pose stands on the floor, the root bone under the pelvis
    np.testing.assert_allclose(rest[0, :3, 3], 0.0)
    assert rest[1:25, 1, 3].min() == pytest.approx(0.0, abs=1e-6)
    attributes = document.meshes[0].primitives[0].attributes
    assert 0 not in accessor(document, attributes.JOINTS_0)[:, 0]  # no body part hangs on the root bone
    back = read_glb(root_motion_glb)
    assert np.abs(back.joint_positions() - ours).max() < 1e-4


def test_writer_refuses_other_skeletons_and_reader_damaged_files(tmp_path, motion):
    other = SMPL24.__class__(JOINT_NAMES[:23], SMPL24.parents[:23], SMPL24.offsets[:23])
    with pytest.raises(MotionFormatError):
        write_glb(Motion.rest(3, skeleton=other), io.BytesIO())
    damaged = tmp_path / "damaged.glb"
    buffer = io.BytesIO()
    write_glb(motion, buffer)
    damaged.write_bytes(buffer.getvalue()[:200])
    with pytest.raises(MotionFormatError):
        read_glb(damaged)


def test_a_single_frame_and_a_still_pose_write(tmp_path):
    for frames in (1, 2):
        path = tmp_path / f"still{frames}.glb"
        with open(path, "wb") as handle:
            write_glb(Motion.rest(frames, fps=24), handle)
        back = read_glb(path)
        assert back.num_frames == frames and back.fps == 24
        np.testing.assert_allclose(back.joint_positions(), Motion.rest(frames).joint_positions(), atol=1e-6)


# -- Khronos glTF validator ------------------------------------------------------------------
VALIDATE_JS = """
const validator = require('gltf-validator');
const bytes = new Uint8Array(require('fs').readFileSync(process.argv[2]));
validator.validateBytes(bytes, {maxIssues: 50}).then(
  (report) => console.log(JSON.stringify(report.issues)),
  (error) => { console.error(String(error)); process.exit(2); });
"""


def validator_environment():
    """Environment in which ``require('gltf-validator')`` resolves, or skip."""
    node = shutil.which("node")
    if not node:
        pytest.skip("node is not installed")
    paths = [p for p in os.environ.get("NODE_PATH", "").split(os.pathsep) if p]
    npm = shutil.which("npm")
    if npm:
        found = subprocess.run([npm, "root", "-g"], capture_output=True, text=True, timeout=60)
        paths.append(found.stdout.strip())
    env = {**os.environ, "NODE_PATH": os.pathsep.join(paths)}
    probe = subprocess.run([node, "-e", "require.resolve('gltf-validator')"], env=env, capture_output=True, timeout=60)
    if probe.returncode != 0:
        pytest.skip("the npm package gltf-validator is not installed where node finds it (see NODE_PATH)")
    return node, env


@pytest.mark.parametrize("written", ["glb_path", "root_motion_glb"])
def test_khronos_validator_finds_no_errors_or_warnings(written, request, tmp_path):
    node, env = validator_environment()
    script = tmp_path / "validate.js"
    script.write_text(VALIDATE_JS)
    path = request.getfixturevalue(written)
    done = subprocess.run([node, str(script), str(path)], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    issues = json.loads(done.stdout)
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]


# -- Blender ---------------------------------------------------------------------------------
@pytest.mark.parametrize("written", ["glb_path", "root_motion_glb"])
def test_blender_imports_our_glb_exactly(written, request, motion, tmp_path):
    blender = shutil.which("blender")
    if not blender:
        pytest.skip("Blender is not installed")
    glb_path = request.getfixturevalue(written)
    numpy_dir = str(Path(np.__file__).parent.parent)  # Debian's Blender glTF importer needs numpy
    result = subprocess.run([blender, "--background", "--factory-startup", "--python-exit-code", "1",
                             "--python", str(BLENDER_SCRIPT), "--", str(glb_path), str(FPS),
                             str(tmp_path / "seen.json"), numpy_dir],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and (tmp_path / "seen.json").exists(), result.stdout[-2000:] + result.stderr[-2000:]
    seen = json.loads((tmp_path / "seen.json").read_text())
    bones = list(JOINT_NAMES) + (["root"] if written == "root_motion_glb" else [])
    assert len(seen["bones"]) == len(bones) and set(seen["bones"]) == set(bones)
    assert seen["frame_end"] - seen["frame_start"] + 1 == FRAMES
    skinned = [mesh for mesh in seen["meshes"] if mesh["deformed_by"]]
    assert len(skinned) == 1 and skinned[0]["groups"] >= 24 and skinned[0]["vertices"] > 0
    heads = np.array(seen["heads"])  # (frames, bones, 3), Blender's Z-up: (x, y, z) = (x, -z, y) in ours
    joints = [k for k, name in enumerate(seen["bones"]) if name in JOINT_NAMES]
    ours = motion.joint_positions()[:, [JOINT_NAMES.index(seen["bones"][k]) for k in joints]]
    ours_in_blender = np.stack([ours[..., 0], -ours[..., 2], ours[..., 1]], axis=-1)
    assert np.abs(heads[:, joints] - ours_in_blender).max() < 1e-3  # under a millimetre
    if "root" in seen["bones"]:  # on the floor, where the feet are
        floor = np.median(motion.joint_positions()[..., 1].min(axis=1))
        assert np.abs(heads[:, seen["bones"].index("root"), 2] - floor).max() < 1e-3


# -- glTF --------------------------------------------------------------------------------------
@pytest.mark.survivor
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


pygltflib = pytest.importorskip("pygltflib")


PARENTS = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21)  # SMPL-24, written out


LEAVES = (10, 11, 15, 22, 23)  # the joints no joint names as parent: feet, head, hands


TIPS = {"head": (0.0, 0.16, 0.0), "l_hand": (0.08, 0.0, 0.0), "r_hand": (-0.08, 0.0, 0.0),
        "l_foot": (0.0, 0.0, 0.06), "r_foot": (0.0, 0.0, 0.06)}  # End Sites; the head's drawn 1.6 times longer


DEFAULT_TIP = (0.0, 0.05, 0.0)


SIDES, TRIANGLES_PER_SPINDLE = 8, 16


SEGMENTS = 23 + 5  # a spindle per bone and one past each leaf


VERTICES = SEGMENTS * TRIANGLES_PER_SPINDLE * 3  # 1344: flat shading, three vertices per triangle


FLOAT, UBYTE, ARRAY_BUFFER = 5126, 5121, 34962


WIDTH = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}


# -- the container, by hand ------------------------------------------------------------------
def glb_of(motion) -> bytes:
    buffer = io.BytesIO()
    write_glb(motion, buffer)
    return buffer.getvalue()


def decode(document: dict, blob: bytes, index: int) -> np.ndarray:
    """One accessor's values, (count, width), in their stored type."""
    accessor = document["accessors"][index]
    view = document["bufferViews"][accessor["bufferView"]]
    dtype = {FLOAT: "<f4", UBYTE: "u1"}[accessor["componentType"]]
    width = WIDTH[accessor["type"]]
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    return np.frombuffer(blob, dtype=dtype, count=accessor["count"] * width, offset=start).reshape(accessor["count"], width)


def parts(motion):
    return split_glb(glb_of(motion))


# -- motions with known answers --------------------------------------------------------------
def rest_positions(offsets: np.ndarray) -> np.ndarray:
    positions = np.zeros((24, 3))
    for j in range(1, 24):
        positions[j] = positions[PARENTS[j]] + offsets[j]
    return positions


def performer(seed: int = 3):
    """SMPL-24 with its own proportions, so that no template value hides a wrong one."""
    rng = np.random.default_rng(seed)
    return SMPL24.with_offsets(SMPL24.offsets * rng.uniform(0.85, 1.15, size=(24, 1)))


def glb_dance(frames: int = 6, fps: float = 25.0, seed: int = 1, skeleton=None, metadata=None):
    rng = np.random.default_rng(seed)
    rotvecs = rng.normal(scale=0.7, size=(frames, 24, 3))
    root = rng.normal(scale=0.3, size=(frames, 3)) + [0.0, 0.9, 0.0]
    quaternions = Rotation.from_rotvec(rotvecs.reshape(-1, 3)).as_quat().reshape(frames, 24, 4)[..., [3, 0, 1, 2]]
    motion = Motion(root, quaternions, fps=fps, skeleton=skeleton or performer(), metadata=metadata or {})
    return motion, rotvecs


# -- the body mesh, from its closed form -----------------------------------------------------
def segments(offsets: np.ndarray, names) -> list:
    """(start, end, joint) per spindle in the bind pose: bones first (carried by the parent), then tips."""
    rest = rest_positions(offsets)
    bind = rest + [0.0, -rest[:, 1].min(), 0.0]
    out = [(bind[PARENTS[j]], bind[j], PARENTS[j]) for j in range(1, 24)]
    for j in LEAVES:
        out.append((bind[j], bind[j] + np.array(TIPS.get(names[j], DEFAULT_TIP)), j))
    return out


def spindle(start, end, radius) -> np.ndarray:
    """(16, 3, 3): apex start, apex end, a ring of 8 at a third of the way; ring[0] along d x X (d x Y near X)."""
    d = (end - start) / np.linalg.norm(end - start)
    u = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    ring = [start + (end - start) / 3 + radius * (np.cos(np.pi * k / 4) * u + np.sin(np.pi * k / 4) * v) for k in range(8)]
    out = []
    for k in range(SIDES):
        out += [(start, ring[(k + 1) % 8], ring[k]), (end, ring[k], ring[(k + 1) % 8])]
    return np.array(out)


def expected_mesh(offsets, names=JOINT_NAMES):
    triangles, owners = [], []
    for start, end, joint in segments(offsets, names):
        radius = min(0.035, 0.25 * np.linalg.norm(end - start) + 0.01)
        triangles.append(spindle(start, end, radius))
        owners += [joint] * (TRIANGLES_PER_SPINDLE * 3)
    return np.concatenate(triangles).reshape(-1, 3), np.array(owners)


@pytest.mark.survivor
def test_body_mesh_is_the_closed_form_spindles_with_outward_unit_normals():
    skeleton = performer(5)
    document, blob = parts(still_glb(2, skeleton=skeleton))
    primitive = document["meshes"][0]["primitives"][0]
    attributes = primitive["attributes"]
    positions = decode(document, blob, attributes["POSITION"]).astype(float)
    expected, owners = expected_mesh(skeleton.offsets)
    assert positions.shape == (VERTICES, 3)
    np.testing.assert_allclose(positions, expected, atol=2e-6)
    normals = decode(document, blob, attributes["NORMAL"]).astype(float)
    triangles = positions.reshape(-1, 3, 3)
    face = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    face /= np.linalg.norm(face, axis=1, keepdims=True)
    np.testing.assert_allclose(normals, np.repeat(face, 3, axis=0), atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)
    # counter-clockwise seen from outside: every face normal points away from its spindle's axis
    starts = np.repeat([s for s, _, _ in segments(skeleton.offsets, JOINT_NAMES)], TRIANGLES_PER_SPINDLE, axis=0)
    ends = np.repeat([e for _, e, _ in segments(skeleton.offsets, JOINT_NAMES)], TRIANGLES_PER_SPINDLE, axis=0)
    centroid = triangles.mean(axis=1)
    axis = (ends - starts) / np.linalg.norm(ends - starts, axis=1, keepdims=True)
    radial = centroid - starts - np.sum((centroid - starts) * axis, axis=1, keepdims=True) * axis
    assert (np.sum(radial * normals[::3], axis=1) > 0).all()
    joints = decode(document, blob, attributes["JOINTS_0"])
    assert joints.dtype == np.uint8
    np.testing.assert_array_equal(joints[:, 0], owners)
    np.testing.assert_array_equal(joints[:, 1:], 0)
    weights = decode(document, blob, attributes["WEIGHTS_0"])
    np.testing.assert_array_equal(weights, np.tile([1.0, 0.0, 0.0, 0.0], (VERTICES, 1)))
    assert document["meshes"][0]["name"] == "body" and primitive["material"] == 0
    assert len(document["meshes"]) == 1 and len(document["meshes"][0]["primitives"]) == 1
    assert set(attributes) == {"POSITION", "NORMAL", "JOINTS_0", "WEIGHTS_0"}


@pytest.mark.survivor
def test_a_skeleton_with_its_own_leaf_names_gets_default_tips():
    """SMPL-24's tree under other names: leaves without an End Site get a 5 cm tip straight up, the
    renamed head included (no 1.6 stretch)."""
    names = list(JOINT_NAMES)
    names[15], names[22] = "kopf", "hand_links"
    skeleton = SMPL24.__class__(tuple(names), SMPL24.parents, SMPL24.offsets)
    document, blob = parts(still_glb(1, skeleton=skeleton))
    positions = decode(document, blob, document["meshes"][0]["primitives"][0]["attributes"]["POSITION"]).astype(float)
    expected, _ = expected_mesh(skeleton.offsets, names)
    np.testing.assert_allclose(positions, expected, atol=2e-6)
    head = segments(skeleton.offsets, names)[23 + LEAVES.index(15)]
    np.testing.assert_allclose(head[1] - head[0], [0.0, 0.05, 0.0], atol=1e-12)
    assert [n["name"] for n in document["nodes"][:24]] == names


# -- accessors, views, buffer ------------------------------------------------------------------
@pytest.mark.survivor
def test_accessors_views_and_buffer_are_laid_out_as_described():
    frames, fps = 5, 20.0
    motion, _ = glb_dance(frames, fps)
    document, blob = parts(motion)
    # (type, componentType, count, target) in the order written: the mesh, the skin, the animation
    layout = ([("VEC3", FLOAT, VERTICES, ARRAY_BUFFER), ("VEC3", FLOAT, VERTICES, ARRAY_BUFFER),
               ("VEC4", UBYTE, VERTICES, ARRAY_BUFFER), ("VEC4", FLOAT, VERTICES, ARRAY_BUFFER),
               ("MAT4", FLOAT, 24, None), ("SCALAR", FLOAT, frames, None), ("VEC3", FLOAT, frames, None)]
              + [("VEC4", FLOAT, frames, None)] * 24)
    accessors, views = document["accessors"], document["bufferViews"]
    assert len(accessors) == len(views) == len(layout)
    offset = 0
    for i, (kind, component, count, target) in enumerate(layout):
        accessor, view = accessors[i], views[i]
        assert (accessor["type"], accessor["componentType"], accessor["count"], accessor["bufferView"]) == (kind, component, count, i)
        size = count * WIDTH[kind] * (1 if component == UBYTE else 4)
        offset += -offset % 4
        assert (view["buffer"], view.get("byteOffset", 0), view["byteLength"], view.get("target")) == (0, offset, size, target)
        assert view.get("byteOffset", 0) % 4 == 0
        offset += size
        bounded = i in (0, 5)  # positions and the key times only
        assert ("min" in accessor, "max" in accessor) == (bounded, bounded), i
    assert document["buffers"] == [{"byteLength": offset}] and len(blob) == offset
    positions = decode(document, blob, 0)
    assert accessors[0]["min"] == positions.min(axis=0).astype(float).tolist()
    assert accessors[0]["max"] == positions.max(axis=0).astype(float).tolist()
    closed_form = expected_mesh(motion.skeleton.offsets)[0]
    np.testing.assert_allclose([accessors[0]["min"], accessors[0]["max"]], [closed_form.min(axis=0), closed_form.max(axis=0)], atol=2e-6)
    assert accessors[5]["min"] == [0.0] and accessors[5]["max"] == [float(np.float32((frames - 1) / fps))]


@pytest.mark.survivor
def test_buffer_builder_pads_byte_arrays_to_four_bytes():
    builder = gltf._BufferBuilder(pygltflib)
    first = builder.add(np.array([[7, 8, 9]], dtype=np.uint8), "VEC3")
    second = builder.add(np.array([[1.5, -2.0]]), "VEC2", target=ARRAY_BUFFER, bounds=True)
    assert (first, second) == (0, 1)
    assert [(v.byteOffset, v.byteLength, v.target) for v in builder.views] == [(0, 3, None), (4, 8, ARRAY_BUFFER)]
    assert bytes(builder.data) == bytes([7, 8, 9, 0]) + struct.pack("<2f", 1.5, -2.0)
    assert [a.componentType for a in builder.accessors] == [UBYTE, FLOAT]
    assert builder.accessors[0].min == [] and builder.accessors[0].max == []  # pygltflib: no bounds
    assert (builder.accessors[1].min, builder.accessors[1].max) == ([1.5, -2.0], [1.5, -2.0])


# -- nodes, skin, scene, material, asset -----------------------------------------------------
@pytest.mark.survivor
def test_nodes_skin_scene_material_and_asset_exactly():
    skeleton = performer(9)
    document, blob = parts(still_glb(3, skeleton=skeleton))
    rest = rest_positions(skeleton.offsets)
    floor = -rest[:, 1].min()
    nodes = document["nodes"]
    assert len(nodes) == 25
    assert nodes[0]["translation"] == [0.0, floor, 0.0]
    for j in range(1, 24):
        np.testing.assert_allclose(nodes[j]["translation"], skeleton.offsets[j], atol=1e-12)
    for j in range(24):
        children = [c for c in range(24) if PARENTS[c] == j]
        assert nodes[j].get("children") == (children or None), j
    assert nodes[24] == {"name": "body", "mesh": 0, "skin": 0}
    skin = document["skins"][0]
    assert (skin["name"], skin["joints"], skin["skeleton"], skin["inverseBindMatrices"]) == ("SMPL-24", list(range(24)), 0, 4)
    inverse_bind = decode(document, blob, 4).reshape(24, 4, 4).transpose(0, 2, 1)  # column-major in the file
    expected = np.tile(np.eye(4), (24, 1, 1))
    expected[:, :3, 3] = -(rest + [0.0, floor, 0.0])
    np.testing.assert_allclose(inverse_bind, expected, atol=1e-6)
    assert document["asset"] == {"version": "2.0", "generator": "choreo"}
    assert document["scene"] == 0 and document["scenes"] == [{"name": "dancer", "nodes": [0, 24]}]
    material, = document["materials"]
    assert material["name"] == "body"
    assert material["pbrMetallicRoughness"] == {"baseColorFactor": [0.85, 0.55, 0.35, 1.0], "metallicFactor": 0.0,
                                                "roughnessFactor": 0.8}


@pytest.mark.survivor
def test_writer_refuses_24_joints_in_another_tree_with_its_message():
    parents = list(SMPL24.parents)
    parents[15] = 9  # the head hung from spine3: still 24 joints
    other = SMPL24.__class__(JOINT_NAMES, tuple(parents), SMPL24.offsets)
    with pytest.raises(MotionFormatError) as raised:
        write_glb(still_glb(2, skeleton=other), io.BytesIO())
    assert str(raised.value) == "glTF export supports the SMPL-24 skeleton only"


@pytest.mark.survivor
def test_extras_carry_fps_and_metadata_made_json():
    motion = still_glb(2, fps=24.0)
    motion.metadata = {"seed": 7, "song": Path("songs/a.wav"), "tags": ("a", 1)}
    document, _ = parts(motion)
    assert document["extras"] == {"fps": 24.0, "metadata": {"seed": 7, "song": "songs/a.wav", "tags": ["a", 1]}}


@pytest.mark.survivor
def test_zero_frames_write_no_animation_and_read_says_so(tmp_path):
    empty = Motion(np.zeros((0, 3)), np.zeros((0, 24, 4)), fps=30.0)
    data = glb_of(empty)
    document, blob = split_glb(data)
    assert "animations" not in document or document["animations"] == []
    assert len(document["accessors"]) == 5  # the mesh's four and the skin's
    path = tmp_path / "empty.glb"
    path.write_bytes(data)
    with pytest.raises(MotionFormatError) as raised:
        read_glb(path)
    assert str(raised.value) == f"{path}: glb has no animation to read"


# -- the animation -----------------------------------------------------------------------------
@pytest.mark.survivor
def test_animation_samplers_channels_and_values():
    frames, fps = 7, 12.5
    motion, rotvecs = glb_dance(frames, fps, seed=4)
    document, blob = parts(motion)
    animation, = document["animations"]
    assert animation["name"] == "dance"
    assert animation["samplers"] == ([{"input": 5, "output": 6, "interpolation": "LINEAR"}]
                                     + [{"input": 5, "output": 7 + j, "interpolation": "LINEAR"} for j in range(24)])
    assert animation["channels"] == ([{"sampler": 0, "target": {"node": 0, "path": "translation"}}]
                                     + [{"sampler": 1 + j, "target": {"node": j, "path": "rotation"}} for j in range(24)])
    np.testing.assert_allclose(decode(document, blob, 5)[:, 0], np.arange(frames) / fps, atol=1e-6)
    np.testing.assert_allclose(decode(document, blob, 6), motion.root_positions, atol=1e-6)
    for j in range(24):
        keys = decode(document, blob, 7 + j).astype(float)  # (x, y, z, w)
        np.testing.assert_allclose(np.linalg.norm(keys, axis=1), 1.0, atol=1e-6)
        angle = (Rotation.from_quat(keys).inv() * Rotation.from_rotvec(rotvecs[:, j])).magnitude()
        assert angle.max() < 1e-5, j
        assert (np.sum(keys[1:] * keys[:-1], axis=1) >= 0).all()  # one hemisphere: the short way


# hand-made key signs: (w, x, y, z) in, glTF's (x, y, z, w) out
SIGN_CASES = {
    1: ([(1, 0, 0, 0), (0, 1, 0, 0), (0, -1, 0, 0), (-0.6, -0.8, 0, 0)],  # a dot of exactly 0 keeps its sign
        [(0, 0, 0, 1), (1, 0, 0, 0), (1, 0, 0, 0), (0.8, 0, 0, 0.6)]),
    2: ([(1, 0, 0, 0), (-0.8, 0, 0.6, 0), (0.8, 0, -0.6, 0), (0.8, 0, -0.6, 0)],  # flipped at the first step
        [(0, 0, 0, 1), (0, -0.6, 0, 0.8), (0, -0.6, 0, 0.8), (0, -0.6, 0, 0.8)]),
}


@pytest.mark.survivor
def test_key_signs_flip_into_one_hemisphere_joint_by_joint():
    rotations = np.zeros((4, 24, 4))
    rotations[..., 0] = 1.0
    for j, (given, _) in SIGN_CASES.items():
        rotations[:, j] = given
    document, blob = parts(Motion(np.zeros((4, 3)), rotations, fps=30.0))
    for j in range(24):
        expected = SIGN_CASES[j][1] if j in SIGN_CASES else [(0, 0, 0, 1)] * 4
        np.testing.assert_allclose(decode(document, blob, 7 + j), expected, atol=1e-7, err_msg=str(j))


@pytest.mark.survivor
def test_continuous_returns_the_keys_with_signs_flipped_only():
    keys = np.zeros((4, 3, 4))
    keys[..., 3] = 1.0
    keys[:, 1] = [(0, 0, 0, 1), (0, 0, 0, -1), (0.6, 0, 0, -0.8), (0.8, 0, 0, -0.6)]
    out = gltf._continuous(keys)
    np.testing.assert_array_equal(out[:, 1], [(0, 0, 0, 1), (0, 0, 0, 1), (-0.6, 0, 0, 0.8), (-0.8, 0, 0, 0.6)])
    np.testing.assert_array_equal(out[:, [0, 2]], keys[:, [0, 2]])
    np.testing.assert_array_equal(keys[1, 1], (0, 0, 0, -1))  # the input is left alone


# -- the reader, on files edited here -------------------------------------------------------------
def edited(tmp_path, motion, edit, name="edited.glb") -> Path:
    document, blob = parts(motion)
    blob = bytearray(blob)
    edit(document, blob)
    path = tmp_path / name
    path.write_bytes(join_glb(document, bytes(blob)))
    return path


def put_floats(document, blob, index, values):
    view = document["bufferViews"][document["accessors"][index]["bufferView"]]
    data = np.asarray(values, dtype="<f4").tobytes()
    blob[view["byteOffset"]:view["byteOffset"] + len(data)] = data


def read_error(path) -> str:
    with pytest.raises(MotionFormatError) as raised:
        read_glb(path)
    return str(raised.value)


@pytest.mark.survivor
def test_round_trip_values_and_source(tmp_path):
    motion, _ = glb_dance(5, 25.0, seed=8)
    path = tmp_path / "dance.glb"
    path.write_bytes(glb_of(motion))
    back = read_glb(path)
    assert back.fps == 25.0 and back.metadata == {"source": path.name}
    np.testing.assert_array_equal(back.skeleton.offsets[0], [0.0, 0.0, 0.0])
    np.testing.assert_allclose(back.skeleton.offsets[1:], motion.skeleton.offsets[1:], atol=1e-7)
    np.testing.assert_allclose(back.root_positions, motion.root_positions, atol=1e-6)
    dots = np.abs(np.sum(back.rotations * motion.rotations, axis=-1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-6)


@pytest.mark.survivor
@pytest.mark.filterwarnings("ignore:pygltflib does not support version")
def test_reader_messages_for_missing_joints_keys_and_damage(tmp_path):
    motion = still_glb(3)

    def rename(document, blob):
        document["nodes"][7]["name"], document["nodes"][15]["name"] = "Ankle", "Head"
    assert read_error(edited(tmp_path, motion, rename, "a.glb")) == f"{tmp_path / 'a.glb'}: skeleton is not SMPL-24 (no node named l_ankle)"

    def no_channels(document, blob):
        document["animations"][0]["channels"] = []
    assert read_error(edited(tmp_path, motion, no_channels, "b.glb")) == f"{tmp_path / 'b.glb'}: the animation has no keys"

    def short_joint(document, blob):
        document["accessors"][7 + 4]["count"] = 2
    assert read_error(edited(tmp_path, motion, short_joint, "c.glb")) == f"{tmp_path / 'c.glb'}: joint l_knee is not keyed at every frame"

    def wordy(document, blob):  # one offset of 7 numbers: numpy's long complaint, cut at 100 characters
        document["nodes"][5]["translation"] = [0.0] * 7
    with pytest.raises(ValueError) as numpy_says:
        np.array([[0.0] * 3] * 5 + [[0.0] * 7] + [[0.0] * 3] * 18, dtype=np.float64)
    assert len(str(numpy_says.value)) > 100
    expected = str(numpy_says.value)[:100]
    assert read_error(edited(tmp_path, motion, wordy, "d.glb")) == f"{tmp_path / 'd.glb'}: damaged glb (ValueError: {expected})"

    def bad_sampler(document, blob):
        document["animations"][0]["channels"][3]["sampler"] = 99
    message = read_error(edited(tmp_path, motion, bad_sampler, "e.glb"))
    assert message == f"{tmp_path / 'e.glb'}: damaged glb (IndexError: list index out of range)"

    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"glTF" + b"\xff" * 30)
    assert read_error(junk).startswith(f"{junk}: not a readable glb (")


@pytest.mark.survivor
def test_reader_defaults_for_unkeyed_joints_root_and_missing_translations(tmp_path):
    motion, _ = glb_dance(4, 30.0, seed=2)

    def drop(document, blob):  # no root translation channel, no rotation for l_knee, no offset for spine1
        channels = document["animations"][0]["channels"]
        document["animations"][0]["channels"] = [c for c in channels if c["target"] != {"node": 0, "path": "translation"}
                                                 and c["target"] != {"node": 4, "path": "rotation"}]
        del document["nodes"][3]["translation"]
        document["nodes"][0]["translation"] = [0.25, 1.5, -0.75]
    back = read_glb(edited(tmp_path, motion, drop))
    np.testing.assert_array_equal(back.root_positions, np.tile([0.25, 1.5, -0.75], (4, 1)))
    np.testing.assert_array_equal(back.rotations[:, 4], np.tile([1.0, 0.0, 0.0, 0.0], (4, 1)))
    np.testing.assert_array_equal(back.skeleton.offsets[3], [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(back.skeleton.offsets[0], [0.0, 0.0, 0.0])

    def no_root_at_all(document, blob):
        drop(document, blob)
        del document["nodes"][0]["translation"]
    back = read_glb(edited(tmp_path, motion, no_root_at_all, "b.glb"))
    np.testing.assert_array_equal(back.root_positions, np.zeros((4, 3)))

    def short_root(document, blob):  # a root keyed at fewer frames: the node's translation instead
        document["accessors"][6]["count"] = 3
        document["nodes"][0]["translation"] = [0.5, 1.0, 0.0]
    back = read_glb(edited(tmp_path, motion, short_root, "c.glb"))
    np.testing.assert_array_equal(back.root_positions, np.tile([0.5, 1.0, 0.0], (4, 1)))


@pytest.mark.survivor
def test_reader_takes_times_from_the_first_channel_and_ignores_other_paths(tmp_path):
    motion, _ = glb_dance(4, 30.0, seed=6)

    def extra(document, blob):
        animation = document["animations"][0]
        animation["samplers"].append({"input": 6, "output": 9, "interpolation": "LINEAR"})  # root xs as times, VEC4 values
        animation["channels"].append({"sampler": len(animation["samplers"]) - 1, "target": {"node": 0, "path": "scale"}})
        del document["extras"]["fps"]
    back = read_glb(edited(tmp_path, motion, extra))
    assert back.fps == 30.0
    np.testing.assert_allclose(back.root_positions, motion.root_positions, atol=1e-6)


@pytest.mark.survivor
@pytest.mark.parametrize("frames, fps, stored, shift, expected", [
    (40, 30.0, None, 0.0, 30.0),   # float32 times give 29.99999...: an integer rate within 1e-3 is rounded
    (6, 12.5, None, 0.0, 12.5),    # not near an integer: kept (to float32 precision)
    (2, 24.0, None, 0.0, 24.0),    # two keys are enough to measure the rate
    (5, 20.0, None, 1.0, 20.0),    # keys that start later: the span, not the last time, counts
    (5, 50.0, 50.005, 0.0, 50.005),  # the stored rate, where it is within 1e-3 of the keys'
    (5, 24.0, 40.0, 0.0, 24.0),    # but not a stored rate the keys contradict
    (2, 500.0, 500.5, 0.0, 500.0),  # nor one exactly 1e-3 of the rate away (the bound is strict)
    (5, 24.0, "24", 0.0, 24.0),    # a stored rate that is not a number is ignored
])
def test_reader_frame_rate(tmp_path, frames, fps, stored, shift, expected):
    motion = still_glb(frames, fps=fps)

    def edit(document, blob):
        if stored is None:
            del document["extras"]["fps"]
        else:
            document["extras"]["fps"] = stored
        if shift:
            put_floats(document, blob, 5, np.arange(frames) / fps + shift)
    back = read_glb(edited(tmp_path, motion, edit))
    assert back.fps == pytest.approx(expected, abs=2e-5)
    if isinstance(expected, float) and expected == round(expected) and stored is None:
        assert back.fps == expected  # exactly


@pytest.mark.survivor
def test_reader_names_the_file_when_its_keys_imply_an_impossible_rate(tmp_path):
    motion = still_glb(3, fps=30.0)

    def microseconds(document, blob):
        del document["extras"]["fps"]
        put_floats(document, blob, 5, [0.0, 1e-6, 2e-6])
    path = edited(tmp_path, motion, microseconds)
    assert read_error(path) == f"{path}: fps must be between 1 and 1000, got 1e+06"


@pytest.mark.survivor
def test_reader_frame_rate_exactly_from_extras_where_keys_are_inexact(tmp_path):
    motion = still_glb(7, fps=29.97)
    path = tmp_path / "ntsc.glb"
    path.write_bytes(glb_of(motion))
    assert read_glb(path).fps == 29.97


@pytest.mark.survivor
@pytest.mark.parametrize("times", [[0.0, 0.0, 0.0], [0.0, 0.5, 0.0]])
def test_reader_keys_that_do_not_advance_take_the_stored_rate(tmp_path, times):
    motion = still_glb(3, fps=40.0)
    back = read_glb(edited(tmp_path, motion, lambda document, blob: put_floats(document, blob, 5, times)))
    assert back.fps == 40.0


@pytest.mark.survivor
@pytest.mark.parametrize("extras", ["absent", None, {"fps": None}])
def test_reader_one_key_without_a_stored_rate_is_30_fps(tmp_path, extras):
    def edit(document, blob):
        if extras == "absent":
            del document["extras"]
        else:
            document["extras"] = extras
    back = read_glb(edited(tmp_path, still_glb(1, fps=12.0), edit))
    assert back.fps == 30.0 and back.num_frames == 1


@pytest.mark.survivor
def test_accessor_reader_layouts(tmp_path):
    skeleton = performer(11)
    motion, _ = glb_dance(3, 30.0, seed=5, skeleton=skeleton)
    path = tmp_path / "a.glb"
    path.write_bytes(glb_of(motion))
    document = pygltflib.GLTF2().load_binary(str(path))
    # the first accessor lies at byte 0: the positions, exactly as the closed form has them
    positions = gltf._accessor_array(pygltflib, document, 0)
    assert positions.dtype == np.float64
    np.testing.assert_allclose(positions, expected_mesh(skeleton.offsets)[0], atol=2e-6)
    matrices = gltf._accessor_array(pygltflib, document, 4)
    rest = rest_positions(skeleton.offsets)
    expected = np.tile(np.eye(4), (24, 1, 1))
    expected[:, :3, 3] = -(rest + [0.0, -rest[:, 1].min(), 0.0])
    np.testing.assert_allclose(matrices.reshape(24, 4, 4).transpose(0, 2, 1), expected, atol=1e-6)
    np.testing.assert_array_equal(gltf._accessor_array(pygltflib, document, 5)[:, 0], np.float32(np.arange(3) / 30.0))
    # an explicit tight stride is fine; an accessor offset inside its view is honoured
    document.bufferViews[6].byteStride = 12
    document.accessors[6].byteOffset = 12
    document.accessors[6].count = 2
    np.testing.assert_allclose(gltf._accessor_array(pygltflib, document, 6), motion.root_positions[1:], atol=1e-6)
    message = "glTF accessor layout not supported by choreo's reader"
    document.bufferViews[6].byteStride = 16
    with pytest.raises(MotionFormatError, match=f"^{message}$"):
        gltf._accessor_array(pygltflib, document, 6)
    document.accessors[5].type = "VEC2"
    with pytest.raises(MotionFormatError, match=f"^{message}$"):
        gltf._accessor_array(pygltflib, document, 5)


@pytest.mark.survivor
def test_pygltflib_missing_says_how_to_install(monkeypatch):
    import builtins
    real = builtins.__import__

    def no_pygltflib(name, *args, **kwargs):
        if name == "pygltflib":
            raise ImportError(name)
        return real(name, *args, **kwargs)
    monkeypatch.setattr(builtins, "__import__", no_pygltflib)
    with pytest.raises(MotionFormatError) as raised:
        gltf._gltf()
    assert str(raised.value) == "glTF needs the pygltflib package (pip install pygltflib)"


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("damage", [{"byteOffset": 10**9}, {"bufferView": 99}, {"count": 10**7}])
def test_a_glb_whose_accessors_point_outside_its_buffer_is_refused(tmp_path, damage):
    # Found by fuzzing glTF (175 of 1,500 inputs before the fix): pygltflib loads the document, and
    # the indices and sizes inside it then fail as IndexError / ValueError while reading the dance.
    import json
    import struct

    from choreo.formats.gltf import write_glb

    buffer = io.BytesIO()
    write_glb(small_motion(), buffer)
    data = buffer.getvalue()
    json_length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + json_length])
    for accessor in document["accessors"]:
        accessor.update(damage)
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + json_length:]
    body = struct.pack("<I", len(text)) + b"JSON" + text + rest
    (tmp_path / "bad.glb").write_bytes(b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body)
    with pytest.raises(MotionFormatError, match="glb"):
        read_motion(tmp_path / "bad.glb")


@pytest.mark.hardening
def test_channels_sharing_one_accessor_convert_it_once(tmp_path, monkeypatch):
    def share(document):
        animation = document["animations"][0]
        animation["channels"] += [dict(animation["channels"][1]) for _ in range(2000)]

    path = forged_glb(tmp_path, share)
    conversions = []
    convert = gltf._accessor_array
    monkeypatch.setattr(gltf, "_accessor_array", lambda *a: conversions.append(a[2]) or convert(*a))
    assert read_motion(path).num_frames == 8
    assert len(conversions) == len(set(conversions)) <= 26  # times, root, 24 joints: each once


@pytest.mark.hardening
def test_a_glb_of_more_objects_than_any_dance_is_refused_before_it_is_decoded(tmp_path, monkeypatch):
    """Issue 48, item 13: 100,000 channels on one 8 MB accessor took pygltflib 20-23 s to decode."""
    import time

    handle = io.BytesIO()
    gltf.write_glb(hostile_dance(), handle)
    document, blob = glb_chunks(handle.getvalue())
    document["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": 8 << 20})
    document["accessors"].append({"bufferView": len(document["bufferViews"]) - 1, "componentType": 5126,
                                  "count": (8 << 20) // 16, "type": "VEC4"})
    animation = document["animations"][0]
    animation["samplers"].append({"input": animation["samplers"][0]["input"], "output": len(document["accessors"]) - 1})
    channel = {"sampler": len(animation["samplers"]) - 1, "target": {"node": 1, "path": "rotation"}}
    animation["channels"] += [channel] * 100_000
    document["buffers"][0]["byteLength"] = len(blob) + (8 << 20)
    path = tmp_path / "many.glb"
    path.write_bytes(glb_bytes(document, blob + bytes(8 << 20)))
    assert read_motion(forged_glb(tmp_path, lambda d: None)).num_frames == 8  # choreo's own: 175 objects
    monkeypatch.setattr(gltf, "_gltf", lambda: pytest.fail("decoded before the objects were counted"))
    started = time.perf_counter()
    with pytest.raises(MotionFormatError, match="more than 20,000 JSON objects"):
        read_motion(path)
    assert time.perf_counter() - started < 15


@pytest.mark.fuzz_finding
def test_a_json_chunk_longer_than_the_file_is_refused_before_it_is_allocated(tmp_path):
    """Fuzzing (bvh,glb, seed 7): a glb whose JSON chunk claims 1-2 GB in a 70 kB file made the
    object count's read, and pygltflib's, allocate the claim: a MemoryError under the fuzzer's cap."""
    buffer = io.BytesIO()
    write_glb(still(3), buffer)
    forged = bytearray(buffer.getvalue())
    forged[12:16] = struct.pack("<I", 2**31)
    path = tmp_path / "forged.glb"
    path.write_bytes(bytes(forged))
    with pytest.raises(MotionFormatError) as raised:
        read_glb(path)
    assert str(raised.value) == f"{path}: damaged glb (its JSON chunk reaches past the end of the file)"


# -- round five, item 2: a glb's metadata ----------------------------------------------------------
def looping_emote(frames: int = 60) -> Motion:
    from tests.conftest import wandering_dance

    dancer = wandering_dance(3, frames, 30.0)
    dancer.metadata = {"loop": {"bars": 1, "beats_per_bar": 4, "seconds": frames / 30, "turn_degrees": 90.0,
                                "travel_m": [0.1, -0.2]}, "genre": "waltz", "seed": 3, "source": "song.wav"}
    return dancer


@pytest.mark.hardening
@pytest.mark.parametrize("output", ["back.npz", "back.glb", "back.json"])
def test_a_glbs_metadata_is_read_back(tmp_path, capsys, output):
    """Round five, item 2: converting the glb of a --loop dance (a root bone under it) to NPZ, glb
    or JSON lost its loop (turn and travel) and all other metadata the glb writer keeps in extras."""
    from tests.helpers import run_cli

    write_motion(looping_emote(), tmp_path / "emote.glb", root_motion=True)
    assert read_motion(tmp_path / "emote.glb").metadata == {**looping_emote().metadata, "source": "emote.glb"}
    code, _, err = run_cli(capsys, "convert", tmp_path / "emote.glb", tmp_path / output)
    assert code == 0 and "note" not in err, err
    back = read_motion(tmp_path / output).metadata
    assert back["loop"] == looping_emote().metadata["loop"] and back["genre"] == "waltz" and back["seed"] == 3
    code, _, err = run_cli(capsys, "convert", tmp_path / "emote.glb", tmp_path / "fast.npz", "--fps", "60")
    assert code == 0 and read_motion(tmp_path / "fast.npz").num_frames == 120  # resampled as a loop: whole cycles


@pytest.mark.hardening
@pytest.mark.parametrize("output, named", [("dance.bvh", "dance.bvh"), ("-", "the bvh on stdout")])
def test_writing_metadata_to_a_bvh_says_it_is_dropped(tmp_path, capsys, output, named):
    from tests.helpers import run_cli

    write_motion(looping_emote(), tmp_path / "emote.glb")
    target = output if output == "-" else tmp_path / output
    code, out, err = run_cli(capsys, "convert", tmp_path / "emote.glb", target, "--format", "bvh")
    assert code == 0, err
    named = named if output == "-" else tmp_path / named
    assert err.splitlines()[0] == f"note: {named} cannot hold the dance's metadata (loop, genre, seed): dropped"
    write_motion(still(4), tmp_path / "plain.glb")  # no metadata but its own name: nothing to say
    code, _, err = run_cli(capsys, "convert", tmp_path / "plain.glb", tmp_path / "plain.bvh")
    assert code == 0 and "note" not in err


@pytest.mark.hardening
@pytest.mark.parametrize("loop", [5, "x", {"turn_degrees": "x", "travel_m": [1, 2]}, {"turn_degrees": 9, "travel_m": [1]},
                                  {"turn_degrees": 9, "travel_m": [1, float("nan")]}])
@pytest.mark.parametrize("kind", ["glb", "npz", "json"])
def test_a_damaged_loop_in_a_files_metadata_is_no_loop(tmp_path, capsys, loop, kind):
    """Found with item 2: a ``loop`` that is not one (from any file that keeps metadata) crashed
    ``convert --fps``/``--in-place`` (exit 70, TypeError); it is dropped on reading."""
    from tests.helpers import run_cli

    dancer = looping_emote()
    dancer.metadata = {"loop": loop, "genre": "waltz"}
    write_motion(dancer, tmp_path / f"bad.{kind}")
    assert read_motion(tmp_path / f"bad.{kind}").metadata["genre"] == "waltz"
    assert "loop" not in read_motion(tmp_path / f"bad.{kind}").metadata
    for flag in ("--fps=60", "--in-place"):
        code, _, err = run_cli(capsys, "convert", tmp_path / f"bad.{kind}", tmp_path / "out.npz", flag)
        assert code == 0, err
