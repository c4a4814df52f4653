"""Motion formats: round trips, known poses, foreign channel orders, bad files, atomic writes."""

import io
import math
import pickle
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from choreo.errors import ChoreoError, InputError, MotionFormatError, OutputError
from choreo.formats import parse_bvh, read_joint_positions, read_motion, write_motion
from choreo.formats.bvh import write_bvh
from choreo.motion import Motion
from choreo.skeleton import SMPL24, continuous_euler, euler_to_matrix, matrix_to_euler

TOLERANCE = 1e-4  # 0.1 mm


def random_motion(frames=40, fps=30.0, seed=0, wild=False):
    rng = np.random.default_rng(seed)
    if wild:  # any rotation at all, including angles near 180 degrees
        axis_angle = rng.normal(size=(frames, 24, 3))
        axis_angle *= (rng.uniform(0, math.pi, size=(frames, 24, 1)) / np.linalg.norm(axis_angle, axis=-1, keepdims=True))
    else:
        axis_angle = np.cumsum(rng.normal(scale=0.05, size=(frames, 24, 3)), axis=0)
    root = rng.normal(scale=0.5, size=(frames, 3)) + [0, 0.9, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps, metadata={"seed": 7, "style": "waltz"})


def gimbal_motion():
    """Every joint at the ZXY gimbal lock (X = +-90 deg), where Euler angles are ill-conditioned."""
    rng = np.random.default_rng(3)
    angles = rng.uniform(-math.pi, math.pi, size=(20, 24, 3))
    angles[..., 1] = np.where(rng.random((20, 24)) < 0.5, math.pi / 2, -math.pi / 2) + rng.normal(scale=1e-7, size=(20, 24))
    return Motion.from_rotation_matrices(rng.normal(size=(20, 3)), euler_to_matrix(angles, "ZXY"))


def max_joint_error(a: Motion, b: Motion) -> float:
    return float(np.abs(a.joint_positions() - b.joint_positions()).max())


@pytest.mark.parametrize("extension", [".bvh", ".npz", ".pkl", ".json"])
@pytest.mark.parametrize("fps", [30.0, 60.0])
def test_round_trip_below_a_tenth_of_a_millimetre(tmp_path, extension, fps):
    motion = random_motion(fps=fps, wild=True)
    path = tmp_path / f"dance{extension}"
    write_motion(motion, path)
    back = read_motion(path, format="pkl") if extension == ".pkl" else read_motion(path)
    if extension == ".pkl":  # AIST++ pickles carry no fps: they are 60 fps by definition
        back = back.replace(fps=fps)
    assert back.num_frames == motion.num_frames and back.fps == fps
    assert max_joint_error(back, motion) < TOLERANCE


def test_bvh_round_trip_at_gimbal_lock(tmp_path):
    motion = gimbal_motion()
    write_motion(motion, tmp_path / "lock.bvh")
    assert max_joint_error(read_motion(tmp_path / "lock.bvh"), motion) < TOLERANCE


def bvh_rotation_channels(path) -> np.ndarray:
    """(T, 3 J) the rotation channels of a BVH written by choreo (after the root's 3 positions)."""
    values = np.loadtxt(str(path), skiprows=path.read_text().splitlines().index("MOTION") + 3, ndmin=2)
    return values[:, 3:]


def test_bvh_curves_are_continuous_for_a_spinning_dancer_and_read_back_the_same(tmp_path):
    """A root turning two and a half times and a limb swinging through its middle axis's 90 degrees:
    each frame's Euler triple is the one nearest the previous frame's (no 360 degree wraps, no
    flips to the other solution), and the rotations read back unchanged."""
    frames = 150
    t = np.linspace(0.0, 1.0, frames)
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 0, 1] = 5 * np.pi * t  # the root spins about Y (up)
    axis_angle[:, 16, 0] = np.pi * (t - 0.5) * 1.6  # the left shoulder swings about X through +-72 degrees
    axis_angle[:, 18, :] = np.stack([np.sin(9 * t), np.pi / 2 * np.cos(3 * t), 2 * t], axis=1)  # near gimbal
    motion = Motion.from_axis_angle(np.tile([0.0, 0.9, 0.0], (frames, 1)), axis_angle)
    write_motion(motion, tmp_path / "spin.bvh")
    channels = bvh_rotation_channels(tmp_path / "spin.bvh")
    assert np.abs(np.diff(channels, axis=0)).max() < 45.0  # degrees between frames: no wrap, no flip
    assert np.ptp(channels) > 720  # the spin accumulates instead of wrapping
    back = read_motion(tmp_path / "spin.bvh")
    assert np.abs(back.rotation_matrices() - motion.rotation_matrices()).max() < 1e-5


