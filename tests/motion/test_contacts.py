"""Tests of choreo.motion.contacts.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.motion import (
    foot_contacts,
)


@pytest.mark.survivor
def test_contacts_of_one_and_two_frames():
    np.testing.assert_array_equal(foot_contacts(np.zeros((1, 24, 3)), fps=30), np.ones((1, 4)))
    assert foot_contacts(np.zeros((0, 24, 3)), fps=30).shape == (0, 4)
    moving = np.zeros((2, 24, 3))
    moving[1, [7, 8, 10, 11], 2] = 1.0  # every foot joint moves 1 m in one frame
    np.testing.assert_array_equal(foot_contacts(moving, fps=30), np.zeros((2, 4)))


@pytest.mark.survivor
def test_a_foot_exactly_at_the_threshold_speed_is_moving():
    positions = np.zeros((3, 24, 3))
    positions[:, 7, 0] = [0.0, 0.25, 0.5]  # left ankle: 0.25 m per frame at 2 fps = 0.5 m/s exactly
    contacts = foot_contacts(positions, fps=2.0, speed_threshold=0.5)
    np.testing.assert_array_equal(contacts, [[0, 1, 1, 1]] * 3)
    above = foot_contacts(positions, fps=2.0, speed_threshold=0.5 + 1e-12)
    np.testing.assert_array_equal(above[:, 0], [1, 1, 1])
