"""What benchmarks/fuzz_inputs.py found, each rebuilt from bytes made here: a one-line refusal
(or a quiet fallback for optional entries), never an internal error."""

import io
import pickle
import zipfile

import numpy as np
import pytest

from choreo.errors import InputError, MotionFormatError
from choreo.formats import read_joint_positions, read_motion, write_motion
from choreo.formats.safe_arrays import load_npy, load_npz
from choreo.motion import Motion


def npy_with_header(text: str) -> bytes:
    """An .npy whose header dict is ``text`` (padded as numpy pads it), then 48 bytes of data."""
    header = text.encode()
    header += b" " * (64 - 10 - len(header) % 64 - 1) + b"\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header + bytes(48)


def motion(frames: int = 4) -> Motion:
    rng = np.random.default_rng(0)
    return Motion.from_axis_angle(np.zeros((frames, 3)) + [0, 0.9, 0], rng.normal(scale=0.1, size=(frames, 24, 3)))


def npz_bytes(**arrays) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def smpl_arrays(frames: int = 4) -> dict:
    return {"smpl_poses": np.zeros((frames, 72)), "smpl_trans": np.zeros((frames, 3)) + [0, 0.9, 0],
            "smpl_scaling": np.ones(1)}


# -- .npy headers numpy's tokenizer chokes on (TokenError, not ValueError) ------------------------
@pytest.mark.parametrize("header", ["{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3",
                                    "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3))}"])
def test_an_unbalanced_npy_header_is_refused(tmp_path, header):
    path = tmp_path / "bad.npy"
    path.write_bytes(npy_with_header(header))
    with pytest.raises(MotionFormatError, match="not a readable NumPy array"):
        load_npy(path)
    with pytest.raises(MotionFormatError):
        read_joint_positions(path)
    npz = tmp_path / "bad.npz"
    with zipfile.ZipFile(npz, "w") as archive:
        archive.writestr("smpl_poses.npy", npy_with_header(header))
    with pytest.raises(MotionFormatError, match="not a readable NumPy array"):
        load_npz(npz)