def test_continuous_euler_keeps_each_rotation():
    rng = np.random.default_rng(3)
    for order in ("ZXY", "XYZ", "YZX"):
        angles = matrix_to_euler(euler_to_matrix(rng.uniform(-np.pi, np.pi, (200, 5, 3)), order), order)
        smooth = continuous_euler(angles)
        np.testing.assert_allclose(euler_to_matrix(smooth, order), euler_to_matrix(angles, order), atol=1e-12)
        step = np.abs(np.diff(smooth, axis=0)).sum(-1)
        assert (step <= np.abs(np.diff(angles, axis=0)).sum(-1) + 1e-9).all()  # never further than as solved


def test_bvh_in_centimetres_reads_back_in_metres(tmp_path):
    motion = random_motion()
    with open(tmp_path / "cm.bvh", "wb") as handle:
        write_bvh(motion, handle, units="cm")
    text = (tmp_path / "cm.bvh").read_text()
    assert "OFFSET 5.858135 -8.228004 -1.766408" in text  # l_hip in centimetres
    assert max_joint_error(read_motion(tmp_path / "cm.bvh"), motion) < TOLERANCE


def test_rest_pose_bvh_gives_the_template(tmp_path):
    motion = Motion.rest(3).translated([0.5, 0.0, -1.0])
    write_motion(motion, tmp_path / "rest.bvh")
    text = (tmp_path / "rest.bvh").read_text()
    assert "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation" in text
    assert "Frame Time: 0.03333333" in text
    positions = read_motion(tmp_path / "rest.bvh").joint_positions()
    np.testing.assert_allclose(positions[0], SMPL24.rest_positions() + motion.root_positions[0], atol=1e-5)


def _bvh_with_order(motion: Motion, order: str) -> str:
    """Our skeleton, written by hand with another rotation order, as another tool might."""
    ours = io.BytesIO()
    write_bvh(motion, ours)
    text = ours.getvalue().decode()
    head = text[: text.index("MOTION")].replace("Zrotation Xrotation Yrotation", " ".join(f"{a}rotation" for a in order))
    depth_first = [0, 1, 4, 7, 10, 2, 5, 8, 11, 3, 6, 9, 12, 15, 13, 16, 18, 20, 22, 14, 17, 19, 21, 23]
    angles = np.degrees(matrix_to_euler(motion.rotation_matrices(), order))[:, depth_first]
    rows = np.concatenate([motion.root_positions, angles.reshape(len(angles), -1)], axis=1)
    body = "\n".join(" ".join(f"{v:.6f}" for v in row) for row in rows)
    return f"{head}MOTION\nFrames: {len(rows)}\nFrame Time: {1 / motion.fps:.8f}\n{body}\n"


@pytest.mark.parametrize("order", ["XYZ", "YXZ", "ZYX"])
def test_bvh_with_another_rotation_order(tmp_path, order):
    motion = random_motion(wild=True)
    (tmp_path / "other.bvh").write_text(_bvh_with_order(motion, order))
    assert max_joint_error(read_motion(tmp_path / "other.bvh"), motion) < TOLERANCE


