"""Tests of choreo.formats.safe_pickle.

Markers say where a test came from: fuzz_finding, survivor (pyproject.toml, tests/README.md)."""

import io
import pickle

import numpy as np
import pytest

from choreo.errors import MotionFormatError
from choreo.formats import (
    read_motion,
    registry,
    safe_pickle,
)
from choreo.formats.safe_pickle import MAX_DEPTH, MAX_MEMO_INDEX, UnsafePickle, check_opcodes, load_numpy_pickle
from tests.formats.helpers import TOLERANCE, max_joint_error, random_motion


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


def refused(call, message):
    with pytest.raises(UnsafePickle) as error:
        call()
    assert str(error.value) == message


def dtype_state(order="<"):
    return (3, order, None, None, None, -1, -1, 0)  # numpy's own dtype state for a plain number


@pytest.mark.survivor
def test_dtype_record_byte_orders():
    record = safe_pickle._DTypeRecord("f8")
    assert record.byteorder == "=" and record.resolve() == np.dtype("=f8")
    for order, expected in (("<", "<f8"), (">", ">f8"), ("|", "=f8"), ("=", "=f8")):
        record = safe_pickle._DTypeRecord("f8", False, True)
        record.__setstate__(dtype_state(order))
        assert record.byteorder == order and record.resolve() == np.dtype(expected)
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__(dtype_state("!")), "bad byte order '!'")
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__([3, "<", None, None, None, -1, -1, 0]),
            "structured or sub-array dtypes are not allowed")
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__((3, "<", None, ("x",), None, -1, -1, 0)),
            "structured or sub-array dtypes are not allowed")
    refused(lambda: safe_pickle._DTypeRecord("f8").__setstate__((3, "<", (np.float64, (2,)), None, None, -1, -1, 0)),
            "structured or sub-array dtypes are not allowed")
    refused(lambda: safe_pickle._DTypeRecord("O8"), "dtype 'O8' is not a plain numeric type")


def array_record(shape, dtype, fortran, raw):
    record = safe_pickle._ArrayRecord()
    record.__setstate__((1, shape, dtype, fortran, raw))
    return record.array


@pytest.mark.survivor
def test_array_records_rebuild_c_and_fortran_arrays():
    values = np.arange(6, dtype="<i4")
    dtype = safe_pickle._DTypeRecord("i4")
    np.testing.assert_array_equal(array_record((2, 3), dtype, False, values.tobytes()), [[0, 1, 2], [3, 4, 5]])
    np.testing.assert_array_equal(array_record((2, 3), dtype, True, values.tobytes()), [[0, 2, 4], [1, 3, 5]])
    assert array_record((0,), dtype, False, b"").shape == (0,)
    np.testing.assert_array_equal(array_record((2,), dtype, False, np.array([1, 2], "<i4").tobytes().decode("latin1")), [1, 2])
    refused(lambda: array_record((2,), "i4", False, b"\0" * 8), "array without a plain dtype")
    refused(lambda: safe_pickle._ArrayRecord().__setstate__([1, (2,), dtype, False, b"\0" * 8]), "unexpected array state")
    refused(lambda: array_record((2,), dtype, False, 12345), "array data is not raw bytes")
    refused(lambda: array_record((-1,), dtype, False, b""), "bad array shape (-1,)")
    refused(lambda: array_record([2], dtype, False, b"\0" * 8), "bad array shape [2]")
    refused(lambda: array_record((3,), dtype, False, b"\0" * 8), "array of shape (3,) does not match its 8 bytes")


@pytest.mark.survivor
def test_frombuffer_scalar_codec_and_reconstruct_stand_ins():
    dtype = safe_pickle._DTypeRecord("f4")
    record = safe_pickle._frombuffer(np.array([1.5, 2.5], "=f4").tobytes(), dtype, (2,), "C")
    np.testing.assert_array_equal(record.array, [1.5, 2.5])
    refused(lambda: safe_pickle._frombuffer(b"", "f4", (0,), "C"), "array without a plain dtype")
    refused(lambda: safe_pickle._frombuffer(b"", dtype, (0,), "K"), "array without a plain dtype")
    assert safe_pickle._scalar(dtype, np.array([2.5], "=f4").tobytes()) == 2.5
    refused(lambda: safe_pickle._scalar("f4", b"\0" * 4), "scalar without a plain dtype")
    refused(lambda: safe_pickle._scalar(dtype, b"\0" * 8), "scalar of the wrong size")
    assert safe_pickle._encode("\xe9", "latin1") == b"\xe9" and safe_pickle._encode("\xff", "latin-1") == b"\xff"
    refused(lambda: safe_pickle._encode("\xe9", "utf-8"), "unexpected codec call")
    refused(lambda: safe_pickle._encode(b"x", "latin1"), "unexpected codec call")
    refused(lambda: safe_pickle._reconstruct(list, (0,), b"b"), "only numpy arrays may be reconstructed")
    assert isinstance(safe_pickle._reconstruct(safe_pickle._NdarrayMarker, (0,), b"b"), safe_pickle._ArrayRecord)


