"""The beat tracker: tempo precision, beats on onsets, metrical choices, streaming equality."""

import mir_eval
import numpy as np
import pytest

from choreo.music import BEAT_HOP, SAMPLE_RATE, Music, onset_envelopes, stream_features
from choreo.music.beats import (
    ENVELOPE_LATENCY,
    beat_frames_at,
    envelope_autocorrelation,
    estimate_beats,
    estimate_tempo,
    metrical_salience,
    percussive_part,
    track_beats,
)
from choreo.music.features import BlockConfig
from tests.test_music import click_track

ENVELOPE_FPS = SAMPLE_RATE / BEAT_HOP


@pytest.mark.parametrize("bpm", [97.0, 132.0, 144.0])
def test_tempo_is_heard_finer_than_30_fps_lags(bpm):
    # At 30 fps the nearest autocorrelation lags to 132 bpm are 128.6 and 138.5 bpm (2.6 % off).
    music = Music.from_array(click_track(bpm, 30.0, SAMPLE_RATE), SAMPLE_RATE)
    assert music.tempo == pytest.approx(bpm, rel=0.005)


def test_beats_land_on_the_clicks():
    bpm = 126.0
    music = Music.from_array(click_track(bpm, 30.0, SAMPLE_RATE), SAMPLE_RATE)
    clicks = np.arange(0.0, 30.0, 60.0 / bpm)
    assert mir_eval.beat.f_measure(clicks[clicks > 1], music.beat_times[music.beat_times > 1], 0.03) > 0.95
    # the beat column marks the nearest 30 fps frame of each beat time
    np.testing.assert_array_equal(music.beat_frames, np.round(music.beat_times * 30).astype(int))


def pulse_envelope(period_frames: float, frames: int, phase: float = 0.0, accents=(1.0,)) -> np.ndarray:
    """An onset envelope with a spike every ``period_frames``, cycling through ``accents``."""
    envelope = np.zeros(frames)
    for k, t in enumerate(np.arange(phase, frames - 1, period_frames)):
        envelope[int(round(t))] += accents[k % len(accents)]
    return envelope


def test_triple_metre_is_credited_at_three_and_six_periods():
    period = 60 * ENVELOPE_FPS / 90
    envelope = pulse_envelope(period, int(ENVELOPE_FPS * 40), accents=(1.0, 0.3, 0.3))
    bpms, salience = metrical_salience(envelope_autocorrelation(envelope, ENVELOPE_FPS), ENVELOPE_FPS)
    at = lambda bpm: salience[np.argmin(np.abs(bpms - bpm))]  # noqa: E731
    assert at(90) > at(120) and at(90) > at(67.5)
    assert estimate_tempo(envelope, ENVELOPE_FPS) == pytest.approx(90, rel=0.01)


def test_the_grid_moves_to_the_percussive_onsets():
    period = 60 * ENVELOPE_FPS / 120
    frames = int(ENVELOPE_FPS * 30)
    full = pulse_envelope(period, frames, phase=period / 2)  # loudest changes between the beats
    full += 0.6 * pulse_envelope(period, frames)
    percussive = pulse_envelope(period, frames)  # the drums are on the beats
    _, times = estimate_beats(np.stack([full, percussive]), ENVELOPE_FPS)
    on_beats = (np.arange(0, frames, period) - ENVELOPE_LATENCY) / ENVELOPE_FPS
    distance = np.abs(times[:, None] - on_beats[None, :]).min(axis=1)
    assert np.median(distance) < 0.015
    _, off = estimate_beats(np.stack([full, full]), ENVELOPE_FPS)  # no percussive evidence: stays
    assert np.median(np.abs(off[:, None] - on_beats[None, :]).min(axis=1)) > 0.2


def test_flat_envelopes_have_no_tempo():
    assert estimate_beats(np.zeros((2, 1000)), ENVELOPE_FPS)[0] == 0.0
    assert estimate_tempo(np.ones(1000), ENVELOPE_FPS) == 0.0


