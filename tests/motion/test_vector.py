"""Tests of choreo.motion.vector.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.motion import (
    Motion,
    motion_to_vector,
    vector_to_motion,
)
from tests.motion.helpers import exactly, gram_schmidt, short_random_motion, two_joint_skeleton


@pytest.mark.survivor
def test_frame_vectors_are_float32_and_decoded_in_float64():
    motion = short_random_motion(6, seed=2)
    vectors = motion_to_vector(motion)
    assert vectors.dtype == np.float32
    decoded, contacts = vector_to_motion(vectors, fps=60.0, metadata={"genre": "pop"})
    assert decoded.fps == 60.0 and decoded.metadata == {"genre": "pop"}
    assert contacts.dtype == np.float64
    np.testing.assert_array_equal(contacts, vectors[:, :4].astype(np.float64))
    # float32 numbers, float64 arithmetic: the decoded rotations are the exact Gram-Schmidt
    # of the stored floats
    np.testing.assert_allclose(decoded.rotation_matrices(), gram_schmidt(vectors[:, 7:].reshape(6, 24, 6)),
                               rtol=0, atol=1e-13)


@pytest.mark.survivor
def test_vector_refusals_name_the_problem():
    with pytest.raises(ParameterError, match=exactly("frame vectors must have shape (T, 151), got (5, 150)")):
        vector_to_motion(np.zeros((5, 150)))
    with pytest.raises(ParameterError, match=exactly("frame vectors must have shape (T, 151), got (151,)")):
        vector_to_motion(np.zeros(151))
    small = Motion(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 2, 1)), skeleton=two_joint_skeleton())
    message = exactly("the 151-d frame vector is defined for the SMPL-24 skeleton")
    with pytest.raises(ParameterError, match=message):
        motion_to_vector(small)
