"""Tests of choreo.formats.registry.

Markers say where a test came from: fuzz_finding, hardening, survivor (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import io
import pickle
import re
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from choreo.errors import ChoreoError, InputError, MotionFormatError, OutputError, ParameterError
from choreo.formats import (
    bvh,
    json_format,
    read_joint_positions,
    read_motion,
    registry,
    smpl_params,
    write_motion,
    write_motions,
)
from choreo.formats.fbx import NO_BLENDER
from choreo.formats.rigs import MIXAMO
from choreo.motion import Motion
from choreo.skeleton import SMPL24
from tests.formats.helpers import (
    TOLERANCE,
    max_joint_error,
    npy_with_header,
    npz_bytes,
    random_motion,
    save_npz,
    small_motion,
    smpl_arrays,
    still,
)
from tests.formats.hostile import forged_glb, hostile_dance


@pytest.mark.parametrize("extension", [".bvh", ".npz", ".pkl", ".json"])
@pytest.mark.parametrize("fps", [30.0, 60.0])
def test_round_trip_below_a_tenth_of_a_millimetre(tmp_path, extension, fps):
    motion = random_motion(fps=fps, wild=True)
    path = tmp_path / f"dance{extension}"
    write_motion(motion, path)
    back = read_motion(path, format="pkl") if extension == ".pkl" else read_motion(path)
    assert back.num_frames == motion.num_frames and back.fps == fps
    assert max_joint_error(back, motion) < TOLERANCE


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


@pytest.mark.survivor
def test_format_names_and_extensions():
    assert registry._format_for("a.txt", ".BVH", InputError) is registry.FORMATS["bvh"]
    assert registry._format_for("a.txt", "Npz", InputError) is registry.FORMATS["npz"]
    for path, format, message in (
        ("a.bvh", "abc", "unknown motion format 'abc' (supported: bvh, npz, pkl, json, npy, glb, fbx)"),
        ("folder/noext", None, "folder/noext: unknown motion file type '(none)' "
                               "(supported: .bvh, .npz, .pkl, .json, .npy, .glb, .fbx)"),
        ("a.txt", None, "a.txt: unknown motion file type '.txt' (supported: .bvh, .npz, .pkl, .json, .npy, .glb, .fbx)"),
    ):
        with pytest.raises(OutputError) as error:
            registry._format_for(path, format, OutputError)
        assert str(error.value) == message


@pytest.mark.survivor
def test_reading_refuses_missing_folders_empty_and_write_only_files(tmp_path):
    (tmp_path / "empty.bvh").write_bytes(b"")
    (tmp_path / "x.npy").write_bytes(b"x")
    (tmp_path / "x.fbx").write_bytes(b"x")
    for read in (registry.read_motion, registry.read_joint_positions):
        for name, kind, message in (("none.bvh", InputError, "{}: no such file"),
                                    ("", InputError, "{} is a folder, expected a motion file"),
                                    ("empty.bvh", MotionFormatError, "{} is empty"),
                                    ("x.fbx", InputError, "{}: choreo writes .fbx files but does not read them")):
            path = tmp_path / name if name else tmp_path
            with pytest.raises(kind) as error:
                read(path, format="bvh" if not name else None)
            assert str(error.value) == message.format(path)
    with pytest.raises(InputError) as error:
        registry.read_motion(tmp_path / "x.npy")
    assert str(error.value) == f"{tmp_path / 'x.npy'}: a .npy file holds joint positions only, not a rotation-based motion"
    with pytest.raises(InputError):
        registry.read_joint_positions(tmp_path / "x.weird")


@pytest.mark.survivor
def test_an_explicit_format_overrides_the_extension(dance, tmp_path):
    path = tmp_path / "dance.txt"
    with open(path, "wb") as handle:
        json_format.write_json(dance, handle)
    np.testing.assert_allclose(registry.read_motion(path, format="json").joint_positions(), dance.joint_positions(), atol=1e-5)
    positions, fps = registry.read_joint_positions(path, format="json")
    np.testing.assert_allclose(positions, dance.joint_positions(), atol=1e-5)
    assert fps == 30.0


@pytest.mark.survivor
def test_piped_motion_in_a_format_named_only_by_the_caller(dance, monkeypatch):
    """A protocol-1 pickle starts with no signature the sniffer knows: the format must come from the caller."""
    buffer = io.BytesIO()
    arrays = {k: v.astype(np.float64) for k, v in smpl_params.motion_to_smpl_params(dance).items()}
    pickle.dump(arrays, buffer, protocol=1)
    data = buffer.getvalue()
    assert not data.startswith((b"\x80", b"{", b"PK", b"HIERARCHY"))
    for read in (registry.read_motion, registry.read_joint_positions):
        monkeypatch.setattr("sys.stdin", type("Stdin", (), {"buffer": io.BytesIO(data)})())
        result = read("-", format="pkl")
        positions = result.joint_positions() if isinstance(result, Motion) else result[0]
        np.testing.assert_allclose(positions, dance.with_skeleton(SMPL24).joint_positions(), atol=1e-5)


@pytest.mark.survivor
def test_npz_joint_positions_prefer_the_stored_ones(tmp_path):
    poses, trans = smpl_arrays()
    stored = np.arange(2 * 24 * 3, dtype=np.float32).reshape(2, 24, 3)
    path = save_npz(tmp_path, smpl_poses=poses, smpl_trans=trans, joint_positions=stored, fps=np.array(50.0))
    positions, fps = registry.read_joint_positions(path)
    np.testing.assert_array_equal(positions, stored)
    assert fps == 50.0
    bare = tmp_path / "bare.npz"
    np.savez(bare, smpl_poses=poses, smpl_trans=trans)
    positions, _ = registry.read_joint_positions(bare)
    expected = smpl_params.smpl_params_to_motion(poses, trans, None, 30.0, "x").joint_positions()
    np.testing.assert_allclose(positions, expected, atol=1e-12)
    wrong = tmp_path / "wrong.npz"
    np.savez(wrong, smpl_poses=poses, smpl_trans=trans, joint_positions=stored[:1])
    positions, _ = registry.read_joint_positions(wrong)
    np.testing.assert_allclose(positions, expected, atol=1e-12)


@pytest.mark.survivor
def test_output_checks_stdout_rigs_and_blender(monkeypatch):
    with pytest.raises(OutputError) as error:
        registry.check_output_format("-")
    assert str(error.value) == "writing to stdout (-) needs an explicit --format"
    with pytest.raises(ParameterError) as error:
        registry.check_output_format("x.npz", rig="mixamo")
    assert str(error.value) == "--rig mixamo applies to .bvh and .fbx outputs, not .npz"
    monkeypatch.setattr(registry, "blender_command", lambda: None)
    registry.check_output_format("x.bvh")
    with pytest.raises(OutputError) as error:
        registry.check_output_format("x.fbx")
    assert str(error.value) == NO_BLENDER
    monkeypatch.setattr(registry, "blender_command", lambda: ["/opt/blender/blender"])
    registry.check_output_format("x.fbx")


@pytest.mark.survivor
def test_writing_on_a_rig_writes_the_rigs_bones(dance, tmp_path):
    path = tmp_path / "out.bvh"
    assert registry.write_motion(dance, path, rig="mixamo") == str(path)
    names = [j.name for j in bvh.read_bvh_raw(path).joints]
    assert names == list(MIXAMO.bones)
    np.testing.assert_allclose(registry.read_motion(path).joint_positions(), dance.joint_positions(), atol=1e-4)
    many = [str(tmp_path / "a.bvh"), str(tmp_path / "b.json")]
    assert registry.write_motions(dance, many, rig=None) == many
    assert [j.name for j in bvh.read_bvh_raw(many[0]).joints][:2] == ["pelvis", "l_hip"]


@pytest.mark.survivor
def test_writing_several_files_with_a_format_and_a_rig(dance, tmp_path):
    paths = [str(tmp_path / "a.txt"), str(tmp_path / "b.dat")]
    assert registry.write_motions(dance, paths, format="json") == paths
    np.testing.assert_allclose(json_format.read_json(paths[1]).joint_positions(), dance.joint_positions(), atol=1e-5)
    rigged = [str(tmp_path / "c.bvh")]
    registry.write_motions(dance, rigged, rig="mixamo")
    assert bvh.read_bvh_raw(rigged[0]).joints[0].name == "mixamorig:Hips"


# -- registry ----------------------------------------------------------------------------------
@pytest.mark.survivor
def test_rig_writer_for_fbx_is_given_the_rig(monkeypatch):
    """registry._writer mutant 18: the FBX writer receives the rig (its own default is SMPL-24)."""
    calls = []

    def fake_fbx(motion, handle, rig=None):
        calls.append(rig)
        handle.write(b"fbx")
    monkeypatch.setitem(registry.RIG_WRITERS, "fbx", fake_fbx)
    handle = io.BytesIO()
    registry._writer(registry.FORMATS["fbx"], "mixamo")(still(1), handle)
    assert calls == [MIXAMO] and handle.getvalue() == b"fbx"


@pytest.mark.survivor
def test_write_motions_refuses_the_rig_before_touching_any_path(tmp_path):
    """registry.write_motions mutants 3 and 6: the rig is checked for every path up front, so a
    rig the format cannot carry is the error even where the output folder is missing."""
    missing = tmp_path / "no-such-folder" / "dance.npz"
    with pytest.raises(ParameterError) as raised:
        registry.write_motions(still(1), [str(missing)], rig="mixamo")
    assert str(raised.value) == "--rig mixamo applies to .bvh and .fbx outputs, not .npz"


def dance(frames=6) -> Motion:
    rng = np.random.default_rng(0)
    return Motion.from_axis_angle(rng.normal(size=(frames, 3)) * 0.1 + [0, 0.9, 0], rng.normal(size=(frames, 24, 3)) * 0.2)


@pytest.mark.survivor
@pytest.mark.parametrize("keys", [("smpl_poses",), ("smpl_trans",), ()])
def test_a_pickle_without_poses_or_translations_is_named(tmp_path, keys):
    arrays = {"smpl_poses": np.zeros((4, 72)), "smpl_trans": np.zeros((4, 3))}
    path = tmp_path / "part.pkl"
    path.write_bytes(pickle.dumps({k: arrays[k] for k in keys}, protocol=2))
    with pytest.raises(MotionFormatError, match=f"^{re.escape(str(path))}: pickle lacks the smpl_poses and smpl_trans arrays$"):
        read_motion(path)


@pytest.mark.survivor
def test_a_bad_shape_names_the_file(tmp_path):
    path = tmp_path / "shape.pkl"
    path.write_bytes(pickle.dumps({"smpl_poses": np.zeros((4, 71)), "smpl_trans": np.zeros((4, 3))}, protocol=2))
    with pytest.raises(MotionFormatError, match=f"^{re.escape(str(path))}: smpl_poses must have shape"):
        read_motion(path)


@pytest.mark.survivor
def test_written_pickle_is_what_aistpp_tools_read(tmp_path):
    path = tmp_path / "out.pkl"
    write_motion(dance().replace(fps=60.0), path)
    raw = path.read_bytes()
    assert raw[:2] == b"\x80\x04"  # protocol 4: Python 3.4+, as AIST++'s own files
    arrays = pickle.loads(raw)
    assert sorted(arrays) == ["smpl_loss", "smpl_poses", "smpl_scaling", "smpl_trans"]
    assert arrays["smpl_loss"] == 0.0 and isinstance(arrays["smpl_loss"], float)
    assert all(arrays[k].dtype == np.float64 for k in ("smpl_poses", "smpl_trans", "smpl_scaling"))
    assert arrays["smpl_poses"].shape == (6, 72) and arrays["smpl_scaling"].tolist() == [1.0]
    write_motion(dance().replace(fps=30.0), path)  # another rate: one more key, which AIST++'s tools ignore
    assert pickle.loads(path.read_bytes())["fps"] == 30.0 and read_motion(path).fps == 30.0


def smpl_dict(frames: int = 4) -> dict:
    return {"smpl_poses": np.zeros((frames, 72)), "smpl_trans": np.zeros((frames, 3)) + [0, 0.9, 0],
            "smpl_scaling": np.ones(1)}


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("descr, shape", [("|V0", "(1000000000000,)"), ("<U3", "(2, 24, 3)"), ("|S4", "(2, 24, 3)")])
def test_npy_of_zero_size_or_text_items_is_refused(tmp_path, descr, shape):
    path = tmp_path / "odd.npy"
    path.write_bytes(npy_with_header(f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}")
                     + bytes(2 * 24 * 3 * 12))
    with pytest.raises(MotionFormatError):
        read_joint_positions(path)


# -- wrong value types in AIST++ pickles and NPZ files ---------------------------------------------
@pytest.mark.fuzz_finding
@pytest.mark.parametrize("key, value", [
    ("smpl_scaling", np.zeros(0)),                       # IndexError before
    ("smpl_poses", [[0.0] * 72, [0.0] * 71] * 2),        # ragged lists: numpy's ValueError before
    ("smpl_poses", [["x"] * 72] * 4),                    # text where numbers belong
    ("smpl_trans", None),
    ("smpl_scaling", {"a": 1}),
])  # fmt: skip
def test_pickle_with_wrong_value_types_is_refused(tmp_path, key, value):
    arrays = smpl_dict()
    arrays[key] = value
    path = tmp_path / "bad.pkl"
    path.write_bytes(pickle.dumps(arrays, protocol=4))
    with pytest.raises(MotionFormatError, match=key):
        read_motion(path)


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("fps", [np.zeros(0), np.array("thirty"), np.array([1 + 2j])])
def test_npz_with_an_empty_or_text_fps_is_refused(tmp_path, fps):
    path = tmp_path / "bad.npz"
    path.write_bytes(npz_bytes(**smpl_dict(), fps=fps))
    with pytest.raises(MotionFormatError, match="fps"):
        read_motion(path)


@pytest.mark.fuzz_finding
def test_npz_damaged_optional_entries_are_ignored(tmp_path):
    good = tmp_path / "good.npz"
    write_motion(small_motion(), good)
    with np.load(good) as archive:
        arrays = {key: archive[key] for key in archive.files}
    arrays.update(offsets=np.full((24, 3), "x"), joint_positions=np.array("text"), metadata=np.array("[" * 5000))
    path = tmp_path / "damaged.npz"
    path.write_bytes(npz_bytes(**arrays))
    read = read_motion(path)
    positions, fps = read_joint_positions(path)
    assert positions.shape == (4, 24, 3) and fps == read.fps
    assert np.allclose(read.rotations, small_motion().rotations, atol=1e-6)


@pytest.mark.fuzz_finding
def test_npz_metadata_beyond_unicode_is_refused(tmp_path):
    """json.loads of such a string was a SystemError."""
    codes = np.array('{"a": 1}').reshape(1).view(np.uint32).copy()
    codes[2] = 0x40000030
    path = tmp_path / "m.npz"
    path.write_bytes(npz_bytes(**smpl_dict(), metadata=codes.view("<U8").reshape(())))
    with pytest.raises(MotionFormatError, match="beyond Unicode"):
        read_motion(path)


@pytest.mark.fuzz_finding
def test_npz_member_of_an_unknown_compression_method_is_refused(tmp_path):
    """zipfile raises NotImplementedError for it, which nothing caught."""
    buffer = io.BytesIO()
    np.savez(buffer, **smpl_dict())
    data = bytearray(buffer.getvalue())
    local, central = data.index(b"PK\x03\x04"), data.index(b"PK\x01\x02")
    data[local + 8: local + 10] = (99).to_bytes(2, "little")
    data[central + 10: central + 12] = (99).to_bytes(2, "little")
    path = tmp_path / "method99.npz"
    path.write_bytes(bytes(data))
    with pytest.raises(MotionFormatError, match="not a readable"):
        read_motion(path)


@pytest.mark.fuzz_finding
def test_pickle_asking_for_a_global_with_a_newline_gives_one_line(tmp_path):
    """STACK_GLOBAL takes any string: the refusal quoted it, newline and all."""
    def short_unicode(text: str) -> bytes:
        return b"\x8c" + bytes([len(text)]) + text.encode()

    path = tmp_path / "newline.pkl"
    path.write_bytes(b"\x80\x04" + short_unicode("numpy\n_core.numeric") + short_unicode("_frombuffer") + b"\x93).")
    with pytest.raises(MotionFormatError) as caught:
        read_motion(path)
    assert "\n" not in str(caught.value) and "refusing to load" in str(caught.value)


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("offset", [1e305, 5e3])  # (non-finite offsets are a damaged optional entry: ignored)
def test_npz_with_absurd_bone_offsets_is_refused_on_read(tmp_path, offset):
    # Found by the long run (ROUNDTRIP): accepted from NPZ, written as BVH, then refused by the BVH
    # reader. Nothing choreo accepts may be something it cannot read back.
    arrays = smpl_dict()
    offsets = np.tile([0.0, 0.1, 0.0], (24, 1))
    offsets[7] = [0.0, offset, 0.0]
    (tmp_path / "bones.npz").write_bytes(npz_bytes(**arrays, offsets=offsets))
    with pytest.raises(Exception, match="bone offsets must be finite and under 1000 m"):
        read_motion(tmp_path / "bones.npz")


def motion_json(tmp_path, **changes):
    """A choreo motion JSON of ``small_motion()`` with top-level entries changed."""
    import json

    write_motion(small_motion(), tmp_path / "seed.json")
    document = {**json.loads((tmp_path / "seed.json").read_text()), **changes}
    (tmp_path / "bad.json").write_text(json.dumps(document))
    return tmp_path / "bad.json"


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("names", [[1e308] * 24, "pelvis", [None] + [f"j{i}" for i in range(23)]])
def test_joint_names_that_are_not_strings_are_refused_on_read(tmp_path, names):
    with pytest.raises(MotionFormatError, match="joint_names must be a list of strings"):
        read_motion(motion_json(tmp_path, joint_names=names))


@pytest.mark.fuzz_finding
@pytest.mark.parametrize("changes", [{"parents": [-1.0] + [0.0] * 23}, {"rotations": [0.0, 1.0]}])
def test_float_parents_and_flat_rotations_in_motion_json_are_refused(tmp_path, changes):
    with pytest.raises(MotionFormatError, match="parents must be|malformed motion JSON"):
        read_motion(motion_json(tmp_path, **changes)).joint_positions()


@pytest.mark.fuzz_finding
def test_a_renamed_smpl_skeleton_written_to_bvh_reads_back_as_smpl24(tmp_path):
    """Found by the fuzzer (ROUNDTRIP): choreo wrote SMPL-24's tree under other joint names, then
    refused the file as 'not SMPL-24'. Its tree, in SMPL-24's order, now says which joint is which."""
    from choreo.skeleton import SMPL24

    names = list(SMPL24.names)
    names[0], names[9] = "other", "pine3"
    renamed = read_motion(motion_json(tmp_path, joint_names=names))
    write_motion(renamed, tmp_path / "out.bvh")
    back = read_motion(tmp_path / "out.bvh")
    assert back.skeleton.names == SMPL24.names
    np.testing.assert_allclose(back.joint_positions(), renamed.joint_positions(), atol=1e-5)