def test_beat_frames_at_rounds_and_drops_outside_beats():
    frames = beat_frames_at(np.array([-0.1, 0.0, 0.49, 0.51, 9.98, 10.0]), 30.0, 300)
    assert frames.tolist() == [0, 15, 299]


def test_streamed_envelopes_equal_the_whole_song():
    samples = click_track(131.0, 23.0, SAMPLE_RATE)
    whole = onset_envelopes(samples, SAMPLE_RATE)[:, : len(samples) // BEAT_HOP]
    blocks = [samples[i: i + 9001] for i in range(0, len(samples), 9001)]
    _, tempo, times = stream_features(blocks, "song", config=BlockConfig(block_frames=305, context_frames=60))
    music = Music.from_array(samples, SAMPLE_RATE)
    assert tempo == music.tempo
    np.testing.assert_allclose(times, music.beat_times)
    from choreo.music.features import _BlockFeaturizer

    featurizer = _BlockFeaturizer(BlockConfig(block_frames=305, context_frames=60), 512, SAMPLE_RATE)
    for block in blocks:
        featurizer.push(block)
    featurizer.finish()
    streamed = featurizer.beat_envelopes()
    assert streamed.shape == whole.shape
    np.testing.assert_allclose(streamed, whole, atol=1e-3)


def noisy_pulses(seed: int, frames: int, period: float) -> np.ndarray:
    """Half-wave-rectified noise with accented pulses, a silent lead-in and a fade-out."""
    rng = np.random.default_rng(seed)
    envelope = np.maximum(rng.normal(size=frames), 0.0)
    envelope[np.arange(rng.uniform(0, period), frames, period).astype(int)] += rng.uniform(1, 4)
    envelope[: frames // 10] = 0.0
    envelope[-frames // 8:] *= np.linspace(1, 0, frames // 8) ** 2
    return envelope


@pytest.mark.parametrize("seed,frames,bpm", [(0, 5000, 128.0), (1, 3000, 87.0), (2, 800, 174.0), (3, 40, 120.0),
                                              (4, 12000, 61.3)])
def test_track_beats_is_librosas_dynamic_programme(seed, frames, bpm):
    # choreo's numpy version replaces librosa.beat.beat_track (whose module compiles a numba kernel
    # in every process); librosa itself is the oracle, frame for frame, trimming included.
    librosa = pytest.importorskip("librosa")
    envelope = noisy_pulses(seed, frames, ENVELOPE_FPS * 60 / bpm * 1.01)
    _, expected = librosa.beat.beat_track(onset_envelope=envelope, sr=ENVELOPE_FPS * BEAT_HOP, hop_length=BEAT_HOP,
                                          bpm=bpm, tightness=1600.0, units="frames")
    np.testing.assert_array_equal(track_beats(envelope, ENVELOPE_FPS, bpm, tightness=1600.0), expected)
    assert len(expected) > 0 or frames < 100


def test_track_beats_of_nothing_is_nothing():
    assert len(track_beats(np.zeros(500), ENVELOPE_FPS, 120.0)) == 0
    assert len(track_beats(np.ones(1), ENVELOPE_FPS, 120.0)) == 0


def test_percussive_part_is_librosas_hpss():
    # librosa.decompose imports scikit-learn; choreo's own median-filter HPSS must equal it, silent bins included.
    librosa = pytest.importorskip("librosa")
    rng = np.random.default_rng(5)
    power = (rng.gamma(0.5, size=(64, 700)) * (rng.random((64, 1)) < 0.9)).astype(np.float32)
    power[:, 100:140] = 0.0  # silence: the soft mask's 0 / 0 case
    power[:, ::37] *= 30.0  # broadband clicks
    _, expected = librosa.decompose.hpss(power, kernel_size=(9, 31))
    np.testing.assert_array_equal(percussive_part(power, (9, 31)), expected)
