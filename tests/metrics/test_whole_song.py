"""The whole-song figures (choreo.metrics.whole_song): jerk, beat dip and the rest of a whole dance."""

import numpy as np
import pytest

from choreo.metrics.whole_song import beat_dip, jerks, median_jerk, whole_song

from ..motion.helpers import FPS, wobbly_walk


def test_median_jerk_of_a_cubic_is_its_third_derivative():
    t = np.arange(100) / FPS
    positions = np.zeros((100, 2, 3))
    positions[:, :, 0] = (2.0 * t**3)[:, None]  # d3/dt3 = 12
    assert median_jerk(positions, FPS) == pytest.approx(12.0, rel=1e-6)
    whole, root, body = jerks(positions, FPS)
    assert whole == pytest.approx(12.0, rel=1e-6) and root == pytest.approx(12.0, rel=1e-6) and body == pytest.approx(0.0)


def test_beat_dip_is_deeper_for_a_dancer_who_stops_on_beats():
    t = np.arange(600) / FPS
    stops = np.zeros((600, 24, 3))
    stops[:, :, 0] = (t - np.sin(2 * np.pi * t) / (2 * np.pi))[:, None]  # speed 1 - cos: stops once a second
    even = np.zeros((600, 24, 3))
    even[:, :, 0] = (t - 0.3 * np.sin(2 * np.pi * t) / (2 * np.pi))[:, None]  # speed never below 0.7
    assert beat_dip(stops) > 0.6 and 0.1 < beat_dip(even) < 0.45 and beat_dip(stops) > 2 * beat_dip(even)


def test_whole_song_figures_of_a_walk():
    figures = whole_song(wobbly_walk().joint_positions(), FPS)
    assert figures.seconds == pytest.approx(20.0)
    assert figures.pace == pytest.approx(0.5, rel=0.03)
    assert figures.root_jerk > figures.body_jerk  # the wobble is the root's
    assert 0.0 <= figures.planted <= 1.0
