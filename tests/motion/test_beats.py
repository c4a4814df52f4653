"""Tests of choreo.motion.beats.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.motion import (
    motion_beats,
)


def test_motion_beats_are_minima_of_the_smoothed_mean_joint_speed():
    frames = 120
    t = np.arange(frames)
    speed = 1.0 + np.cos(2 * np.pi * t / 30)  # minima at 15, 45, 75, 105 (frame-to-frame step)
    x = np.concatenate([[0.0], np.cumsum(speed[:-1])]) * 0.01
    positions = np.zeros((frames, 24, 3))
    positions[..., 0] = x[:, None]
    beats = motion_beats(positions)
    assert beats.tolist() == [15, 45, 75, 105]


@pytest.mark.survivor
def test_dances_too_short_for_a_beat_have_an_empty_integer_array():
    for frames in [0, 1, 2]:
        beats = motion_beats(np.zeros((frames, 24, 3)))
        assert beats.shape == (0,) and beats.dtype.kind == "i", frames
        assert np.arange(5)[beats].tolist() == []  # usable as an index
