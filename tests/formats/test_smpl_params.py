"""Tests of choreo.formats.smpl_params.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from choreo.errors import MotionFormatError
from choreo.formats import smpl_params
from choreo.motion import Motion
from tests.formats.helpers import smpl_arrays


# -- SMPL parameters --------------------------------------------------------------------------------------
@pytest.mark.survivor
def test_smpl_params_numbers_and_their_refusals():
    assert smpl_params.as_float_array(np.array([1, 2]), "k", "n").dtype == np.float64
    assert smpl_params.as_float_array([1, 2], "k", "n").dtype == np.float64
    assert smpl_params.first_number(np.array([[60, 2]]), "fps", "n") == 60.0
    for call, message in (
        (lambda: smpl_params.as_float_array(np.array(["a"]), "k", "n"), "n: k holds <U1 values, not numbers"),
        (lambda: smpl_params.as_float_array([[1, 2], [3]], "k", "n"), "n: k is not an array of numbers"),
        (lambda: smpl_params.first_number(np.zeros(0), "fps", "n"), "n: fps is empty"),
    ):
        with pytest.raises(MotionFormatError) as error:
            call()
        assert str(error.value) == message


@pytest.mark.survivor
def test_smpl_params_become_a_motion_with_trans_over_scaling():
    poses, trans = smpl_arrays()
    motion = smpl_params.smpl_params_to_motion(poses, trans, None, 60.0, "n.pkl")
    np.testing.assert_allclose(motion.root_positions, trans, atol=1e-12)
    assert motion.metadata == {"source": "n.pkl"} and motion.fps == 60.0
    np.testing.assert_allclose(motion.rotation_matrices()[:, 5], Rotation.from_rotvec(poses[:, 15:18]).as_matrix(), atol=1e-9)
    scaled = smpl_params.smpl_params_to_motion(poses, trans * 95.0, np.array([95.0]), 1.0, "n.pkl")
    np.testing.assert_allclose(scaled.root_positions, trans, atol=1e-12)
    assert scaled.fps == 1.0
    one = smpl_params.smpl_params_to_motion(poses[:1], trans[:1], 1.0, 30.0, "n.pkl")
    assert one.num_frames == 1


@pytest.mark.survivor
@pytest.mark.parametrize("change, message", [
    (dict(poses=np.array([["a"] * 72])), "n.pkl: smpl_poses holds <U1 values, not numbers"),
    (dict(trans=np.array([["a"] * 3] * 2)), "n.pkl: smpl_trans holds <U1 values, not numbers"),
    (dict(scaling=np.zeros(0)), "n.pkl: smpl_scaling is empty"),
    (dict(trans=np.zeros((2, 2))), "n.pkl: smpl_trans must have shape (2, 3), got (2, 2)"),
    (dict(poses=np.zeros((0, 72)), trans=np.zeros((0, 3))), "n.pkl: no frames"),
    (dict(scaling=np.array([np.nan])), "n.pkl: NaN, infinite or non-positive values in SMPL parameters"),
    (dict(scaling=np.array([0.0])), "n.pkl: NaN, infinite or non-positive values in SMPL parameters"),
    (dict(fps=np.inf), "n.pkl: bad frame rate inf"),
    (dict(fps=0.0), "n.pkl: bad frame rate 0.0"),
])
def test_smpl_params_refusals(change, message):
    poses, trans = smpl_arrays()
    args = dict(poses=poses, trans=trans, scaling=None, fps=30.0)
    args.update(change)
    with pytest.raises(MotionFormatError) as error:
        smpl_params.smpl_params_to_motion(args["poses"], args["trans"], args["scaling"], args["fps"], "n.pkl")
    assert str(error.value) == message


@pytest.mark.survivor
def test_motion_to_smpl_params_in_float32_with_scaled_trans(dance):
    params = smpl_params.motion_to_smpl_params(dance, scaling=2.0)
    assert {k: v.dtype for k, v in params.items()} == {"smpl_poses": np.float32, "smpl_trans": np.float32,
                                                       "smpl_scaling": np.float32}
    np.testing.assert_allclose(params["smpl_trans"], dance.root_positions * 2.0, rtol=1e-6)
    np.testing.assert_array_equal(params["smpl_scaling"], [2.0])
    other = dance.skeleton.__class__(dance.skeleton.names[::-1], tuple(range(-1, 23)), dance.skeleton.offsets)
    with pytest.raises(MotionFormatError) as error:
        smpl_params.motion_to_smpl_params(Motion.rest(1, skeleton=other))
    assert str(error.value) == "SMPL parameters need the SMPL-24 skeleton"


@pytest.mark.survivor
def test_first_number_names_its_key_and_file():
    with pytest.raises(MotionFormatError) as error:
        smpl_params.first_number(np.array(["a"]), "fps", "n.npz")
    assert str(error.value) == "n.npz: fps holds <U1 values, not numbers"