@pytest.mark.hardening
def test_a_bvh_with_zero_leg_offsets_converts_to_glb_and_mixamo(tmp_path):
    import io

    from choreo.errors import MotionFormatError
    from choreo.formats import read_motion, write_motion
    from choreo.formats.bvh import write_bvh
    from choreo.formats.rigs import retarget
    from choreo.motion import Motion
    from choreo.skeleton import SMPL24

    offsets = SMPL24.offsets.copy()
    offsets[[1, 2, 4, 5, 7, 8, 10, 11]] = 0.0
    motion = Motion.from_axis_angle(np.zeros((4, 3)), np.zeros((4, 24, 3)), fps=30.0,
                                    skeleton=SMPL24.with_offsets(offsets))
    buffer = io.BytesIO()
    write_bvh(motion, buffer)
    (tmp_path / "legless.bvh").write_bytes(buffer.getvalue())
    legless = read_motion(tmp_path / "legless.bvh")
    write_motion(legless, tmp_path / "out.glb")  # was a NaN in the glTF JSON: exit 70
    write_motion(legless, tmp_path / "out.bvh", rig="mixamo")  # was "motion contains NaN"
    assert np.isfinite(read_motion(tmp_path / "out.bvh").joint_positions()).all()
    with pytest.raises(MotionFormatError, match="legs have no length"):
        retarget(legless, "mixamo", lengths="rig")