@pytest.mark.survivor
def test_encode_refuses_the_default_codec():
    refused(lambda: safe_pickle._encode("abc"), "unexpected codec call")


@pytest.mark.survivor
def test_unpickler_names_what_it_refuses():
    unpickler = safe_pickle._StandInUnpickler(io.BytesIO(b""))
    assert unpickler.find_class("numpy", "dtype") is safe_pickle._DTypeRecord
    refused(lambda: unpickler.find_class("os", "system"), "refusing to load os.system")
    refused(lambda: unpickler.find_class("os\n", "system"), "refusing to load 'os\\n.system'")


@pytest.mark.survivor
def test_materialiser_counts_and_refuses():
    build = safe_pickle._Materialiser()
    shared = [1, 2]
    value, size = build._build({"a": shared, "b": (shared, 3)}, 0)
    assert value == {"a": [1, 2], "b": ([1, 2], 3)} and isinstance(value["b"], tuple) and isinstance(value["a"], list)
    assert value["a"] is value["b"][0]  # a shared list is built once
    assert size == 1 + 3 + (1 + 3 + 1)  # a literal count: every container and item of the unfolded tree
    assert build.total == 3 + 3 + 5 + 9  # every built node, shared ones again each time they are reached
    assert safe_pickle._Materialiser()._build(safe_pickle._ArrayRecord.of(np.zeros(2)), 0)[1] == 1
    assert safe_pickle._Materialiser().total == 0
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._ArrayRecord()), "array without data")
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._DTypeRecord("f8")), "stray numpy object")
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._NdarrayMarker), "stray numpy object")
    refused(lambda: safe_pickle._Materialiser()(safe_pickle._NdarrayMarker()), "stray numpy object")


def chain(items, wraps):
    """A list of ``items`` ones inside ``wraps`` single-item lists: every list is reached once, and
    the total the materialiser counts (container sizes) is (items + 1) + (items + 2) + ... + (items + 1 + wraps)."""
    value = [1] * items
    for _ in range(wraps):
        value = [value]
    return value


@pytest.mark.survivor
def test_materialiser_limits_on_one_tree_and_on_the_total(monkeypatch):
    monkeypatch.setattr(safe_pickle, "MAX_OBJECTS", 100)
    message = "pickle unfolds into more than 100 values"
    assert len(safe_pickle._Materialiser()([0] * 99)) == 99  # 100 nodes: at the limit
    refused(lambda: safe_pickle._Materialiser()([0] * 100), message)
    assert sum(range(4, 29)) == 400 and sum(range(4, 30)) == 429
    assert safe_pickle._Materialiser()(chain(3, 24)) == chain(3, 24)  # a total of exactly 400 = 4 x 100
    refused(lambda: safe_pickle._Materialiser()(chain(3, 25)), message)  # 429


@pytest.mark.survivor
def test_pickled_python2_text_and_errors_name_their_cause(tmp_path):
    path = tmp_path / "p.pkl"
    path.write_bytes(pickle.dumps({"name": "caf\xe9"}, protocol=2))
    assert safe_pickle.load_numpy_pickle(path) == {"name": "caf\xe9"}
    path.write_bytes(b"\x80\x02U\x04caf\xe9q\x00.")  # a Python 2 str (bytes) read as latin-1 text
    assert safe_pickle.load_numpy_pickle(path) == "caf\xe9"
    path.write_bytes(b"\x80\x02]q\x00h\x01.")  # a memo GET of an index never PUT
    refused(lambda: safe_pickle.load_numpy_pickle(path), "unreadable pickle (UnpicklingError)")


@pytest.mark.survivor
def test_empty_bytes_and_the_format_list():
    assert safe_pickle._empty_bytes() == b""
    refused(lambda: safe_pickle._empty_bytes(10), "unexpected bytes() call")
    assert [f.name for f in registry.list_formats()] == ["bvh", "npz", "pkl", "json", "npy", "glb", "fbx"]


