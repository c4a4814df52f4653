"""Tests of choreo.music.rhythm.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.music import BEAT_COLUMN, FEATURE_DIM, PEAK_COLUMN, beat_phase, rhythm_channels, stretch_features


@pytest.mark.survivor
def test_two_beats_give_a_phase():
    phase = beat_phase(np.array([10, 20]), 30)
    assert phase is not None and phase[15] == pytest.approx(0.5) and phase[25] == pytest.approx(0.5)


@pytest.mark.survivor
def test_an_irregular_grid_is_interpolated_inside_and_continued_outside_from_the_first_beat():
    beats = np.array([13, 20, 30, 40])  # gaps 7, 10, 10: median period 10
    phase = beat_phase(beats, 50)
    assert phase[16] == pytest.approx(3 / 7)  # between the first two beats: linear, not the median grid
    assert phase[40] == pytest.approx(0.0)  # on the last beat
    assert phase[13] == pytest.approx(0.0)
    assert phase[5] == pytest.approx(0.2)  # (5 - 13) / 10, counted from the first beat
    assert phase[45] == pytest.approx(0.2)  # (45 - 13) / 10


@pytest.mark.survivor
def test_rhythm_channels_refuse_other_shapes_with_the_expected_one():
    with pytest.raises(ParameterError, match=rf"music features must have shape \(T, {FEATURE_DIM}\), got \(10, 34\)"):
        rhythm_channels(np.zeros((10, FEATURE_DIM - 1)))
    with pytest.raises(ParameterError, match="must have shape"):
        rhythm_channels(np.zeros(FEATURE_DIM))


@pytest.mark.survivor
def test_rhythm_channels_are_float32_and_a_half_marked_frame_is_no_beat():
    features = np.zeros((60, FEATURE_DIM))
    features[[0, 15, 30, 45], BEAT_COLUMN] = 1.0
    features[[7, 22], BEAT_COLUMN] = 0.5  # not above one half: no beat, still 120 bpm
    channels = rhythm_channels(features)
    assert channels.dtype == np.float32
    assert channels[0, 2] == pytest.approx(0.0, abs=1e-6)


@pytest.mark.survivor
def test_stretched_features_are_float32_with_unit_spikes_inside_the_song():
    features = np.zeros((100, FEATURE_DIM))  # float64 in
    features[[0, 40, 99], BEAT_COLUMN] = 1.0  # 99 / 1.6 = 61.9: rounds to 62, past the last frame (61)
    features[[10], PEAK_COLUMN] = 0.5  # not a spike
    fast = stretch_features(features, 1.6)
    assert fast.dtype == np.float32 and len(fast) == 62
    assert np.flatnonzero(fast[:, BEAT_COLUMN]).tolist() == [0, 25]
    assert set(fast[:, BEAT_COLUMN].tolist()) == {0.0, 1.0} and not fast[:, PEAK_COLUMN].any()


@pytest.mark.survivor
@pytest.mark.parametrize("factor", [0.25, 4.0])
def test_stretch_factors_at_the_bounds_are_taken(factor):
    assert len(stretch_features(np.zeros((9, FEATURE_DIM)), factor)) == int(np.floor(8 / factor)) + 1


@pytest.mark.survivor
@pytest.mark.parametrize("factor", [0.2499, 4.001, 5.0])
def test_stretch_factors_outside_the_bounds_are_refused(factor):
    with pytest.raises(ParameterError, match=rf"stretch factor must be within \[0.25, 4\], got {factor}"):
        stretch_features(np.zeros((9, FEATURE_DIM)), factor)
