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

from choreo.errors import MotionFormatError, OutputError  # noqa: E402
from choreo.formats import fbx  # noqa: E402
from choreo.formats.fbx import blender_command, write_fbx, write_fbx_stream
from choreo.formats.rigs import MIXAMO
from choreo.motion import Motion  # noqa: E402
from choreo.skeleton import JOINT_NAMES, SMPL24  # noqa: E402
from tests.conftest import wandering_dance
from tests.formats.gltf_helpers import still_glb

IMPORT_SCRIPT = Path(__file__).parents[1] / "blender" / "import_fbx.py"
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


@pytest.fixture(scope="module", params=["smpl", "mixamo", "smpl root motion", "mixamo root motion"])
def seen(request, motion, tmp_path_factory):
    if blender_command() is None:
        pytest.skip("neither Blender nor bpy is installed")
    rig, root_motion = request.param.split()[0], request.param.endswith("root motion")
    folder = tmp_path_factory.mktemp(f"fbx_{rig}")
    path = folder / "dance.fbx"
    write_fbx(motion, path, rig=None if rig == "smpl" else rig, root_motion=root_motion)
    assert path.read_bytes().startswith(b"Kaydara FBX Binary")
    return request.param, blender_view(path, folder / "seen.json")


@needs_blender
def test_bones_hierarchy_and_frames(seen):
    rig, view = seen
    if rig.startswith("smpl"):
        names, parents = list(JOINT_NAMES), {n: (None if p < 0 else JOINT_NAMES[p]) for n, p in zip(JOINT_NAMES, SMPL24.parents)}
    else:
        names, parents = list(MIXAMO.bones), {n: (None if p < 0 else MIXAMO.bones[p]) for n, p in zip(MIXAMO.bones, MIXAMO.parents)}
    if rig.endswith("root motion"):  # a root bone above the hips
        parents = {**parents, names[0]: "root", "root": None}
        names = ["root", *names]
    assert len(view["bones"]) == len(names) and set(view["bones"]) == set(names)  # no added leaf bones
    assert dict(zip(view["bones"], view["parents"])) == parents
    assert view["frame_end"] - view["frame_start"] + 1 == FRAMES and view["frame_start"] == 1  # our frame 0 at time 0
    assert view["fps"] == pytest.approx(FPS)
    assert [kind for _, kind in view["objects"]] == ["ARMATURE"]


@needs_blender
def test_joint_positions_within_a_centimetre(seen, motion):
    rig, view = seen
    ours = motion.joint_positions()
    bones = [k for k, name in enumerate(view["bones"]) if name != "root"]
    joints = [JOINT_NAMES.index(n) if rig.startswith("smpl") else MIXAMO.smpl_joints[MIXAMO.bones.index(n)]
              for n in (view["bones"][k] for k in bones)]
    heads = np.array(view["heads"])  # (frames, bones, 3), Blender's Z-up metres
    error = np.abs(heads[:, bones] - to_blender(ours[:, joints])).max()
    assert error < 0.01, error
    if "root" in view["bones"]:  # at floor level, where the feet are, carrying the travel
        root = heads[:, view["bones"].index("root")]
        assert np.abs(root[:, 2] - np.median(ours[..., 1].min(axis=1))).max() < 0.01
        hips = heads[:, bones[joints.index(0)]]
        assert np.linalg.norm(root[:, :2] - hips[:, :2], axis=-1).max() < 0.5


@needs_blender
def test_rest_pose_stands_on_the_floor_in_the_rigs_rest(seen, motion):
    """The FBX's static pose (what engines take as rest) is the rig's rest, not the first frame."""
    rig, view = seen
    rest = dict(zip(view["bones"], np.array(view["rest_heads"])))
    if rig.startswith("smpl"):
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
    script = Path(__file__).parents[1] / "blender" / "fbx_curves.py"
    command = blender_command(script) + [str(tmp_path / "spin.fbx"), str(tmp_path / "curves.json")]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    curves = json.loads((tmp_path / "curves.json").read_text())
    assert curves["curves"] > 24 and curves["largest_step"] < 90


