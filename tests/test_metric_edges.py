"""Beat metrics at their edges, against literal computations: no beats, one beat, a tempo of zero,
a dance exactly as long as the metric needs. Written from the mutants that survived the first
mutation run (docs/mutation.md): each test here fails when one of those mutants is planted."""

import warnings

import numpy as np
import pytest

from choreo.metrics import MetricWarning, beat_align_score, beat_autocorrelation, beat_distances, salience_at, same_pulse, tempo_salience
from choreo.metrics.beats import _nearest_distances, motion_beat_train


def pulsing_positions(frames: int, period: float) -> np.ndarray:
    """A body gliding along x whose speed dips every ``period`` frames (motion beats there)."""
    t = np.arange(frames)
    speed = 1.05 - np.cos(2 * np.pi * t / period)
    positions = np.zeros((frames, 24, 3))
    positions[..., 0] = np.cumsum(speed)[:, None] * 0.01
    return positions


def warned_here(record) -> bool:
    """The warning names the caller's line (stacklevel 2), not the metric's own."""
    return len(record) == 1 and record[0].category is MetricWarning and record[0].filename == __file__


def test_nearest_distances_equal_a_brute_force_search():
    rng = np.random.default_rng(0)
    for _ in range(50):
        references = rng.integers(0, 100, size=rng.integers(1, 6))
        queries = rng.integers(-20, 120, size=8)  # before the first and after the last reference too
        brute = np.array([min(abs(q - r) for r in references) for q in queries])
        np.testing.assert_array_equal(_nearest_distances(queries, rng.permutation(references)), brute)


def test_beat_align_with_one_motion_beat_is_scored_not_refused():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert beat_align_score(np.array([10, 20]), np.array([10])) == pytest.approx((1 + np.exp(-100 / 18)) / 2)
        assert beat_align_score(np.array([10]), np.array([13, 50])) == pytest.approx(np.exp(-9 / 18))


@pytest.mark.parametrize("music, dance", [([], [10]), ([10], []), ([], [])])
def test_beat_align_without_beats_is_zero_with_a_warning(music, dance):
    with pytest.warns(MetricWarning, match="^BeatAlign: no music beats or no motion beats; scoring 0$") as record:
        assert beat_align_score(np.array(music), np.array(dance)) == 0.0
    assert warned_here(record)


@pytest.mark.parametrize("music, dance", [([], [10]), ([10], []), ([], [])])
def test_beat_distances_without_beats_are_nan_with_a_warning(music, dance):
    with pytest.warns(MetricWarning, match="^beat distances: no music beats or no motion beats; returning NaN$") as record:
        distances = beat_distances(np.array(music), np.array(dance))
    assert np.isnan(distances).all() and len(distances) == 2 and warned_here(record)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert beat_distances(np.array([10]), np.array([14, 30])) == pytest.approx(((4**2 + 20**2) / 2, 4**2))


def test_motion_beat_train_holds_one_unit_bump_per_beat():
    positions = pulsing_positions(300, 30.0)
    train = motion_beat_train(positions)
    from choreo.metrics import motion_beats

    beats = motion_beats(positions)
    assert len(beats) >= 8 and train.sum() == pytest.approx(len(beats))
    assert train[beats].max() == pytest.approx(1 / np.sqrt(2 * np.pi), rel=0.02)  # a unit-mass Gaussian, sigma 1


def test_beat_autocorrelation_is_the_literal_normalised_linear_one():
    positions = pulsing_positions(200, 23.0)
    train = motion_beat_train(positions)
    train = train - train.mean()
    literal = np.array([np.dot(train[: len(train) - k], train[k:]) for k in range(60)])
    np.testing.assert_allclose(beat_autocorrelation(positions, 59), literal / literal[0], atol=1e-9)


def test_beat_autocorrelation_of_a_still_body_is_zeros_of_the_asked_length():
    np.testing.assert_array_equal(beat_autocorrelation(np.zeros((90, 24, 3)), 40), np.zeros(41))


def test_salience_reads_one_or_two_periods_and_needs_both_inside():
    autocorrelation = np.linspace(1.0, 0.0, 61)  # lag 30 = 0.5, lag 60 = 0.0 (60 bpm at 30 fps: period 30)
    assert salience_at(autocorrelation, 30.0, 60.0) == pytest.approx(0.5)  # the larger of the two
    assert salience_at(autocorrelation[:60], 30.0, 60.0) == 0.0  # two periods past the last lag
    assert salience_at(autocorrelation, 30.0, 0.0) == 0.0 and salience_at(autocorrelation, 30.0, -60.0) == 0.0
    slow = np.full(3601, 0.25)  # 1 bpm: a period of 1800 frames, two fit
    assert salience_at(slow, 30.0, 1.0) == pytest.approx(0.25)
    rising = np.linspace(0.0, 1.0, 61)
    assert salience_at(rising, 30.0, 60.0) == pytest.approx(1.0)  # two periods when larger


def test_tempo_salience_needs_more_than_four_periods():
    assert tempo_salience(pulsing_positions(120, 30.0), 30.0, 60.0) == 0.0  # exactly four periods
    enough = pulsing_positions(130, 30.0)
    assert tempo_salience(enough, 30.0, 60.0) == pytest.approx(salience_at(beat_autocorrelation(enough, 61), 30.0, 60.0))
    assert tempo_salience(enough, 30.0, 60.0) > 0.3
    assert tempo_salience(enough, 30.0, 0.0) == 0.0


def test_same_pulse_edges():
    assert same_pulse(0.5, 0.5)  # any positive tempo, however slow
    assert same_pulse(125.0, 100.0, tolerance=0.25) and not same_pulse(126.0, 100.0, tolerance=0.25)  # inclusive
