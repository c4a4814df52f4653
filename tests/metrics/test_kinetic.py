"""Tests of choreo.metrics.kinetic.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.metrics import (
    kinetic_features,
)
from choreo.motion import Motion
from tests.metrics.helpers import no_warnings


def test_motionless_body_has_zero_kinetic_energy():
    still = np.repeat(Motion.rest(1).joint_positions(), 30, axis=0)
    still = still - still[:1, :1]
    features = kinetic_features(still)
    np.testing.assert_allclose(features[0::3], 0, atol=1e-12)
    np.testing.assert_allclose(features[1::3], 0, atol=1e-12)


@pytest.mark.survivor
def test_kinetic_features_of_two_frames_are_silent():
    positions = np.zeros((2, 24, 3))
    positions[1, 5] = [0.5, 0.25, 0.0]  # one step of joint 5: velocity (30, 15, 0) m/s at dt 1/60
    with no_warnings():
        features = kinetic_features(positions)
    assert features[15] == 900.0 and features[16] == 225.0  # joint 5's horizontal and vertical energy
    np.testing.assert_array_equal(np.delete(features.reshape(24, 3)[:, :2], 5, axis=0), 0.0)
    assert np.isnan(features[2::3]).all()  # no acceleration to average: NaN, without a warning


@pytest.mark.survivor
def test_kinetic_features_are_rounded_to_float32():
    positions = np.zeros((6, 24, 3))
    positions[5, 0, 1] = 1 / 60  # joint 0 rises 1/60 m between frames 4 and 5: 1 m/s there
    # frames 1..5 average the differences k in [i-2, i+2] within 1..5: {1-3}, {1-4}, {1-5}, {2-5}, {3-5}
    expected_vertical = (0 + 0 + (1 / 5) ** 2 + (1 / 4) ** 2 + (1 / 3) ** 2) / 5
    features = kinetic_features(positions)
    assert features.dtype == np.float32
    assert features[1] == np.float32(expected_vertical)