def test_bvh_with_smpl_names_in_another_style_and_order(tmp_path):
    motion = random_motion()
    write_motion(motion, tmp_path / "a.bvh")
    text = (tmp_path / "a.bvh").read_text()
    for name in sorted(SMPL24.names, key=len, reverse=True):  # m_avg_L_Hip style, as SMPL-to-FBX tools name them
        styled = "m_avg_" + "_".join(part.capitalize() if len(part) > 1 else part.upper() for part in name.split("_"))
        text = text.replace(f"JOINT {name}\n", f"JOINT {styled}\n").replace(f"ROOT {name}\n", f"ROOT {styled}\n")
    assert "m_avg_L_Hip" in text
    (tmp_path / "b.bvh").write_text(text)
    assert max_joint_error(read_motion(tmp_path / "b.bvh"), motion) < TOLERANCE


def test_truncated_bvh(tmp_path):
    write_motion(random_motion(), tmp_path / "a.bvh")
    text = (tmp_path / "a.bvh").read_text()
    for cut in (0.3, 0.8, 0.999):
        (tmp_path / "cut.bvh").write_text(text[: int(len(text) * cut)])
        with pytest.raises(MotionFormatError) as info:
            read_motion(tmp_path / "cut.bvh")
        assert "\n" not in str(info.value) and "cut.bvh" in str(info.value)


def test_bvh_with_another_skeleton(tmp_path):
    text = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 10 0
