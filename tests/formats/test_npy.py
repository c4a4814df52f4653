"""Tests of choreo.formats.npy.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import io

import numpy as np
import pytest

from choreo.errors import MotionFormatError
from choreo.formats import npy


@pytest.mark.survivor
def test_npy_positions_read_as_float64_in_either_layout(tmp_path):
    positions = np.arange(2 * 72, dtype=np.float32).reshape(2, 72) / 7.0
    np.save(tmp_path / "flat.npy", positions)
    back = npy.read_npy_joint_positions(tmp_path / "flat.npy")
    assert back.dtype == np.float64 and back.shape == (2, 24, 3)
    for t in range(2):
        for j in range(24):
            for k in range(3):
                assert back[t, j, k] == np.float32(positions[t, 3 * j + k])
    np.save(tmp_path / "one.npy", np.ones((1, 24, 3), dtype=np.int16))
    np.testing.assert_array_equal(npy.read_npy_joint_positions(tmp_path / "one.npy"), np.ones((1, 24, 3)))


@pytest.mark.survivor
@pytest.mark.parametrize("array, message", [
    (np.zeros((5, 3)), "expected joint positions of shape (T, 24, 3), got (5, 3)"),
    (np.zeros((2, 73)), "expected joint positions of shape (T, 24, 3), got (2, 73)"),
    (np.zeros((0, 24, 3)), "empty, NaN or infinite joint positions"),
    (np.full((1, 24, 3), np.inf), "empty, NaN or infinite joint positions"),
    (np.zeros((1, 24, 3), dtype=bool), "holds bool values, not joint positions"),
])
def test_npy_positions_refusals(tmp_path, array, message):
    path = tmp_path / "bad.npy"
    np.save(path, array)
    with pytest.raises(MotionFormatError) as error:
        npy.read_npy_joint_positions(path)
    assert str(error.value) == f"{path}: {message}"


@pytest.mark.survivor
def test_npy_unreadable_path_names_the_error(tmp_path):
    with pytest.raises(MotionFormatError) as error:
        npy.read_npy_joint_positions(tmp_path)
    assert str(error.value) == f"{tmp_path}: not a readable .npy array (IsADirectoryError)"


@pytest.mark.survivor
def test_npy_writer_stores_float32_positions(dance):
    buffer = io.BytesIO()
    npy.write_npy(dance, buffer)
    buffer.seek(0)
    stored = np.load(buffer)
    assert stored.dtype == np.float32
    np.testing.assert_allclose(stored, dance.joint_positions(), atol=1e-6)
