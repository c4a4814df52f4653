"""AIST++ pickles and the safe unpickler at their edges: exact refusals, exact limits, the file
written byte for byte as AIST++ tools expect. Written from mutants that survived (docs/mutation.md)."""

import pickle
import re

import numpy as np
import pytest

from choreo.errors import MotionFormatError
from choreo.formats import read_motion, write_motion
from choreo.formats.safe_pickle import MAX_DEPTH, MAX_MEMO_INDEX, UnsafePickle, check_opcodes, load_numpy_pickle
from choreo.motion import Motion


def dance(frames=6) -> Motion:
    rng = np.random.default_rng(0)
    return Motion.from_axis_angle(rng.normal(size=(frames, 3)) * 0.1 + [0, 0.9, 0], rng.normal(size=(frames, 24, 3)) * 0.2)


@pytest.mark.parametrize("keys", [("smpl_poses",), ("smpl_trans",), ()])
def test_a_pickle_without_poses_or_translations_is_named(tmp_path, keys):
    arrays = {"smpl_poses": np.zeros((4, 72)), "smpl_trans": np.zeros((4, 3))}
    path = tmp_path / "part.pkl"
    path.write_bytes(pickle.dumps({k: arrays[k] for k in keys}, protocol=2))
    with pytest.raises(MotionFormatError, match=f"^{re.escape(str(path))}: pickle lacks the smpl_poses and smpl_trans arrays$"):
        read_motion(path)


def test_a_bad_shape_names_the_file(tmp_path):
    path = tmp_path / "shape.pkl"
    path.write_bytes(pickle.dumps({"smpl_poses": np.zeros((4, 71)), "smpl_trans": np.zeros((4, 3))}, protocol=2))
    with pytest.raises(MotionFormatError, match=f"^{re.escape(str(path))}: smpl_poses must have shape"):
        read_motion(path)


def test_written_pickle_is_what_aistpp_tools_read(tmp_path):
    path = tmp_path / "out.pkl"
    write_motion(dance(), path)
    raw = path.read_bytes()
    assert raw[:2] == b"\x80\x04"  # protocol 4: Python 3.4+, as AIST++'s own files
    arrays = pickle.loads(raw)
    assert sorted(arrays) == ["smpl_loss", "smpl_poses", "smpl_scaling", "smpl_trans"]
    assert arrays["smpl_loss"] == 0.0 and isinstance(arrays["smpl_loss"], float)
    assert all(arrays[k].dtype == np.float64 for k in ("smpl_poses", "smpl_trans", "smpl_scaling"))
    assert arrays["smpl_poses"].shape == (6, 72) and arrays["smpl_scaling"].tolist() == [1.0]


def nested(depth: int):
    value = [1.0]
    for _ in range(depth):
        value = [value]
    return value


def test_nesting_is_allowed_up_to_the_limit_and_refused_past_it(tmp_path):
    # nested(d): d + 1 lists, the innermost value at depth d + 1 (the outermost list is depth 0)
    (tmp_path / "ok.pkl").write_bytes(pickle.dumps(nested(MAX_DEPTH - 1), protocol=2))
    assert load_numpy_pickle(tmp_path / "ok.pkl") == nested(MAX_DEPTH - 1)
    (tmp_path / "deep.pkl").write_bytes(pickle.dumps(nested(MAX_DEPTH), protocol=2))
    with pytest.raises(UnsafePickle, match=f"^pickle nests containers more than {MAX_DEPTH} deep$"):
        load_numpy_pickle(tmp_path / "deep.pkl")


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


def test_bytes_in_python2_style_pickles_come_back(tmp_path):
    value = {"raw": b"\x00\xff\x10abc", "text": "bal\u00e9"}
    (tmp_path / "bytes.pkl").write_bytes(pickle.dumps(value, protocol=2))  # bytes go through codecs.encode(.., 'latin1')
    assert load_numpy_pickle(tmp_path / "bytes.pkl") == value
