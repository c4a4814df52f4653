"""FBX through Blender: Blender's own FBX importer reads back the bones, frames and joint positions we meant.

Needs ``blender`` on PATH (or the ``bpy`` module); skipped otherwise, except the test of the error
a user without either gets. About 15 s with Blender 3.4 on 2 cores (four Blender runs).
"""

import io
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import wandering_dance

from choreo.errors import MotionFormatError, OutputError
from choreo.formats import fbx
from choreo.formats.fbx import blender_command, write_fbx, write_fbx_stream
from choreo.formats.rigs import MIXAMO
from choreo.motion import Motion
from choreo.skeleton import JOINT_NAMES, SMPL24

IMPORT_SCRIPT = Path(__file__).parent / "blender" / "import_fbx.py"
FRAMES, FPS = 40, 30.0
needs_blender = pytest.mark.skipif(blender_command() is None, reason="neither Blender nor bpy is installed")


@pytest.fixture(scope="module")
def motion():
    return wandering_dance(2, FRAMES, FPS)


def blender_view(path: Path, out: Path) -> dict:
    """What Blender's FBX importer makes of ``path`` (see tests/blender/import_fbx.py)."""
    command = blender_command(IMPORT_SCRIPT) + [str(path), str(out), fbx._numpy_dir()]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and out.exists(), done.stdout[-2000:] + done.stderr[-2000:]
    return json.loads(out.read_text())


def to_blender(positions: np.ndarray) -> np.ndarray:
    """choreo's Y-up (x, y, z) as Blender's Z-up world: (x, -z, y)."""
    return np.stack([positions[..., 0], -positions[..., 2], positions[..., 1]], axis=-1)


@pytest.fixture(scope="module", params=["smpl", "mixamo"])
def seen(request, motion, tmp_path_factory):
    if blender_command() is None:
        pytest.skip("neither Blender nor bpy is installed")
    folder = tmp_path_factory.mktemp(f"fbx_{request.param}")
    path = folder / "dance.fbx"
    write_fbx(motion, path, rig=None if request.param == "smpl" else request.param)
    assert path.read_bytes().startswith(b"Kaydara FBX Binary")
    return request.param, blender_view(path, folder / "seen.json")


@needs_blender
def test_bones_hierarchy_and_frames(seen):
    rig, view = seen
    if rig == "smpl":
        names, parents = list(JOINT_NAMES), {n: (None if p < 0 else JOINT_NAMES[p]) for n, p in zip(JOINT_NAMES, SMPL24.parents)}
    else:
        names, parents = list(MIXAMO.bones), {n: (None if p < 0 else MIXAMO.bones[p]) for n, p in zip(MIXAMO.bones, MIXAMO.parents)}
    assert len(view["bones"]) == len(names) and set(view["bones"]) == set(names)  # no added leaf bones
    assert dict(zip(view["bones"], view["parents"])) == parents
    assert view["frame_end"] - view["frame_start"] + 1 == FRAMES and view["frame_start"] == 1  # our frame 0 at time 0
    assert view["fps"] == pytest.approx(FPS)
    assert [kind for _, kind in view["objects"]] == ["ARMATURE"]


@needs_blender
def test_joint_positions_within_a_centimetre(seen, motion):
    rig, view = seen
    ours = motion.joint_positions()
    joints = [JOINT_NAMES.index(n) if rig == "smpl" else MIXAMO.smpl_joints[MIXAMO.bones.index(n)] for n in view["bones"]]
    heads = np.array(view["heads"])  # (frames, bones, 3), Blender's Z-up metres
    error = np.abs(heads - to_blender(ours[:, joints])).max()
    assert error < 0.01, error


@needs_blender
def test_rest_pose_stands_on_the_floor_in_the_rigs_rest(seen, motion):
    """The FBX's static pose (what engines take as rest) is the rig's rest, not the first frame."""
    rig, view = seen
    rest = dict(zip(view["bones"], np.array(view["rest_heads"])))
    if rig == "smpl":
        expected = to_blender(motion.skeleton.rest_positions())
        got = np.array([rest[name] for name in JOINT_NAMES])
        np.testing.assert_allclose(got - got[0], expected, atol=1e-4)
    else:  # Mixamo's T-pose: arms level along +-X, legs plumb
        for side in ("Left", "Right"):
            arm = np.array([rest[f"mixamorig:{side}{n}"] for n in ("Arm", "ForeArm", "Hand")])
            assert np.ptp(arm[:, 1:], axis=0).max() < 1e-4 and np.ptp(arm[:, 0]) > 0.4
            leg = np.array([rest[f"mixamorig:{side}{n}"] for n in ("UpLeg", "Leg", "Foot")])
            assert np.ptp(leg[:, :2], axis=0).max() < 1e-4 and np.ptp(leg[:, 2]) > 0.7
    heads = np.array(view["rest_heads"])
    assert abs(heads[:, 0].mean()) < 0.1 and abs(heads[:, 1].mean()) < 0.1  # at the origin
    assert -0.01 < heads[:, 2].min() < 0.1  # standing on the floor (only End Site tips reach lower)


@needs_blender
def test_stream_writer_gives_the_same_kind_of_file(motion):
    buffer = io.BytesIO()
    write_fbx_stream(motion.slice_frames(0, 3), buffer, rig="mixamo")
    assert buffer.getvalue().startswith(b"Kaydara FBX Binary") and len(buffer.getvalue()) > 10_000


def test_without_blender_one_line_says_how_to_get_it(monkeypatch, motion, tmp_path):
    monkeypatch.setattr(fbx, "blender_command", lambda: None)
    with pytest.raises(OutputError) as raised:
        write_fbx(motion, tmp_path / "dance.fbx")
    message = str(raised.value)
    assert "\n" not in message and "apt install blender" in message and "pip install bpy" in message
    assert not (tmp_path / "dance.fbx").exists()


def test_refuses_other_skeletons(tmp_path):
    other = SMPL24.__class__(JOINT_NAMES[:23], SMPL24.parents[:23], SMPL24.offsets[:23])
    with pytest.raises(MotionFormatError):
        write_fbx(Motion.rest(3, skeleton=other), tmp_path / "x.fbx")


@needs_blender
def test_the_fbx_curves_of_a_spinning_dancer_do_not_wrap(tmp_path):
    """Issue 47: a root turning two and a half times and a limb through 70 degrees either way. The
    FBX Blender builds keeps continuous curves (its importer makes each frame's Euler compatible
    with the last, and choreo's BVH already is): no key steps anywhere near 360 degrees."""
    frames = 150
    t = np.linspace(0.0, 1.0, frames)
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 0, 1] = 5 * np.pi * t
    axis_angle[:, 16, 0] = np.pi * (t - 0.5) * 1.6
    write_fbx(Motion.from_axis_angle(np.tile([0.0, 0.9, 0.0], (frames, 1)), axis_angle), tmp_path / "spin.fbx")
    script = Path(__file__).parent / "blender" / "fbx_curves.py"
    command = blender_command(script) + [str(tmp_path / "spin.fbx"), str(tmp_path / "curves.json")]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    curves = json.loads((tmp_path / "curves.json").read_text())
    assert curves["curves"] > 24 and curves["largest_step"] < 90
