"""Tests of choreo.metrics.beats.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import warnings

import numpy as np
import pytest
import scipy.linalg

from choreo.metrics import (
    MetricWarning,
    beat_align_score,
    beat_autocorrelation,
    beat_distances,
    diversity,
    foot_contact_score,
    frechet_distance,
    motion_beats,
    salience_at,
    same_pulse,
    tempo_salience,
)
from choreo.metrics.beats import _nearest_distances, motion_beat_train
from tests.metrics.helpers import no_warnings, pulsing_positions, sliding_body


def test_beat_align_default_sigma_is_three_frames():
    # music beats at 10 and 40; motion beats 3 frames off the first, on the second
    value = beat_align_score(np.array([10, 40]), np.array([13, 40]))
    assert value == pytest.approx((np.exp(-9 / (2 * 3.0**2)) + 1.0) / 2)
    # it averages over MUSIC beats: an extra motion beat far away changes nothing
    assert beat_align_score(np.array([10, 40]), np.array([13, 40, 90])) == pytest.approx(value)


def test_beat_align_is_one_when_speed_minima_sit_on_the_beats():
    beat_every = 15  # frames: a beat every 0.5 s at 30 fps
    frames = np.arange(300)
    # Speed is lowest exactly on the beats: position = integral of a speed with minima there.
    speed = 1.0 - np.cos(2 * np.pi * frames / beat_every) + 0.05
    x = np.concatenate([[0.0], np.cumsum(speed[:-1])]) * 0.01  # p[t+1] - p[t] = speed[t]
    positions = np.zeros((300, 24, 3))
    positions[..., 0] = x[:, None]
    dance_beats = motion_beats(positions)
    music_beats = np.arange(beat_every, 300, beat_every)  # frames 15, 30, ..., 285
    assert beat_align_score(music_beats, dance_beats) == pytest.approx(1.0, abs=1e-3)
    shifted = beat_align_score(music_beats + 7, dance_beats)  # half a beat off: exp(-7^2 / 18) ~ 0.07
    assert shifted < 0.1
    to_music, to_motion = beat_distances(music_beats, dance_beats)
    assert to_motion == pytest.approx(0.0, abs=1e-9) and to_music == pytest.approx(0.0, abs=1e-9)
    assert beat_distances(music_beats + 3, dance_beats) == pytest.approx((9.0, 9.0))


@pytest.mark.parametrize("bpm", [60.0, 90.0, 104.4, 128.0, 144.0])
def test_tempo_salience_is_high_at_the_rate_of_speed_minima_only(bpm):
    frames = np.arange(1800)  # 60 s at 30 fps, speed minima every 60/bpm s: not on whole frames
    speed = 1.05 - np.cos(2 * np.pi * frames * bpm / 60 / 30)
    positions = np.zeros((1800, 24, 3))
    positions[..., 0] = np.cumsum(speed)[:, None] * 0.01
    assert tempo_salience(positions, 30.0, bpm) > 0.5
    assert tempo_salience(positions, 30.0, bpm / 2) > 0.5  # every other beat is a beat too
    assert tempo_salience(positions, 30.0, bpm * 1.3) < 0.2  # another tempo
    assert tempo_salience(positions[:40], 30.0, bpm) == 0.0  # too short for a period
    once = beat_autocorrelation(positions, 200)  # computed once, read at any tempo: the same numbers
    for tempo in (bpm, bpm / 2, bpm * 1.3):
        assert salience_at(once, 30.0, tempo) == pytest.approx(tempo_salience(positions, 30.0, tempo))


def test_same_pulse_counts_half_and_double_time():
    assert same_pulse(120.0, 120.0) and same_pulse(87.0, 174.0) and same_pulse(203.0, 102.0)
    assert same_pulse(124.0, 120.0) and not same_pulse(126.0, 120.0)  # within 4 %, not 5 %
    assert not same_pulse(80.0, 120.0) and not same_pulse(100.0, 0.0)


def test_beat_align_without_beats_warns_and_scores_zero():
    with pytest.warns(MetricWarning):
        assert beat_align_score(np.array([]), np.array([3, 5])) == 0.0


def literal_salience(positions: np.ndarray, fps: float, bpm: float) -> float:
    """Normalised linear autocorrelation of the beat train by a plain loop, read by hand-written
    linear interpolation at one and two periods; 0 when two periods do not fit."""
    train = motion_beat_train(positions)
    train = train - train.mean()
    period = 60.0 * fps / bpm
    lags = int(2 * period) + 2
    ac = [sum(train[i] * train[i + k] for i in range(len(train) - k)) for k in range(lags)]
    ac = [value / ac[0] for value in ac]
    values = []
    for m in (1, 2):
        lag = m * period
        low = int(np.floor(lag))
        frac = lag - low
        values.append(ac[low] if frac == 0 else ac[low] * (1 - frac) + ac[low + 1] * frac)
    return max(values)


@pytest.mark.survivor
def test_beat_autocorrelation_of_an_odd_length_dance_is_the_literal_one():
    positions = pulsing_positions(201, 23.0)  # odd: a 3n-point FFT would not round-trip
    train = motion_beat_train(positions)
    train = train - train.mean()
    literal = np.array([sum(train[i] * train[i + k] for i in range(len(train) - k)) for k in range(70)])
    np.testing.assert_allclose(beat_autocorrelation(positions, 69), literal / literal[0], atol=1e-9)


@pytest.mark.survivor
def test_tempo_salience_below_one_bpm_and_just_past_four_periods():
    slow = pulsing_positions(600, 120.0)  # fps 1, 0.5 bpm: a period of 120 frames, five of them
    expected = literal_salience(slow, 1.0, 0.5)
    assert expected > 0.5
    assert tempo_salience(slow, 1.0, 0.5) == pytest.approx(expected, abs=1e-9)
    short = pulsing_positions(121, 30.0)  # one frame more than four periods at 60 bpm, 30 fps
    expected = literal_salience(short, 30.0, 60.0)
    assert expected > 0.3
    assert tempo_salience(short, 30.0, 60.0) == pytest.approx(expected, abs=1e-9)


@pytest.mark.survivor
@pytest.mark.parametrize("music, dance", [([], [10]), ([10], []), ([], [])])
def test_beat_align_refusal_text_and_value(music, dance):
    with pytest.warns(MetricWarning, match="^BeatAlign: no music beats or no motion beats; scoring 0$"):
        assert beat_align_score(np.array(music), np.array(dance)) == 0.0


@pytest.mark.survivor
@pytest.mark.parametrize("music, dance", [([], [10, 20]), ([10, 20], []), ([], [])])
def test_beat_distance_refusal_text_and_values(music, dance):
    with pytest.warns(MetricWarning, match="^beat distances: no music beats or no motion beats; returning NaN$") as record:
        distances = beat_distances(np.array(music), np.array(dance))
    assert [w.category for w in record] == [MetricWarning]
    assert isinstance(distances, tuple) and len(distances) == 2 and np.isnan(distances[0]) and np.isnan(distances[1])


@pytest.mark.survivor
def test_beat_distances_with_a_single_beat_on_either_side():
    with no_warnings():
        # one music beat: motion beats 14, 30 are 4 and 20 away; the music beat is 4 from 14
        assert beat_distances(np.array([10]), np.array([14, 30])) == pytest.approx(((16 + 400) / 2, 16))
        # one motion beat: it is 4 from music beat 10; music beats 10, 20 are 4 and 6 from it
        assert beat_distances(np.array([10, 20]), np.array([14])) == pytest.approx((16, (16 + 36) / 2))


@pytest.mark.survivor
@pytest.mark.parametrize("frames", [0, 1, 2])
def test_pfc_refusal_text_and_value(frames):
    with pytest.warns(MetricWarning, match="^PFC needs at least 3 frames; returning NaN$") as record:
        value = foot_contact_score(sliding_body(3, [0.0, 0.1, 0.3])[:frames])
    assert [w.category for w in record] == [MetricWarning] and np.isnan(value)


@pytest.mark.survivor
@pytest.mark.parametrize("sizes", [(1, 5), (5, 1), (1, 1), (0, 3)])
def test_fid_refusal_text_and_value(sizes):
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(sizes[0], 2)), rng.normal(size=(sizes[1], 2))
    with pytest.warns(MetricWarning, match="^FID needs at least 2 samples per set; returning NaN$") as record:
        value = frechet_distance(a, b)
    assert [w.category for w in record] == [MetricWarning] and np.isnan(value)


@pytest.mark.survivor
def test_fid_warns_at_exactly_as_many_samples_as_dimensions():
    a = np.array([[0.0, 0.0], [1.0, 2.0]])
    b = np.array([[1.0, 1.0], [2.0, 0.0]])
    message = "^FID with 2 samples for 2 feature dimensions: covariances are singular, the value is unreliable$"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        with pytest.warns(MetricWarning, match=message) as record:
            frechet_distance(a, b)
    assert MetricWarning in [w.category for w in record]


def offset_fid(a: np.ndarray, b: np.ndarray, offset: float) -> float:
    """FID with both covariances lifted by offset * I inside the square root only, written with
    symmetric eigen-decompositions: tr sqrt(A B) = sum sqrt(eig(A^1/2 B A^1/2))."""
    cov_a, cov_b = np.cov(a, rowvar=False), np.cov(b, rowvar=False)
    lifted_a, lifted_b = cov_a + offset * np.eye(len(cov_a)), cov_b + offset * np.eye(len(cov_b))
    w, v = np.linalg.eigh(lifted_a)
    half = v @ np.diag(np.sqrt(w)) @ v.T
    root_trace = np.sqrt(np.clip(np.linalg.eigvalsh(half @ lifted_b @ half), 0, None)).sum()
    return float(((a.mean(0) - b.mean(0)) ** 2).sum() + np.trace(cov_a) + np.trace(cov_b) - 2 * root_trace)


@pytest.mark.survivor
def test_fid_retries_a_failed_square_root_with_a_small_offset():
    a = np.array([[-3.0, -3.0, 2.0], [0.0, 1.0, 1.0]])
    b = np.array([[1.0, -3.0, 0.0], [-2.0, -1.0, 3.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if np.isfinite(scipy.linalg.sqrtm(np.cov(a, rowvar=False) @ np.cov(b, rowvar=False))).all():
            pytest.skip("this scipy's sqrtm does not fail on this product; the retry is not reached")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.warns(MetricWarning, match="^FID with 2 samples for 3 feature dimensions"):
            value = frechet_distance(a, b)
    # exactly 2 + 13 + 11 - 2 * 2 = 22 without the offset; 1e-5 on the diagonals lowers it by ~2.6e-4
    assert value == pytest.approx(offset_fid(a, b, 1e-5), abs=1e-8)
    assert value == pytest.approx(22.0 - 2.595756e-4, abs=1e-9)


@pytest.mark.survivor
@pytest.mark.parametrize("count", [0, 1])
def test_diversity_refusal_text_and_value(count):
    with pytest.warns(MetricWarning, match="^diversity needs at least 2 samples; returning NaN$") as record:
        value = diversity(np.ones((count, 4)))
    assert [w.category for w in record] == [MetricWarning] and np.isnan(value)


def warned_here(record) -> bool:
    """The warning names the caller's line (stacklevel 2), not the metric's own."""
    return len(record) == 1 and record[0].category is MetricWarning and record[0].filename == __file__


@pytest.mark.survivor
def test_nearest_distances_equal_a_brute_force_search():
    rng = np.random.default_rng(0)
    for _ in range(50):
        references = rng.integers(0, 100, size=rng.integers(1, 6))
        queries = rng.integers(-20, 120, size=8)  # before the first and after the last reference too
        brute = np.array([min(abs(q - r) for r in references) for q in queries])
        np.testing.assert_array_equal(_nearest_distances(queries, rng.permutation(references)), brute)


@pytest.mark.survivor
def test_beat_align_with_one_motion_beat_is_scored_not_refused():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert beat_align_score(np.array([10, 20]), np.array([10])) == pytest.approx((1 + np.exp(-100 / 18)) / 2)
        assert beat_align_score(np.array([10]), np.array([13, 50])) == pytest.approx(np.exp(-9 / 18))


@pytest.mark.survivor
@pytest.mark.parametrize("music, dance", [([], [10]), ([10], []), ([], [])])
def test_beat_align_without_beats_is_zero_with_a_warning(music, dance):
    with pytest.warns(MetricWarning, match="^BeatAlign: no music beats or no motion beats; scoring 0$") as record:
        assert beat_align_score(np.array(music), np.array(dance)) == 0.0
    assert warned_here(record)


@pytest.mark.survivor
@pytest.mark.parametrize("music, dance", [([], [10]), ([10], []), ([], [])])
def test_beat_distances_without_beats_are_nan_with_a_warning(music, dance):
    with pytest.warns(MetricWarning, match="^beat distances: no music beats or no motion beats; returning NaN$") as record:
        distances = beat_distances(np.array(music), np.array(dance))
    assert np.isnan(distances).all() and len(distances) == 2 and warned_here(record)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert beat_distances(np.array([10]), np.array([14, 30])) == pytest.approx(((4**2 + 20**2) / 2, 4**2))


@pytest.mark.survivor
def test_motion_beat_train_holds_one_unit_bump_per_beat():
    positions = pulsing_positions(300, 30.0)
    train = motion_beat_train(positions)
    from choreo.metrics import motion_beats

    beats = motion_beats(positions)
    assert len(beats) >= 8 and train.sum() == pytest.approx(len(beats))
    assert train[beats].max() == pytest.approx(1 / np.sqrt(2 * np.pi), rel=0.02)  # a unit-mass Gaussian, sigma 1


@pytest.mark.survivor
def test_beat_autocorrelation_is_the_literal_normalised_linear_one():
    positions = pulsing_positions(200, 23.0)
    train = motion_beat_train(positions)
    train = train - train.mean()
    literal = np.array([np.dot(train[: len(train) - k], train[k:]) for k in range(60)])
    np.testing.assert_allclose(beat_autocorrelation(positions, 59), literal / literal[0], atol=1e-9)


@pytest.mark.survivor
def test_beat_autocorrelation_of_a_still_body_is_zeros_of_the_asked_length():
    np.testing.assert_array_equal(beat_autocorrelation(np.zeros((90, 24, 3)), 40), np.zeros(41))


@pytest.mark.survivor
def test_salience_reads_one_or_two_periods_and_needs_both_inside():
    autocorrelation = np.linspace(1.0, 0.0, 61)  # lag 30 = 0.5, lag 60 = 0.0 (60 bpm at 30 fps: period 30)
    assert salience_at(autocorrelation, 30.0, 60.0) == pytest.approx(0.5)  # the larger of the two
    assert salience_at(autocorrelation[:60], 30.0, 60.0) == 0.0  # two periods past the last lag
    assert salience_at(autocorrelation, 30.0, 0.0) == 0.0 and salience_at(autocorrelation, 30.0, -60.0) == 0.0
    slow = np.full(3601, 0.25)  # 1 bpm: a period of 1800 frames, two fit
    assert salience_at(slow, 30.0, 1.0) == pytest.approx(0.25)
    rising = np.linspace(0.0, 1.0, 61)
    assert salience_at(rising, 30.0, 60.0) == pytest.approx(1.0)  # two periods when larger


@pytest.mark.survivor
def test_tempo_salience_needs_more_than_four_periods():
    assert tempo_salience(pulsing_positions(120, 30.0), 30.0, 60.0) == 0.0  # exactly four periods
    enough = pulsing_positions(130, 30.0)
    assert tempo_salience(enough, 30.0, 60.0) == pytest.approx(salience_at(beat_autocorrelation(enough, 61), 30.0, 60.0))
    assert tempo_salience(enough, 30.0, 60.0) > 0.3
    assert tempo_salience(enough, 30.0, 0.0) == 0.0


@pytest.mark.survivor
def test_same_pulse_edges():
    assert same_pulse(0.5, 0.5)  # any positive tempo, however slow
    assert same_pulse(125.0, 100.0, tolerance=0.25) and not same_pulse(126.0, 100.0, tolerance=0.25)  # inclusive
