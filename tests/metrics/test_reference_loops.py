"""Tests of choreo.metrics.reference_loops.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.metrics import (
    kinetic_features,
)
from choreo.metrics.reference_loops import literal_kinetic, random_dances
from choreo.motion import Motion


def test_vectorised_kinetic_features_equal_the_literal_definition():
    positions = random_dances(1, frames=40)[0]
    positions = positions - positions[:1, :1]
    np.testing.assert_allclose(kinetic_features(positions), literal_kinetic(positions), rtol=2e-5, atol=1e-4)


@pytest.mark.survivor
def test_random_dances_default_to_150_frames_and_seed_0():
    (dance,) = random_dances(1)
    assert dance.shape == (150, 24, 3)
    rng = np.random.default_rng(0)
    angles = rng.normal(0.0, 0.05, size=(150, 24, 3)).cumsum(axis=0)
    root = rng.normal(0.0, 0.02, size=(150, 3)).cumsum(axis=0) + np.array([0.0, 0.9, 0.0])
    np.testing.assert_allclose(dance, Motion.from_axis_angle(root, angles).joint_positions(), rtol=1e-12, atol=1e-12)


@pytest.mark.survivor
def test_random_dances_are_the_seeded_random_walk():
    dances = random_dances(2, frames=6, seed=5)
    rng = np.random.default_rng(5)
    for dance in dances:
        angles = rng.normal(0.0, 0.05, size=(6, 24, 3)).cumsum(axis=0)
        root = rng.normal(0.0, 0.02, size=(6, 3)).cumsum(axis=0) + np.array([0.0, 0.9, 0.0])
        np.testing.assert_allclose(dance, Motion.from_axis_angle(root, angles).joint_positions(), rtol=1e-12, atol=1e-12)