def test_a_damaged_npy_version_does_not_make_numpy_read_gigabytes(tmp_path):
    """Version 1.255: numpy would read a 4-byte header length (2 GB here) and ask for that much."""
    data = bytearray(npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"))
    data[7] = 0xFF
    data[10:12] = b"\x00\x7b"
    path = tmp_path / "v1_255.npy"
    path.write_bytes(bytes(data))
    with pytest.raises(MotionFormatError, match="version 1.255"):
        load_npy(path)
    data[6:8] = b"\x02\x00"  # a real version 2.0, whose 4-byte length field now says 2 GB
    path.write_bytes(bytes(data))
    with pytest.raises(MotionFormatError, match="header"):
        load_npy(path)


@pytest.mark.parametrize("descr, shape", [("|V0", "(1000000000000,)"), ("<U3", "(2, 24, 3)"), ("|S4", "(2, 24, 3)")])
def test_npy_of_zero_size_or_text_items_is_refused(tmp_path, descr, shape):
    path = tmp_path / "odd.npy"
    path.write_bytes(npy_with_header(f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}")
                     + bytes(2 * 24 * 3 * 12))
    with pytest.raises(MotionFormatError):
        read_joint_positions(path)


def test_a_float_wav_of_huge_finite_samples_is_refused(tmp_path):
    """2e38 is finite, but the mono mix and the spectra overflow to inf (librosa's error before)."""
    import soundfile as sf

    from choreo.errors import AudioError
    from choreo.music import Music

    rate = 22050
    song = 0.3 * np.sin(2 * np.pi * 330 * np.arange(rate) / rate)
    song[100:200] = 2e38
    path = tmp_path / "loud.wav"
    sf.write(path, np.stack([song, song], 1).astype(np.float32), rate, subtype="FLOAT")
    with pytest.raises(AudioError, match="beyond"):
        Music.from_file(path)


# -- wrong value types in AIST++ pickles and NPZ files ---------------------------------------------
@pytest.mark.parametrize("key, value", [
    ("smpl_scaling", np.zeros(0)),                       # IndexError before
    ("smpl_poses", [[0.0] * 72, [0.0] * 71] * 2),        # ragged lists: numpy's ValueError before
    ("smpl_poses", [["x"] * 72] * 4),                    # text where numbers belong
    ("smpl_trans", None),
    ("smpl_scaling", {"a": 1}),
])  # fmt: skip
def test_pickle_with_wrong_value_types_is_refused(tmp_path, key, value):
    arrays = smpl_arrays()
    arrays[key] = value
    path = tmp_path / "bad.pkl"
    path.write_bytes(pickle.dumps(arrays, protocol=4))
    with pytest.raises(MotionFormatError, match=key):
        read_motion(path)


@pytest.mark.parametrize("fps", [np.zeros(0), np.array("thirty"), np.array([1 + 2j])])
def test_npz_with_an_empty_or_text_fps_is_refused(tmp_path, fps):
    path = tmp_path / "bad.npz"
    path.write_bytes(npz_bytes(**smpl_arrays(), fps=fps))
    with pytest.raises(MotionFormatError, match="fps"):
        read_motion(path)


def test_npz_damaged_optional_entries_are_ignored(tmp_path):
    good = tmp_path / "good.npz"
    write_motion(motion(), good)
    with np.load(good) as archive:
        arrays = {key: archive[key] for key in archive.files}
    arrays.update(offsets=np.full((24, 3), "x"), joint_positions=np.array("text"), metadata=np.array("[" * 5000))
    path = tmp_path / "damaged.npz"
    path.write_bytes(npz_bytes(**arrays))
    read = read_motion(path)
    positions, fps = read_joint_positions(path)
    assert positions.shape == (4, 24, 3) and fps == read.fps
    assert np.allclose(read.rotations, motion().rotations, atol=1e-6)


# -- repertoire arrays that disagree ---------------------------------------------------------------
@pytest.fixture
def repertoire_arrays():
    from choreo.skeleton import SMPL24
    from choreo_graph.config import CLIP_FRAMES
    n = 2  # format 1: every clip's frames in full (still read; format 2 pools them, tests/test_graph.py)
    rotations = np.zeros((n, CLIP_FRAMES, 24, 4), np.float16)
    rotations[..., 0] = 1
    return {"format_version": np.array(1), "names": np.array(["a@0", "a@120"]),
            "genres": np.array(["waltz", ""]), "root_positions": np.zeros((n, CLIP_FRAMES, 3), np.float32),
            "rotations": rotations, "offsets": SMPL24.offsets.astype(np.float32),
            "poses": np.zeros((n, CLIP_FRAMES, 24, 3), np.float16), "style": np.ones((n, 32), np.float32),
            "beat_counts": np.ones(n, np.float32), "tempo": np.ones((n, CLIP_FRAMES), np.float32),
            "source": np.array("test")}


def test_a_consistent_repertoire_loads(tmp_path, repertoire_arrays):
    from choreo_graph.repertoire import Repertoire

    path = tmp_path / "r.npz"
    path.write_bytes(npz_bytes(**repertoire_arrays))
    repertoire = Repertoire.load(path)
    assert len(repertoire) == 2 and repertoire.clip_motion(1).num_frames == 240


@pytest.mark.parametrize("key, value, words", [
    ("root_positions", np.zeros((0, 240, 3), np.float32), "root_positions"),   # IndexError in clip_motion before
    ("style", np.ones((3, 32), np.float32), "style"),
    ("tempo", np.ones((2, 100), np.float32), "tempo"),
    ("beat_counts", np.array(["x", "y"]), "beat_counts"),
    ("poses", np.full((2, 240, 24, 3), np.nan, np.float16), "NaN"),
    ("names", np.array("one"), "empty"),
    ("offsets", np.zeros((23, 3), np.float32), "offsets"),
])  # fmt: skip
def test_repertoire_arrays_that_disagree_are_refused(tmp_path, repertoire_arrays, key, value, words):
    from choreo_graph.repertoire import Repertoire

    repertoire_arrays[key] = value
    path = tmp_path / "r.npz"
    path.write_bytes(npz_bytes(**repertoire_arrays))
    with pytest.raises(InputError, match=words):
        Repertoire.load(path)


def pooled(arrays: dict) -> dict:
    """The format 1 arrays of ``repertoire_arrays`` as format 2: clip 0 at pool frame 0, clip 1 at 120."""
    arrays = dict(arrays, format_version=np.array(2), clip_starts=np.array([0, 120]))
    del arrays["poses"]  # computed from the rotations on reading
    for key in ("root_positions", "rotations"):
        clips = arrays.pop(key)
        arrays[f"pool_{key}"] = np.concatenate([clips[0], clips[1][120:]])
    return arrays


@pytest.mark.parametrize("key, value, words", [
    (None, None, None),  # the consistent file loads
    ("clip_starts", np.array([0, 121]), "clip_starts must be 2 whole numbers from 0 to 120"),  # past the pool's end
    ("clip_starts", np.array([-1, 0]), "clip_starts"),  # numpy would wrap a negative index around
    ("clip_starts", np.array([0.0, 120.0]), "clip_starts"),
    ("clip_starts", np.array([0]), "clip_starts"),
    ("pool_rotations", np.zeros((359, 24, 4), np.float16), "pool_rotations"),
    ("pool_root_positions", np.zeros((360, 4), np.float32), "pool_root_positions"),
    ("pool_root_positions", np.full((360, 3), np.nan, np.float32), "NaN"),
    ("offsets", np.zeros((24, 2), np.float32), "offsets"),
    ("names", np.array("one"), "empty"),
])  # fmt: skip
def test_pooled_repertoires_are_checked_before_clips_are_cut(tmp_path, repertoire_arrays, key, value, words):
    from choreo_graph.repertoire import Repertoire

    arrays = pooled(repertoire_arrays)
    if key is not None:
        arrays[key] = value
    path = tmp_path / "r.npz"
    path.write_bytes(npz_bytes(**arrays))
    if words is None:
        repertoire = Repertoire.load(path)
        np.testing.assert_array_equal(repertoire.root_positions, repertoire_arrays["root_positions"])
        assert repertoire.rotations.shape == (2, 240, 24, 4)
        return
    with pytest.raises(InputError, match=words):
        Repertoire.load(path)


def test_repertoire_text_beyond_unicode_is_refused(tmp_path, repertoire_arrays):
    """numpy loads 4-byte code points unchecked; str.rpartition on one was a SystemError."""
    from choreo_graph.repertoire import Repertoire

    codes = repertoire_arrays["names"].view(np.uint32).copy()
    codes[1] = 0x40000030
    repertoire_arrays["names"] = codes.view(repertoire_arrays["names"].dtype)
    path = tmp_path / "r.npz"
    path.write_bytes(npz_bytes(**repertoire_arrays))
    with pytest.raises(InputError, match="beyond Unicode"):
        Repertoire.load(path)


def test_npz_metadata_beyond_unicode_is_refused(tmp_path):
    """json.loads of such a string was a SystemError."""
    codes = np.array('{"a": 1}').reshape(1).view(np.uint32).copy()
    codes[2] = 0x40000030
    path = tmp_path / "m.npz"
    path.write_bytes(npz_bytes(**smpl_arrays(), metadata=codes.view("<U8").reshape(())))
    with pytest.raises(MotionFormatError, match="beyond Unicode"):
        read_motion(path)


def test_npz_member_named_with_a_newline_gives_one_line(tmp_path):
    path = tmp_path / "n.npz"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("format\nversion.npy", b"\x93NUMPY damaged")
    with pytest.raises(MotionFormatError) as caught:
        load_npz(path)
    assert "\n" not in str(caught.value) and "format\\nversion" in str(caught.value)


# -- SGMD checkpoints whose schedule or layer counts hang or divide by zero ------------------------
@pytest.mark.parametrize("section, key, value, words", [
    ("diffusion_config", "timesteps", 1 << 31, "timesteps"),          # a schedule built step by step: a hang
    ("diffusion_config", "cosine_offset", -1, "cosine_offset"),       # ZeroDivisionError before
    ("diffusion_config", "max_beta", float("nan"), "max_beta"),
    ("model_config", "num_layers", 1 << 16, "num_layers"),            # minutes to lay out, even on meta
    ("model_config", "music_layers", 128, "layers"),                  # more layers than weights in the file
])  # fmt: skip
def test_checkpoint_schedule_and_layer_counts_are_checked_first(tmp_path, tiny_checkpoint, section, key, value, words):
    from choreo_sgmd.checkpoint import load_checkpoint, save_checkpoint
    from choreo_sgmd.generator import SGMDGenerator

    state = load_checkpoint(tiny_checkpoint)
    state[section] = {**state[section], key: value}
    forged = tmp_path / "forged.pt"
    save_checkpoint(state, forged)
    with pytest.raises(InputError, match=words):
        SGMDGenerator(forged)


def test_npz_member_of_an_unknown_compression_method_is_refused(tmp_path):
    """zipfile raises NotImplementedError for it, which nothing caught."""
    buffer = io.BytesIO()
    np.savez(buffer, **smpl_arrays())
    data = bytearray(buffer.getvalue())
    local, central = data.index(b"PK\x03\x04"), data.index(b"PK\x01\x02")
    data[local + 8: local + 10] = (99).to_bytes(2, "little")
    data[central + 10: central + 12] = (99).to_bytes(2, "little")
    path = tmp_path / "method99.npz"
    path.write_bytes(bytes(data))
    with pytest.raises(MotionFormatError, match="not a readable"):
        read_motion(path)


def test_pickle_asking_for_a_global_with_a_newline_gives_one_line(tmp_path):
    """STACK_GLOBAL takes any string: the refusal quoted it, newline and all."""
    def short_unicode(text: str) -> bytes:
        return b"\x8c" + bytes([len(text)]) + text.encode()

    path = tmp_path / "newline.pkl"
    path.write_bytes(b"\x80\x04" + short_unicode("numpy\n_core.numeric") + short_unicode("_frombuffer") + b"\x93).")
    with pytest.raises(MotionFormatError) as caught:
        read_motion(path)
    assert "\n" not in str(caught.value) and "refusing to load" in str(caught.value)


@pytest.mark.parametrize("offset", [1e305, 5e3])  # (non-finite offsets are a damaged optional entry: ignored)
def test_npz_with_absurd_bone_offsets_is_refused_on_read(tmp_path, offset):
    # Found by the long run (ROUNDTRIP): accepted from NPZ, written as BVH, then refused by the BVH
    # reader. Nothing choreo accepts may be something it cannot read back.
    arrays = smpl_arrays()
    offsets = np.tile([0.0, 0.1, 0.0], (24, 1))
    offsets[7] = [0.0, offset, 0.0]
    (tmp_path / "bones.npz").write_bytes(npz_bytes(**arrays, offsets=offsets))
    with pytest.raises(Exception, match="bone offsets must be finite and under 1000 m"):
        read_motion(tmp_path / "bones.npz")


@pytest.mark.parametrize("damage", [{"byteOffset": 10**9}, {"bufferView": 99}, {"count": 10**7}])
def test_a_glb_whose_accessors_point_outside_its_buffer_is_refused(tmp_path, damage):
    # Found by fuzzing glTF (175 of 1,500 inputs before the fix): pygltflib loads the document, and
    # the indices and sizes inside it then fail as IndexError / ValueError while reading the dance.
    import json
    import struct

    from choreo.formats.gltf import write_glb

    buffer = io.BytesIO()
    write_glb(motion(), buffer)
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


def test_a_checkpoint_config_key_with_a_newline_gives_one_line(tmp_path, tiny_checkpoint):
    # Found by the 100,000-input run: the refusal quoted the key, newline and all, on two lines.
    from choreo_sgmd.checkpoint import load_checkpoint, save_checkpoint
    from choreo_sgmd.generator import SGMDGenerator

    state = load_checkpoint(tiny_checkpoint)
    state["model_config"] = {**state["model_config"], "\nstyle_mode": "none"}
    forged = tmp_path / "forged.pt"
    save_checkpoint(state, forged)
    with pytest.raises(InputError, match="damaged SGMD checkpoint") as refused:
        SGMDGenerator(forged)
    assert "\n" not in str(refused.value)


def test_a_protocol_2_pickle_of_an_empty_array_loads_and_bytes_n_does_not(tmp_path):
    # Protocol 2 writes an empty array's data as a call of bytes(); the safe unpickler refused it
    # (a false refusal, noticed while fuzzing). bytes(n) would allocate what the file asks: refused.
    from choreo.formats.safe_pickle import UnsafePickle, load_numpy_pickle

    (tmp_path / "empty.pkl").write_bytes(pickle.dumps({"smpl_poses": np.zeros((0, 72))}, protocol=2))
    assert load_numpy_pickle(tmp_path / "empty.pkl")["smpl_poses"].shape == (0, 72)
    (tmp_path / "bomb.pkl").write_bytes(b"\x80\x02c__builtin__\nbytes\nJ\x00\x00\x00\x40\x85R.")  # bytes(2**30)
    with pytest.raises(UnsafePickle, match="unexpected bytes"):
        load_numpy_pickle(tmp_path / "bomb.pkl")


def motion_json(tmp_path, **changes):
    """A choreo motion JSON of ``motion()`` with top-level entries changed."""
    import json

    write_motion(motion(), tmp_path / "seed.json")
    document = {**json.loads((tmp_path / "seed.json").read_text()), **changes}
    (tmp_path / "bad.json").write_text(json.dumps(document))
    return tmp_path / "bad.json"


@pytest.mark.parametrize("names", [[1e308] * 24, "pelvis", [None] + [f"j{i}" for i in range(23)]])
def test_joint_names_that_are_not_strings_are_refused_on_read(tmp_path, names):
    with pytest.raises(MotionFormatError, match="joint_names must be a list of strings"):
        read_motion(motion_json(tmp_path, joint_names=names))


@pytest.mark.parametrize("changes", [{"parents": [-1.0] + [0.0] * 23}, {"rotations": [0.0, 1.0]}])
def test_float_parents_and_flat_rotations_in_motion_json_are_refused(tmp_path, changes):
    with pytest.raises(MotionFormatError, match="parents must be|malformed motion JSON"):
        read_motion(motion_json(tmp_path, **changes)).joint_positions()


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


@pytest.mark.parametrize("rate", [2, 3999, 1_000_000])
def test_a_wav_claiming_an_absurd_sample_rate_is_refused_at_once(tmp_path, rate):
    """Found by the fuzzer (HANG): a 19 kB WAV whose header said 2 Hz was resampled into 80 minutes of song."""
    import soundfile

    from choreo.errors import AudioError
    from choreo.music.audio import audio_duration

    path = tmp_path / "odd.wav"
    soundfile.write(path, np.zeros(9600, np.float32), rate)
    with pytest.raises(AudioError, match=f"sample rate of {rate} Hz"):
        audio_duration(path)


def test_a_path_csv_header_with_a_newline_is_named_in_one_line(tmp_path):
    """Found by the fuzzer (a two-line refusal): the header's cells were printed as they were."""
    from choreo.constraints.parse import read_root_path
    from choreo.errors import InputError

    path = tmp_path / "path.csv"
    path.write_bytes(b'"\xff\n0",1\n1,1,1\n')
    with pytest.raises(InputError) as raised:
        read_root_path(path)
    assert "\n" not in str(raised.value)
