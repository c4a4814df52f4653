"""Tests of choreo_graph.repertoire.

Markers say where a test came from: fuzz_finding (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.errors import InputError
from tests.formats.helpers import npz_bytes


# -- repertoire arrays that disagree ---------------------------------------------------------------
@pytest.fixture
def repertoire_arrays():
    from choreo.skeleton import SMPL24
    from choreo_graph.config import CLIP_FRAMES
    n = 2  # format 1: every clip's frames in full (still read; format 2 pools them, tests/graph/test_generator.py)
    rotations = np.zeros((n, CLIP_FRAMES, 24, 4), np.float16)
    rotations[..., 0] = 1
    return {"format_version": np.array(1), "names": np.array(["a@0", "a@120"]),
            "genres": np.array(["waltz", ""]), "root_positions": np.zeros((n, CLIP_FRAMES, 3), np.float32),
            "rotations": rotations, "offsets": SMPL24.offsets.astype(np.float32),
            "poses": np.zeros((n, CLIP_FRAMES, 24, 3), np.float16), "style": np.ones((n, 32), np.float32),
            "beat_counts": np.ones(n, np.float32), "tempo": np.ones((n, CLIP_FRAMES), np.float32),
            "source": np.array("test")}


@pytest.mark.fuzz_finding
def test_a_consistent_repertoire_loads(tmp_path, repertoire_arrays):
    from choreo_graph.repertoire import Repertoire

    path = tmp_path / "r.npz"
    path.write_bytes(npz_bytes(**repertoire_arrays))
    repertoire = Repertoire.load(path)
    assert len(repertoire) == 2 and repertoire.clip_motion(1).num_frames == 240


@pytest.mark.fuzz_finding
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


@pytest.mark.fuzz_finding
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


@pytest.mark.fuzz_finding
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