@pytest.mark.survivor
def test_pickle_file_size_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(safe_pickle, "MAX_FILE_BYTES", 3 << 20)
    path = tmp_path / "p.pkl"
    data = pickle.dumps({"a": 1}, protocol=2)
    path.write_bytes(data + b"\0" * ((3 << 20) - len(data)))  # exactly at the limit: read up to its STOP
    assert safe_pickle.load_numpy_pickle(path) == {"a": 1}
    path.write_bytes(data + b"\0" * ((3 << 20) - len(data) + 1))
    refused(lambda: safe_pickle.load_numpy_pickle(path), "file is larger than 3 MiB")


# -- safe pickle -------------------------------------------------------------------------------
@pytest.mark.survivor
def test_unpickler_running_out_of_stack_is_an_unsafe_pickle(tmp_path, monkeypatch):
    """safe_pickle.load_numpy_pickle mutants 17-19: a RecursionError while unpickling is reported
    as one line. No file found reaches it (Python's unpickler builds nesting without recursion),
    so the stand-in lookup is made to raise it."""
    path = tmp_path / "a.pkl"
    path.write_bytes(pickle.dumps({"smpl_poses": np.zeros((1, 72))}, protocol=4))
    assert load_numpy_pickle(path)["smpl_poses"].shape == (1, 72)  # a good file

    def too_deep(self, module, name):
        raise RecursionError("maximum recursion depth exceeded")
    monkeypatch.setattr(safe_pickle._StandInUnpickler, "find_class", too_deep)
    with pytest.raises(UnsafePickle) as raised:
        load_numpy_pickle(path)
    assert str(raised.value) == "pickle nests too deeply"


def nested(depth: int):
    value = [1.0]
    for _ in range(depth):
        value = [value]
    return value


@pytest.mark.survivor
def test_nesting_is_allowed_up_to_the_limit_and_refused_past_it(tmp_path):
    # nested(d): d + 1 lists, the innermost value at depth d + 1 (the outermost list is depth 0)
    (tmp_path / "ok.pkl").write_bytes(pickle.dumps(nested(MAX_DEPTH - 1), protocol=2))
    assert load_numpy_pickle(tmp_path / "ok.pkl") == nested(MAX_DEPTH - 1)
    (tmp_path / "deep.pkl").write_bytes(pickle.dumps(nested(MAX_DEPTH), protocol=2))
    with pytest.raises(UnsafePickle, match=f"^pickle nests containers more than {MAX_DEPTH} deep$"):
        load_numpy_pickle(tmp_path / "deep.pkl")


@pytest.mark.survivor
def test_memo_indices_up_to_the_limit_pass_the_opcode_check():
    def put(index):  # protocol 2: an empty dict, LONG_BINPUT index, STOP
        return b"\x80\x02}r" + index.to_bytes(4, "little") + b"."

    check_opcodes(put(MAX_MEMO_INDEX))
    with pytest.raises(UnsafePickle, match="^pickle memo index out of range$"):
        check_opcodes(put(MAX_MEMO_INDEX + 1))
    with pytest.raises(UnsafePickle, match=r"^pickle opcode INST is not allowed$"):
        check_opcodes(b"(ios\nsystem\n.")
    with pytest.raises(UnsafePickle, match=r"^malformed pickle \(ValueError\)$"):
        check_opcodes(b"\x80\x02\xff")


@pytest.mark.survivor
def test_bytes_in_python2_style_pickles_come_back(tmp_path):
    value = {"raw": b"\x00\xff\x10abc", "text": "bal\u00e9"}
    (tmp_path / "bytes.pkl").write_bytes(pickle.dumps(value, protocol=2))  # bytes go through codecs.encode(.., 'latin1')
    assert load_numpy_pickle(tmp_path / "bytes.pkl") == value


@pytest.mark.fuzz_finding
def test_a_protocol_2_pickle_of_an_empty_array_loads_and_bytes_n_does_not(tmp_path):
    # Protocol 2 writes an empty array's data as a call of bytes(); the safe unpickler refused it
    # (a false refusal, noticed while fuzzing). bytes(n) would allocate what the file asks: refused.
    from choreo.formats.safe_pickle import UnsafePickle, load_numpy_pickle

    (tmp_path / "empty.pkl").write_bytes(pickle.dumps({"smpl_poses": np.zeros((0, 72))}, protocol=2))
    assert load_numpy_pickle(tmp_path / "empty.pkl")["smpl_poses"].shape == (0, 72)
    (tmp_path / "bomb.pkl").write_bytes(b"\x80\x02c__builtin__\nbytes\nJ\x00\x00\x00\x40\x85R.")  # bytes(2**30)
    with pytest.raises(UnsafePickle, match="unexpected bytes"):
        load_numpy_pickle(tmp_path / "bomb.pkl")