\t\t}
\t}
}
MOTION
Frames: 1
Frame Time: 0.033333
0 90 0 0 0 0 0 0 0
"""
    (tmp_path / "other.bvh").write_text(text)
    with pytest.raises(MotionFormatError, match="not SMPL-24"):
        read_motion(tmp_path / "other.bvh")
    raw = parse_bvh(text)  # the generic parser still reads it
    assert [j.name for j in raw.joints] == ["Hips", "Spine"] and raw.values.shape == (1, 9)


def test_nan_in_bvh_and_in_npz(tmp_path):
    write_motion(random_motion(), tmp_path / "a.bvh")
    lines = (tmp_path / "a.bvh").read_text().splitlines()
    lines[-3] = " ".join(["nan"] + lines[-3].split()[1:])
    (tmp_path / "nan.bvh").write_text("\n".join(lines) + "\n")
    with pytest.raises(MotionFormatError, match="NaN"):
        read_motion(tmp_path / "nan.bvh")
    poses = np.zeros((4, 72))
    poses[2, 5] = np.inf
    np.savez(tmp_path / "inf.npz", smpl_poses=poses, smpl_trans=np.zeros((4, 3)))
    with pytest.raises(MotionFormatError):
        read_motion(tmp_path / "inf.npz")


def test_npz_has_aistpp_keys_and_reads_plain_aistpp_npz(tmp_path):
    motion = random_motion()
    write_motion(motion, tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz") as data:
        assert data["smpl_poses"].shape == (40, 72) and data["smpl_trans"].shape == (40, 3)
        assert data["joint_positions"].shape == (40, 24, 3) and float(data["fps"]) == 30.0
        assert float(data["smpl_scaling"][0]) == 1.0
    # A bare AIST++-style NPZ: scaled translation, no fps.
    np.savez(tmp_path / "bare.npz", smpl_poses=motion.axis_angle().reshape(40, 72),
             smpl_trans=motion.root_positions * 93.0, smpl_scaling=np.array([93.0]))
    bare = read_motion(tmp_path / "bare.npz")
    assert bare.fps == 30.0
    np.testing.assert_allclose(bare.root_positions, motion.root_positions, atol=1e-9)
    assert read_motion(tmp_path / "a.npz").metadata["style"] == "waltz"


def test_aistpp_pickle_is_read_safely(tmp_path):
    motion = random_motion(fps=60)
    arrays = {"smpl_poses": motion.axis_angle().reshape(-1, 72), "smpl_trans": motion.root_positions * 95.0,
              "smpl_scaling": np.array([95.0]), "smpl_loss": 1.5}
    (tmp_path / "gBR_sBM_cAll_d04_mBR0_ch01.pkl").write_bytes(pickle.dumps(arrays, protocol=2))
    back = read_motion(tmp_path / "gBR_sBM_cAll_d04_mBR0_ch01.pkl")
    assert back.fps == 60.0 and max_joint_error(back, motion) < TOLERANCE

    class Evil:
        def __reduce__(self):
            return (print, ("pwned",))

    (tmp_path / "evil.pkl").write_bytes(pickle.dumps({"smpl_poses": Evil()}))
    with pytest.raises(MotionFormatError):
        read_motion(tmp_path / "evil.pkl")


def test_numpy_pickles_are_rebuilt_exactly(tmp_path):
    from choreo.formats.safe_pickle import load_numpy_pickle

    value = {"c": np.arange(12.0).reshape(3, 4), "f": np.asfortranarray(np.arange(6, dtype="<i4").reshape(2, 3)),
             "big": np.arange(5, dtype=">f4"), "scalar": np.float64(1.5), "flag": np.bool_(True), "list": [1, "x"]}
    for protocol in (2, 4, 5):
        (tmp_path / "a.pkl").write_bytes(pickle.dumps(value, protocol=protocol))
        back = load_numpy_pickle(tmp_path / "a.pkl")
        for key in ("c", "f", "big"):
            np.testing.assert_array_equal(back[key], value[key])
            assert back[key].dtype == value[key].dtype
        assert back["scalar"] == 1.5 and back["flag"] and back["list"] == [1, "x"]


class _HugeArray:
    """Pickles as an ndarray that claims 10^12 float64s but carries 8 bytes."""

    def __reduce__(self):
        from numpy._core.multiarray import _reconstruct

        return _reconstruct, (np.ndarray, (0,), b"b"), (1, (10**12,), np.dtype("f8"), False, b"\0" * 8)


@pytest.mark.parametrize("case, message", [
    (b"\x80\x02}r\xff\xff\xff\x7f.", "memo index"),  # one opcode that would grow the memo to 16 GiB
    (pickle.dumps({"smpl_poses": _HugeArray()}, protocol=2), "does not match its 8 bytes"),
    (pickle.dumps({"smpl_poses": np.zeros(2, dtype=[("a", "f8")])}, protocol=2), "not a plain numeric type"),
    (pickle.dumps({"smpl_poses": np.array([1, None], dtype=object)}, protocol=2), "not a plain numeric type"),
    (pickle.dumps({"smpl_poses": __import__("os").getcwd}, protocol=2), "refusing to load"),
])  # fmt: skip
def test_crafted_pickles_are_refused_before_numpy_sees_them(tmp_path, case, message):
    (tmp_path / "bad.pkl").write_bytes(case)
    with pytest.raises(MotionFormatError, match=message):
        read_motion(tmp_path / "bad.pkl")


def test_dtype_state_is_never_passed_to_numpy(tmp_path):
    """A structured dtype state smuggled behind a plain type code (numpy itself may crash on these)."""
    data = pickle.dumps(np.zeros(3), protocol=2)
    crafted = data.replace(b"NNNJ", b"N(X\x01\x00\x00\x00atNJ", 1)  # names=('a',) instead of None
    assert crafted != data
    (tmp_path / "bad.pkl").write_bytes(crafted)
    from choreo.formats.safe_pickle import UnsafePickle, load_numpy_pickle

    with pytest.raises(UnsafePickle, match="structured"):
        load_numpy_pickle(tmp_path / "bad.pkl")


def test_joint_positions_from_every_format(tmp_path):
    motion = random_motion()
    expected = motion.joint_positions()
    for extension in (".bvh", ".npz", ".json", ".npy"):
        write_motion(motion, tmp_path / f"a{extension}")
        positions, fps = read_joint_positions(tmp_path / f"a{extension}")
        assert positions.shape == (40, 24, 3)
        np.testing.assert_allclose(positions, expected, atol=TOLERANCE)
        assert fps == (None if extension == ".npy" else 30.0)
    with pytest.raises(InputError, match="joint positions only"):
        read_motion(tmp_path / "a.npy")
    np.save(tmp_path / "wrong.npy", np.zeros((10, 17, 3)))
    with pytest.raises(MotionFormatError, match="shape"):
        read_joint_positions(tmp_path / "wrong.npy")


def test_unknown_extensions(tmp_path):
    (tmp_path / "a.c3d").write_bytes(b"x")
    with pytest.raises(InputError, match="unknown motion file type"):
        read_motion(tmp_path / "a.c3d")
    with pytest.raises(OutputError, match="unknown motion file type"):
        write_motion(random_motion(), tmp_path / "a.c3d")
    (tmp_path / "a.fbx").write_bytes(b"x")
    with pytest.raises(InputError, match="writes .fbx files but does not read them"):
        read_motion(tmp_path / "a.fbx")
    with pytest.raises(OutputError, match="unknown motion format"):
        write_motion(random_motion(), tmp_path / "a.bvh", format="c3d")


def test_missing_and_read_only_output_folders_leave_nothing(tmp_path):
    with pytest.raises(OutputError, match="does not exist"):
        write_motion(random_motion(), tmp_path / "missing" / "a.bvh")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if sys.platform != "win32" and not __import__("os").access(locked, __import__("os").W_OK):
            with pytest.raises(OutputError, match="not writable"):
                write_motion(random_motion(), locked / "a.bvh")
    finally:
        locked.chmod(0o700)
    assert list(tmp_path.rglob("a.bvh")) == []


def test_failing_writer_leaves_no_file_and_keeps_the_old_one(tmp_path, monkeypatch):
    target = tmp_path / "dance.bvh"
    target.write_text("previous version")
    import choreo.formats.registry as registry

    def explode(motion, handle):
        handle.write(b"HIERARCHY\npartial")
        raise RuntimeError("disk on fire")

    monkeypatch.setitem(registry.FORMATS, "bvh", registry.FORMATS["bvh"].__class__("bvh", ".bvh", "", None, explode))
    with pytest.raises(RuntimeError):
        write_motion(random_motion(), target)
    assert target.read_text() == "previous version"
    assert [p.name for p in tmp_path.iterdir()] == ["dance.bvh"]


def test_stdout(capsysbinary):
    write_motion(random_motion(frames=3), "-", format="bvh")
    assert capsysbinary.readouterr().out.startswith(b"HIERARCHY")
    with pytest.raises(OutputError, match="--format"):
        write_motion(random_motion(frames=3), "-")


@pytest.fixture(scope="module")
def reference_bvh_text():
    buffer = io.BytesIO()
    write_bvh(random_motion(frames=3), buffer)
    return buffer.getvalue().decode()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_fuzz_bvh_parser_only_raises_our_errors(reference_bvh_text, data):
    text = reference_bvh_text
    kind = data.draw(st.sampled_from(["cut", "replace", "insert", "garbage"]))
    if kind == "cut":
        text = text[: data.draw(st.integers(0, len(text)))]
    elif kind == "replace":
        at = data.draw(st.integers(0, len(text) - 1))
        text = text[:at] + data.draw(st.text(max_size=5)) + text[at + 1:]
    elif kind == "insert":
        at = data.draw(st.integers(0, len(text)))
        text = text[:at] + data.draw(st.sampled_from(["{", "}", " JOINT x ", "nan", "1e999", "\n", "End Site"])) + text[at:]
    else:
        text = data.draw(st.text(max_size=200))
    try:
        motion = parse_bvh(text)
    except ChoreoError:
        return
    assert np.isfinite(motion.values).all()


@settings(max_examples=60, deadline=None)
@given(blob=st.binary(max_size=400), keep=st.integers(0, 2000))
def test_fuzz_npz_and_pkl_readers_only_raise_our_errors(tmp_path_factory, blob, keep):
    folder = tmp_path_factory.mktemp("fuzz")
    valid = io.BytesIO()
    np.savez(valid, smpl_poses=np.zeros((2, 72)), smpl_trans=np.zeros((2, 3)))
    for name, content in (("a.npz", blob), ("b.npz", valid.getvalue()[:keep] + blob), ("c.pkl", blob),
                          ("d.pkl", pickle.dumps({"smpl_poses": np.zeros((2, 72))})[:keep] + blob)):
        (folder / name).write_bytes(content)
        try:
            read_motion(folder / name)
        except ChoreoError:
            pass
