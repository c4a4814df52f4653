"""glTF 2.0 binary: the file says what we mean, to our own reading, to Khronos's validator and to Blender.

The joint positions are recomputed here from the glb alone (accessors decoded and nodes composed in
this file, not by choreo's reader or forward kinematics), so a wrong axis, quaternion order, offset
or time base in the writer fails.
The validator test needs node and the npm package ``gltf-validator`` where node finds it (for
example ``npm install --prefix /tmp/gv gltf-validator`` and ``NODE_PATH=/tmp/gv/node_modules``, or
``npm install -g gltf-validator``); the Blender test needs ``blender`` on PATH. Each is skipped otherwise.
"""

import io
import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

pygltflib = pytest.importorskip("pygltflib")

from choreo.errors import MotionFormatError  # noqa: E402
from choreo.formats.gltf import read_glb, write_glb  # noqa: E402
from choreo.motion import Motion  # noqa: E402
from choreo.skeleton import JOINT_NAMES, SMPL24  # noqa: E402

BLENDER_SCRIPT = Path(__file__).parent / "blender" / "import_glb.py"
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


def test_khronos_validator_finds_no_errors_or_warnings(glb_path, tmp_path):
    node, env = validator_environment()
    script = tmp_path / "validate.js"
    script.write_text(VALIDATE_JS)
    done = subprocess.run([node, str(script), str(glb_path)], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    issues = json.loads(done.stdout)
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]


# -- Blender ---------------------------------------------------------------------------------
def test_blender_imports_our_glb_exactly(glb_path, motion, tmp_path):
    blender = shutil.which("blender")
    if not blender:
        pytest.skip("Blender is not installed")
    numpy_dir = str(Path(np.__file__).parent.parent)  # Debian's Blender glTF importer needs numpy
    result = subprocess.run([blender, "--background", "--factory-startup", "--python-exit-code", "1",
                             "--python", str(BLENDER_SCRIPT), "--", str(glb_path), str(FPS),
                             str(tmp_path / "seen.json"), numpy_dir],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and (tmp_path / "seen.json").exists(), result.stdout[-2000:] + result.stderr[-2000:]
    seen = json.loads((tmp_path / "seen.json").read_text())
    assert len(seen["bones"]) == 24 and set(seen["bones"]) == set(JOINT_NAMES)
    assert seen["frame_end"] - seen["frame_start"] + 1 == FRAMES
    skinned = [mesh for mesh in seen["meshes"] if mesh["deformed_by"]]
    assert len(skinned) == 1 and skinned[0]["groups"] == 24 and skinned[0]["vertices"] > 0
    heads = np.array(seen["heads"])  # (frames, 24, 3), Blender's Z-up: (x, y, z) = (x, -z, y) in ours
    ours = motion.joint_positions()[:, [JOINT_NAMES.index(name) for name in seen["bones"]]]
    ours_in_blender = np.stack([ours[..., 0], -ours[..., 2], ours[..., 1]], axis=-1)
    assert np.abs(heads - ours_in_blender).max() < 1e-3  # under a millimetre