@pytest.mark.hardening
@pytest.mark.parametrize("field, value", [("count", 2**63), ("count", 2**64 + 5), ("byteOffset", 2**63),
                                          ("count", -1), ("byteOffset", 1.5)])
def test_huge_or_odd_counts_and_offsets_are_a_damaged_file(tmp_path, field, value):
    path = forged_glb(tmp_path, lambda document: document["accessors"][-1].__setitem__(field, value))
    with pytest.raises(MotionFormatError):
        read_motion(path)


@pytest.mark.hardening
def test_sparse_accessors_are_refused_in_one_line(tmp_path):
    sparse = {"count": 1, "indices": {"bufferView": 0, "componentType": 5121}, "values": {"bufferView": 0}}
    path = forged_glb(tmp_path, lambda document: [a.__setitem__("sparse", sparse) for a in document["accessors"]])
    with pytest.raises(MotionFormatError, match="sparse"):
        read_motion(path)


@pytest.mark.hardening
@pytest.mark.parametrize("name", ["l_hip\nMOTION\nFrames: 1", "l hip", "l_hip{", "", "l_hip\x1b[2J", "l_hip\u200b"])
def test_joint_names_that_would_break_a_file_are_refused(tmp_path, name):
    names = list(SMPL24.names)
    names[1] = name
    for extension in (".bvh", ".glb"):
        with pytest.raises(MotionFormatError, match="joint name"):
            write_motion(hostile_dance(names=names), tmp_path / f"out{extension}")
    assert not list(tmp_path.iterdir())


