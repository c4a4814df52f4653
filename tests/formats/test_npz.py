"""Tests of choreo.formats.npz.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import io
import json
from pathlib import Path

import numpy as np
import pytest

from choreo.errors import MotionFormatError
from choreo.formats import (
    npz,
    read_motion,
    write_motion,
)
from choreo.formats.npz import write_npz
from choreo.skeleton import SMPL24
from tests.formats.helpers import random_motion, save_npz, smpl_arrays, still


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


# -- NPZ ------------------------------------------------------------------------------------------------------
@pytest.mark.survivor
def test_npz_written_keys_and_types(dance):
    motion = dance.replace(metadata={"where": Path("/x")})
    buffer = io.BytesIO()
    npz.write_npz(motion, buffer)
    buffer.seek(0)
    stored = dict(np.load(buffer))
    assert stored["joint_positions"].dtype == np.float32 and stored["offsets"].dtype == np.float64
    np.testing.assert_array_equal(stored["offsets"], dance.skeleton.offsets)
    assert json.loads(str(stored["metadata"])) == {"where": "/x"}


@pytest.mark.survivor
def test_npz_reads_offsets_fps_metadata_and_stored_positions(tmp_path):
    poses, trans = smpl_arrays()
    offsets = SMPL24.offsets * 1.1
    positions = np.arange(2 * 24 * 3, dtype=np.float32).reshape(2, 24, 3)
    path = save_npz(tmp_path, smpl_poses=poses, smpl_trans=trans, fps=np.array([25.0]), offsets=offsets,
                    joint_positions=positions, metadata=np.array('{"genre": "pop"}'))
    motion = npz.read_npz(path)
    np.testing.assert_allclose(motion.skeleton.offsets, offsets)
    assert motion.fps == 25.0 and motion.metadata == {"genre": "pop", "source": path.name}
    stored = npz.read_npz_joint_positions(path)
    assert stored.dtype == np.float64
    np.testing.assert_array_equal(stored, positions)


@pytest.mark.survivor
@pytest.mark.parametrize("offsets", [SMPL24.offsets[:23] * 1.1, np.full((24, 3), np.nan), np.full((24, 3), "a")])
def test_npz_damaged_offsets_fall_back_to_the_template(tmp_path, offsets):
    poses, trans = smpl_arrays()
    motion = npz.read_npz(save_npz(tmp_path, smpl_poses=poses, smpl_trans=trans, offsets=offsets))
    np.testing.assert_array_equal(motion.skeleton.offsets, SMPL24.offsets)
    assert motion.fps == 30.0


@pytest.mark.survivor
@pytest.mark.parametrize("arrays, message", [
    (dict(smpl_poses=np.zeros((1, 72))), "NPZ lacks the smpl_poses and smpl_trans arrays"),
    (dict(smpl_trans=np.zeros((1, 3))), "NPZ lacks the smpl_poses and smpl_trans arrays"),
    (dict(smpl_poses=np.zeros((1, 72)), smpl_trans=np.zeros((1, 3)), fps=np.zeros(0)), "fps is empty"),
    (dict(smpl_poses=np.zeros((1, 72)), smpl_trans=np.zeros((1, 2))), "smpl_trans must have shape (1, 3), got (1, 2)"),
])
def test_npz_refusals_name_the_file(tmp_path, arrays, message):
    path = save_npz(tmp_path, **arrays)
    with pytest.raises(MotionFormatError) as error:
        npz.read_npz(path)
    assert str(error.value) == f"{path}: {message}"


# -- npz ---------------------------------------------------------------------------------------
@pytest.mark.survivor
def test_npz_stores_an_integer_frame_rate_as_float64():
    """npz.write_npz mutants 7 and 9: a Motion keeps fps=30 as given (an int); the file's fps is float64."""
    buffer = io.BytesIO()
    write_npz(still(2, fps=30), buffer)
    buffer.seek(0)
    with np.load(buffer, allow_pickle=False) as archive:
        fps = archive["fps"]
    assert fps.dtype == np.float64 and fps.shape == () and float(fps) == 30.0
