"""Tests of choreo.formats.json_format.

Markers say where a test came from: hardening, survivor (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest

from choreo.errors import MotionFormatError
from choreo.formats import (
    json_format,
)
from choreo.formats.json_format import read_json, write_json
from choreo.motion import Motion
from choreo.skeleton import SMPL24
from tests.formats.helpers import still
from tests.formats.hostile import hostile_dance, peak_bytes


# -- JSON ---------------------------------------------------------------------------------------------------
def precise_motion():
    axis_angle = np.zeros((1, 24, 3))
    axis_angle[0, 0] = [0.123456789, 0.0, 0.0]
    offsets = SMPL24.offsets.copy()
    offsets[1] = [0.12345678, -0.087654321, 0.0]
    return Motion.from_axis_angle([[1.23456789, 0.98765432, -0.11111111]], axis_angle,
                                  skeleton=SMPL24.with_offsets(offsets), metadata={"where": Path("/x/y")})


@pytest.mark.survivor
def test_json_document_fields_and_their_precision():
    motion = precise_motion()
    buffer = io.BytesIO()
    json_format.write_json(motion, buffer)
    document = json.loads(buffer.getvalue())
    assert document["format"] == "choreo-motion" and document["version"] == 1
    assert document["metadata"] == {"where": "/x/y"}
    assert document["offsets"][1] == [0.123457, -0.087654, 0.0]
    assert document["root_positions"] == [[1.234568, 0.987654, -0.111111]]
    assert document["rotations"][0][0] == [0.1234568, 0.0, 0.0]
    positions = np.array(document["joint_positions"])
    assert positions.shape == (1, 24, 3)
    np.testing.assert_allclose(positions, motion.joint_positions(), atol=5.1e-6)
    assert np.abs(positions * 1e5 - np.round(positions * 1e5)).max() < 1e-6  # 5 decimals


@pytest.mark.survivor
def test_json_reads_its_skeleton_and_metadata(tmp_path):
    motion = precise_motion()
    path = tmp_path / "m.json"
    with open(path, "wb") as handle:
        json_format.write_json(motion, handle)
    back = json_format.read_json(path)
    assert back.metadata == {"where": "/x/y", "source": "m.json"}  # like every reader, the file it came from, by name
    np.testing.assert_allclose(back.skeleton.offsets[1], [0.123457, -0.087654, 0.0])
    np.testing.assert_allclose(back.joint_positions(), motion.joint_positions(), atol=1e-5)


@pytest.mark.survivor
@pytest.mark.parametrize("document, message", [
    ({"version": 1}, "not a choreo motion JSON (format field missing)"),
    ({"format": "choreo-motion", "fps": 30}, "malformed motion JSON (KeyError)"),
])
def test_json_refusals(tmp_path, document, message):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(document))
    with pytest.raises(MotionFormatError) as error:
        json_format.read_json(path)
    assert str(error.value) == f"{path}: {message}"


# -- JSON (bugs the reading of these survivors found) ------------------------------------------
def motion_document(**changes) -> dict:
    buffer = io.BytesIO()
    write_json(still(2), buffer)
    document = json.loads(buffer.getvalue())
    document.update(changes)
    return document


@pytest.mark.survivor
@pytest.mark.parametrize("changes, message", [
    ({"fps": 10 ** 400}, "malformed motion JSON (OverflowError)"),  # was an internal error
    ({"root_positions": [[10 ** 400, 0, 0]] * 2}, "motion contains NaN or infinite values"),  # numpy reads it as inf
    ({"fps": 0.5}, "fps must be between 1 and 1000, got 0.5"),  # was Motion's message without the file
])
def test_json_values_a_motion_cannot_hold_name_the_file(tmp_path, changes, message):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(motion_document(**changes)))
    with pytest.raises(MotionFormatError) as raised:
        read_json(path)
    assert str(raised.value) == f"{path}: {message}"


@pytest.mark.hardening
def test_a_motion_json_is_written_in_blocks_of_frames_as_one_dumps_wrote_it(tmp_path, monkeypatch):
    """Issue 48, item 14: ``json.dumps`` of the whole document peaked at 20x the motion (4 GB for 20
    minutes at 120 fps). Streamed a block at a time, the bytes are the same and the writer holds
    about what the NPZ writer holds."""
    from choreo.formats import json_format
    from choreo.formats.npz import write_npz

    monkeypatch.setattr(json_format, "CHUNK_FRAMES", 64)
    for frames in (0, 1, 64, 300):
        motion = hostile_dance(frames)
        motion.metadata["where"] = tmp_path  # written as text (default=str)
        document = {"format": "choreo-motion", "version": 1, "fps": motion.fps, "joint_names": list(SMPL24.names),
                    "parents": list(SMPL24.parents), "offsets": np.round(SMPL24.offsets, 6).tolist(),
                    "root_positions": np.round(motion.root_positions, 6).tolist(),
                    "rotations": np.round(motion.axis_angle(), 7).tolist(),
                    "joint_positions": np.round(motion.joint_positions(), 5).tolist(), "metadata": motion.metadata}
        handle = io.BytesIO()
        json_format.write_json(motion, handle)
        assert handle.getvalue() == json.dumps(document, default=str).encode()
    monkeypatch.setattr(json_format, "CHUNK_FRAMES", 256)
    with open(tmp_path / "dance.json", "wb") as out, open(tmp_path / "dance.npz", "wb") as npz:
        streamed = peak_bytes(json_format.write_json, hostile_dance(6000), out)  # the whole document: 58 MB
        stored = peak_bytes(write_npz, hostile_dance(6000), npz)
    assert streamed < 2 * stored + (2 << 20)