# -- FBX: Blender replaced ---------------------------------------------------------------------
class FakeBlender:
    """Stands in for ``_run_blender``: records what it was asked and writes an FBX where told."""

    def __init__(self, payload=b"Kaydara FBX Binary  \0fake"):
        self.payload, self.calls = payload, []

    def __call__(self, command, timeout):
        bvh, out, frames, numpy_dir = command[-4:]
        self.calls.append({"command": list(command), "timeout": timeout, "bvh": Path(bvh),
                           "bvh_text": Path(bvh).read_text(), "out": Path(out), "frames": frames, "numpy_dir": numpy_dir})
        if self.payload is not None:
            Path(out).write_bytes(self.payload)


@pytest.mark.survivor
def test_write_fbx_runs_blender_on_a_bvh_in_a_private_folder(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # nothing here is named like a stray relative path
    fake = FakeBlender()
    monkeypatch.setattr(fbx, "blender_command", lambda: ["/opt/blender", "--python", "s.py", "--"])
    monkeypatch.setattr(fbx, "_run_blender", fake)
    motion = still_glb(1)  # one frame is enough
    target = tmp_path / "out.fbx"
    assert fbx.write_fbx(motion, target) == str(target)
    call, = fake.calls
    assert call["command"][:4] == ["/opt/blender", "--python", "s.py", "--"] and len(call["command"]) == 8
    assert call["bvh"].name == "dance.bvh" and call["out"].name == "dance.fbx" and call["bvh"].parent == call["out"].parent
    assert call["bvh"].parent.name.startswith("choreo-fbx-") and not call["bvh"].parent.exists()
    assert call["bvh_text"].startswith("HIERARCHY\nROOT pelvis") and "Frames: 1\n" in call["bvh_text"]
    assert call["frames"] == "1" and call["numpy_dir"] == str(Path(np.__file__).parent.parent)
    assert call["timeout"] == pytest.approx(300.1)
    assert target.read_bytes() == fake.payload


@pytest.mark.survivor
def test_write_fbx_retargets_onto_a_rig_with_a_time_limit_per_frame(monkeypatch, tmp_path):
    fake = FakeBlender(payload=b"x")  # one byte is a file
    monkeypatch.setattr(fbx, "blender_command", lambda: ["blender", "--"])
    monkeypatch.setattr(fbx, "_run_blender", fake)
    fbx.write_fbx(still_glb(10), tmp_path / "rigged.fbx", rig="mixamo")
    call, = fake.calls
    assert call["bvh_text"].startswith("HIERARCHY\nROOT mixamorig:Hips\n") and "Frames: 10\n" in call["bvh_text"]
    assert call["frames"] == "10" and call["timeout"] == pytest.approx(301.0)
    assert (tmp_path / "rigged.fbx").read_bytes() == b"x"


@pytest.mark.survivor
def test_write_fbx_output_failures(monkeypatch, tmp_path):
    monkeypatch.setattr(fbx, "blender_command", lambda: ["blender", "--"])
    monkeypatch.setattr(fbx, "_run_blender", FakeBlender(payload=b""))
    with pytest.raises(OutputError) as raised:
        fbx.write_fbx(still_glb(2), tmp_path / "empty.fbx")
    assert str(raised.value) == "Blender ran but wrote no FBX file"
    monkeypatch.setattr(fbx, "_run_blender", FakeBlender())
    target = tmp_path / "no" / "such" / "folder.fbx"
    with pytest.raises(OutputError) as raised:
        fbx.write_fbx(still_glb(2), target)
    assert str(raised.value) == f"{target}: cannot write (No such file or directory)"


@pytest.mark.survivor
def test_write_fbx_messages(monkeypatch, tmp_path):
    monkeypatch.setattr(fbx, "blender_command", lambda: ["blender", "--"])
    monkeypatch.setattr(fbx, "_run_blender", FakeBlender(payload=None))
    with pytest.raises(MotionFormatError) as raised:
        fbx.write_fbx(Motion(np.zeros((0, 3)), np.zeros((0, 24, 4))), tmp_path / "a.fbx")
    assert str(raised.value) == "FBX export needs at least one frame"
    other = SMPL24.__class__(JOINT_NAMES[:23], SMPL24.parents[:23], SMPL24.offsets[:23])
    with pytest.raises(MotionFormatError) as raised:
        fbx.write_fbx(Motion.rest(2, skeleton=other), tmp_path / "a.fbx")
    assert str(raised.value) == "FBX export supports the SMPL-24 skeleton only"
    with pytest.raises(OutputError) as raised:
        fbx.write_fbx(still_glb(2), tmp_path / "a.fbx")
    assert str(raised.value) == "Blender ran but wrote no FBX file"
    assert not (tmp_path / "a.fbx").exists()


@pytest.mark.survivor
def test_write_fbx_stream_passes_its_rig_and_copies_the_file(monkeypatch):
    seen = []

    def fake_write_fbx(motion, path, rig=None, root_motion=False):
        seen.append((Path(path), rig))
        Path(path).write_bytes(b"FBX-BYTES")
    monkeypatch.setattr(fbx, "write_fbx", fake_write_fbx)
    handle = io.BytesIO()
    fbx.write_fbx_stream(still_glb(2), handle, rig="mixamo")
    (path, rig), = seen
    assert rig == "mixamo" and path.name == "dance.fbx" and path.parent.name.startswith("choreo-fbx-")
    assert handle.getvalue() == b"FBX-BYTES" and not path.parent.exists()


class Done:
    def __init__(self, returncode, stdout="", stderr=""):
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


def fake_run(monkeypatch, outcome):
    """Blender's child process replaced: it ends with ``outcome`` (a Done) or raises it."""
    import contextlib

    calls = []

    class Child:
        returncode = None

        def communicate(self, timeout):
            calls[-1][1]["timeout"] = timeout
            if isinstance(outcome, subprocess.TimeoutExpired):
                raise outcome
            self.returncode = outcome.returncode
            return outcome.stdout, outcome.stderr

    @contextlib.contextmanager
    def child_process(command, **kwargs):
        calls.append((command, kwargs))
        if isinstance(outcome, OSError):
            raise outcome
        yield Child()
    monkeypatch.setattr(fbx, "child_process", child_process)
    return calls


@pytest.mark.survivor
def test_run_blender_call_is_headless_captured_and_time_limited(monkeypatch):
    calls = fake_run(monkeypatch, Done(0, "Error: not fatal", "x"))
    fbx._run_blender(["blender", "--background"], 321.5)
    (command, kwargs), = calls
    assert command == ["blender", "--background"]
    assert kwargs == {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, "text": True, "timeout": 321.5,
                      "stdin": subprocess.DEVNULL, "errors": "replace"}


@pytest.mark.survivor
@pytest.mark.parametrize("outcome, message", [
    (Done(1, stdout="Read dance.bvh\nError: first\nError: second\nError: third\nSaved nothing\n",
          stderr="Warning: old\n"), "Blender could not write the FBX: Error: third"),
    (Done(1, stdout="Error: from stdout", stderr="TypeError: from stderr"), "Blender could not write the FBX: Error: from stdout"),
    (Done(2, stdout="  step one \n\n  step two  \n", stderr=""), "Blender could not write the FBX: step two"),
    (Done(3, stdout="", stderr=" \n"), "Blender could not write the FBX: exit 3"),
    (subprocess.TimeoutExpired(["blender"], 123.4), "Blender took longer than 123 s to write the FBX"),
    (FileNotFoundError(2, "No such file or directory"), "cannot run Blender (No such file or directory)"),
    (OSError("exec format wrong"), "cannot run Blender (exec format wrong)"),
])
def test_run_blender_failures_are_one_line(monkeypatch, outcome, message):
    fake_run(monkeypatch, outcome)
    with pytest.raises(OutputError) as raised:
        fbx._run_blender(["blender"], 123.4)
    assert str(raised.value) == message


@pytest.mark.survivor
def test_blender_command_prefers_blender_on_path(monkeypatch):
    monkeypatch.setattr(fbx.shutil, "which", lambda name: "/usr/local/bin/blender" if name == "blender" else None)
    assert fbx.blender_command("/s/x.py") == ["/usr/local/bin/blender", "--background", "--factory-startup",
                                              "--python-exit-code", "1", "--python", "/s/x.py", "--"]
    monkeypatch.setattr(fbx.shutil, "which", lambda name: None)
    monkeypatch.setattr(fbx.importlib.util, "find_spec", lambda name: object() if name == "bpy" else None)
    assert fbx.blender_command("/s/x.py") == [fbx.sys.executable, "/s/x.py", "--"]
    monkeypatch.setattr(fbx.importlib.util, "find_spec", lambda name: None)
    assert fbx.blender_command() is None