# -- JSON -----------------------------------------------------------------------------------------
@pytest.mark.hardening
@pytest.mark.parametrize("text", ['{"format": "choreo-motion", "rotations": ' + "[" * 10**6 + "]" * 10**6 + "}",
                                  "[" * 10**6, '{"a": ' * 10**5 + "1" + "}" * 10**5])
def test_deeply_nested_motion_json_is_a_format_error(tmp_path, text):
    path = tmp_path / "deep.json"
    path.write_text(text)
    with pytest.raises(MotionFormatError):
        read_motion(path)


# -- where outputs come from, and the preview ------------------------------------------------------
@pytest.mark.hardening
def test_outputs_carry_the_inputs_file_name_not_its_path(tmp_path):
    folder = tmp_path / "private user"
    folder.mkdir()
    write_motion(hostile_dance(), folder / "take.bvh")
    motion = read_motion(folder / "take.bvh")
    assert motion.metadata["source"] == "take.bvh"
    for extension in (".json", ".glb"):
        write_motion(motion, tmp_path / f"out{extension}")
        assert b"private user" not in (tmp_path / f"out{extension}").read_bytes()
    assert read_motion(tmp_path / "out.json").metadata["source"] == "take.bvh"


@pytest.mark.hardening
def test_a_failing_companion_output_leaves_no_motion(tmp_path):
    def fail(temporary):
        raise OutputError("the preview cannot be rendered")

    with pytest.raises(OutputError):
        write_motions(hostile_dance(), [str(tmp_path / "a.bvh"), str(tmp_path / "a.json")],
                      companions={str(tmp_path / "a.mp4"): fail})
    assert list(tmp_path.iterdir()) == []
    written = write_motions(hostile_dance(), [str(tmp_path / "a.bvh")],
                            companions={str(tmp_path / "a.mp4"): lambda temporary: temporary.write_bytes(b"v")})
    assert written == [str(tmp_path / "a.bvh")] and (tmp_path / "a.mp4").read_bytes() == b"v"


@pytest.mark.parametrize("fps", [1e9, "60", float("nan")])
def test_a_pickles_rate_outside_choreos_range_is_refused(tmp_path, fps):
    path = tmp_path / "odd.pkl"
    path.write_bytes(pickle.dumps({**smpl_dict(), "fps": fps}, protocol=4))
    with pytest.raises(MotionFormatError, match="its fps must be a number from 10 to 240"):
        read_motion(path)
