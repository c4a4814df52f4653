"""The beat tracker: tempo precision, beats on onsets, metrical choices, streaming equality."""

import mir_eval
import numpy as np
import pytest

from choreo.music import (
    BEAT_HOP,
    SAMPLE_RATE,
    Music,
    onset_envelopes,
    stream_features,
)
from choreo.music.beats import (
    ENVELOPE_LATENCY,
    beat_frames_at,
    envelope_autocorrelation,
    estimate_beats,
    estimate_tempo,
    metrical_salience,
    onset_peaks,
    percussive_part,
    pick_peaks,
    track_beats,
)
from choreo.music import beats as beats_module
from choreo.music.features import BlockConfig
from tests.music.helpers import click_track

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
def test_track_beats_is_librosas_dynamic_programme(seed, frames, bpm, monkeypatch):
    # choreo's numpy version replaces librosa.beat.beat_track (whose module compiles a numba kernel
    # in every process); librosa itself is the oracle, frame for frame, before the trimming (whose
    # threshold choreo halves: the next tests; librosa's trim=False keeps only silence out).
    librosa = pytest.importorskip("librosa")
    monkeypatch.setattr(beats_module, "_fade_threshold", lambda local, beats: 0.0)
    envelope = noisy_pulses(seed, frames, ENVELOPE_FPS * 60 / bpm * 1.01)
    _, expected = librosa.beat.beat_track(onset_envelope=envelope, sr=ENVELOPE_FPS * BEAT_HOP, hop_length=BEAT_HOP,
                                          bpm=bpm, tightness=1600.0, units="frames", trim=False)
    np.testing.assert_array_equal(track_beats(envelope, ENVELOPE_FPS, bpm, tightness=1600.0), expected)
    assert len(expected) > 0 or frames < 100


def test_a_quieter_second_half_keeps_its_beats():
    # librosa's trim threshold is the whole RMS of the beats' scores: every beat of a quieter last
    # minute falls under it, and it lost them all (an LMMS song heard no beat after 146 of its 236 s).
    # (librosa 0.11's beat_track keeps none after the first half of this envelope.)
    period = ENVELOPE_FPS * 60 / 120.0
    envelope = pulse_envelope(period, 96 * 120)
    envelope[len(envelope) // 2:] *= 0.4
    beats = track_beats(envelope, ENVELOPE_FPS, 120.0)
    assert beats[-1] > len(envelope) - 2 * period
    assert np.all(np.abs(np.diff(beats) - period) <= 1)


def test_silence_before_and_after_the_music_has_no_beats():
    period = ENVELOPE_FPS * 60 / 120.0
    envelope = pulse_envelope(period, 96 * 60)
    envelope[: 96 * 10] = 0.0
    envelope[-96 * 15:] = 0.0
    beats = track_beats(envelope, ENVELOPE_FPS, 120.0)
    assert beats[0] >= 96 * 10 - 2 and beats[-1] <= len(envelope) - 96 * 15 + 2


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


FPS = 96.0


def peaks_by_definition(x, pre_max, post_max, pre_avg, post_avg, delta, wait):
    """librosa.util.peak_pick's rule, one frame at a time: n is a peak when x[n] is the maximum of
    x[n - pre_max : n + post_max] and at least delta above the mean of x[n - pre_avg : n + post_avg]
    (windows cut at the ends; frame 0 looks only forwards), and more than ``wait`` frames follow
    the previous peak."""
    peaks, last = [], -np.inf
    for n in range(len(x)):
        if n == 0:
            biggest, mean = x[:post_max].max(), x[:post_avg].mean()
        else:
            biggest = x[max(n - pre_max, 0):n + post_max].max()
            mean = x[max(n - pre_avg, 0):n + post_avg].mean()
        if x[n] == biggest and x[n] >= mean + delta and n > last + wait:
            peaks.append(n)
            last = n
    return peaks


@pytest.mark.survivor
@pytest.mark.parametrize("pre_max, post_max, pre_avg, post_avg, delta, wait",
                         [(1, 1, 3, 4, 0.0, 0), (3, 1, 2, 2, 0.1, 2), (1, 3, 5, 1, 0.05, 1), (2, 2, 1, 6, 0.0, 4)])
def test_pick_peaks_follows_the_definition_on_coarse_values_with_ties(pre_max, post_max, pre_avg, post_avg, delta, wait):
    rng = np.random.default_rng(pre_max * 10 + wait)
    for _ in range(40):
        x = rng.integers(0, 4, size=int(rng.integers(1, 30))) / 4.0  # quarters: ties everywhere
        found = pick_peaks(x, pre_max, post_max, pre_avg, post_avg, delta, wait)
        assert found.dtype.kind == "i"
        assert found.tolist() == peaks_by_definition(x, pre_max, post_max, pre_avg, post_avg, delta, wait)


@pytest.mark.survivor
def test_pick_peaks_by_hand():
    x = np.array([0.0, 1.0, 0.0, 0.9, 0.0, 0.0, 0.8, 0.0])
    assert pick_peaks(x, 1, 2, 1, 2, 0.0, 0).tolist() == [1, 3, 6]
    assert pick_peaks(x, 1, 2, 1, 2, 0.0, 1).tolist() == [1, 3, 6]  # two frames apart is more than one
    assert pick_peaks(x, 1, 2, 1, 2, 0.0, 2).tolist() == [1, 6]  # 3 is only two after 1
    assert pick_peaks(x, 3, 1, 1, 2, 0.0, 0).tolist() == [1]  # 1.0 is two frames before 0.9, 0.9 three before 0.8
    assert pick_peaks(np.array([0.5, 0.5]), 1, 1, 1, 1, 0.0, 0).tolist() == [0, 1]  # equal to the mean is enough
    assert pick_peaks(np.zeros(0), 1, 1, 1, 1, 0.0, 0).tolist() == []


@pytest.mark.survivor
def test_onset_peaks_ignore_offset_and_scale_and_take_integer_envelopes():
    envelope = np.zeros(200)
    envelope[[20, 50, 90, 140]] = [3.0, 1.0, 2.0, 4.0]
    peaks = onset_peaks(envelope, 30.0)
    assert peaks.tolist() == [20, 50, 90, 140]
    assert onset_peaks(envelope + 7.0, 30.0).tolist() == peaks.tolist()
    assert onset_peaks(5.0 * envelope, 30.0).tolist() == peaks.tolist()
    assert onset_peaks(envelope.astype(int), 30.0).tolist() == peaks.tolist()


@pytest.mark.survivor
def test_onset_peaks_of_a_flat_or_broken_envelope_are_none():
    for envelope in (np.zeros(50), np.r_[np.ones(10), np.nan, np.ones(10)], np.r_[np.ones(5), np.inf]):
        peaks = onset_peaks(envelope, 30.0)
        assert peaks.shape == (0,) and peaks.dtype.kind == "i"


def impulses(length: int, frames) -> np.ndarray:
    envelope = np.zeros(length)
    envelope[list(frames)] = 1.0
    return envelope


@pytest.mark.survivor
def test_the_grid_moves_half_a_beat_when_the_percussion_sits_between_the_beats():
    full = impulses(947, range(10, 947, 48))  # 120 bpm at 96 fps
    tempo, on_beats = estimate_beats(np.stack([full, full]), FPS)
    frames = track_beats(full, FPS, tempo)
    assert tempo == 120.0 and frames.tolist() == list(range(10, 923, 48))
    np.testing.assert_allclose(on_beats, (frames - ENVELOPE_LATENCY) / FPS)
    between = impulses(947, range(34, 947, 48))
    tempo, moved = estimate_beats(np.stack([full, between]), FPS)
    # frames + 24, the last (946) dropped: a move may not reach the envelope's last frame
    np.testing.assert_allclose(moved, (np.arange(34, 946, 48) - ENVELOPE_LATENCY) / FPS)
    tempo, kept = estimate_beats(np.stack([full, np.ones(947)]), FPS)  # as strong between as on: no move
    np.testing.assert_allclose(kept, on_beats)


@pytest.mark.survivor
def test_two_beats_are_enough_to_move_the_grid():
    full = impulses(130, [20, 68])
    _, on_beats = estimate_beats(np.stack([full, full]), FPS)
    _, moved = estimate_beats(np.stack([full, impulses(130, [44, 92])]), FPS)
    np.testing.assert_allclose(on_beats * FPS, [19, 67])
    np.testing.assert_allclose(moved * FPS, [43, 91])


@pytest.mark.survivor
def test_a_beat_on_the_first_frames_is_at_time_zero():
    full = impulses(300, range(1, 300, 48))
    _, beats = estimate_beats(np.stack([full, full]), FPS)
    assert beats[0] == 0.0 and beats[1] == pytest.approx(48 / FPS)


@pytest.mark.survivor
def test_no_tempo_means_no_beats():
    for envelope in (np.zeros(500), np.ones(500)):  # silence; a constant hum has no rises
        tempo, beats = estimate_beats(np.stack([envelope, envelope]), FPS)
        assert tempo == 0.0 and beats.shape == (0,)


def awkward_envelopes(count: int):
    """Coarse values (ties everywhere), a few equal spikes, long silent or quiet lead-ins and silent
    tails, over lengths from shorter than the tracker's window to thousands of frames. (A flat envelope
    with a single bump is left out: every path scores the same up to float rounding, and the two
    programmes break those ties differently.)"""
    rng = np.random.default_rng(11)
    made = 0
    while made < count:
        frames = int(rng.choice([20, 60, 97, 150, 400, 1200]))
        bpm = float(rng.choice([60.0, 87.5, 120.0, 143.0, 200.0]))
        kind = made % 5
        if kind == 4:  # a quiet lead-in, under the 1 % that may start the beat sequence
            envelope = np.maximum(rng.normal(size=frames), 0.0)
            envelope[: frames // 3] *= 0.003
        elif kind == 0:
            envelope = rng.integers(0, 3, frames).astype(float)
        elif kind == 1:
            envelope = np.zeros(frames)
            envelope[rng.integers(0, frames, 5)] = 1.0
        elif kind == 2:
            envelope = np.maximum(rng.normal(size=frames), 0.0)
            envelope[: frames // 3] = 0.0
        else:
            envelope = np.abs(rng.normal(size=frames)) ** 3
            envelope[-frames // 2:] = 0.0
        if envelope.any():
            made += 1
            yield envelope, bpm


@pytest.mark.survivor
def test_track_beats_equals_librosa_on_awkward_envelopes(monkeypatch):
    librosa = pytest.importorskip("librosa")
    monkeypatch.setattr(beats_module, "_fade_threshold", lambda local, beats: 0.0)  # librosa's trim=False
    for envelope, bpm in awkward_envelopes(100):
        _, expected = librosa.beat.beat_track(onset_envelope=envelope, sr=FPS * 160, hop_length=160, bpm=bpm,
                                              tightness=1600.0, units="frames", trim=False)
        found = track_beats(envelope, FPS, bpm, tightness=1600.0)
        assert found.dtype.kind == "i"
        np.testing.assert_array_equal(found, expected, err_msg=f"{len(envelope)} frames at {bpm} bpm")


@pytest.mark.survivor
def test_track_beats_needs_two_frames_something_to_hear_and_a_tempo():
    assert track_beats(np.array([0.0, 1.0]), FPS, 120.0).dtype.kind == "i"
    for envelope, bpm in ((np.ones(1), 120.0), (np.zeros(300), 120.0), (np.ones(300), 0.0), (np.ones(300), -5.0)):
        beats = track_beats(envelope, FPS, bpm)
        assert beats.shape == (0,) and beats.dtype.kind == "i"


@pytest.mark.survivor
def test_envelope_autocorrelation_by_definition():
    from scipy.ndimage import uniform_filter1d

    from choreo.music.beats import envelope_autocorrelation

    envelope = np.random.default_rng(3).gamma(0.7, size=500)
    rises = np.maximum(envelope - uniform_filter1d(envelope, 96), 0.0)
    lags = np.arange(500)  # a short envelope: every lag up to its length - 1
    expected = np.array([(rises[: 500 - k] * rises[k:]).sum() / (500 - k) for k in lags])
    found = envelope_autocorrelation(envelope, FPS)
    assert found.shape == (500,)
    np.testing.assert_allclose(found, expected / expected[0], rtol=1e-9, atol=1e-12)
    assert envelope_autocorrelation(np.random.default_rng(4).random(5000), FPS).shape == (12 * 96 + 1,)
    flat = envelope_autocorrelation(np.ones(300), FPS)  # no rises at all
    assert not flat.any() and np.isfinite(flat).all()


@pytest.mark.survivor
def test_metrical_salience_by_definition():
    from choreo.music.beats import metrical_salience

    correlation = np.random.default_rng(5).random(400)  # shorter than six periods of slow tempi: those read 0
    bpms, salience = metrical_salience(correlation, FPS)
    assert bpms[0] == 50.0 and bpms[-1] == 260.0 and len(bpms) == 841  # 50 to 260 bpm in quarters, both ends
    lags = np.arange(400)

    def at(multiple, bpm):
        return np.interp(multiple * 60.0 * FPS / bpm, lags, correlation, right=0.0)

    expected = [at(1, b) + max(at(2, b) + at(4, b), at(3, b) + at(6, b)) for b in bpms]
    np.testing.assert_allclose(salience, expected, rtol=1e-12)


@pytest.mark.survivor
def test_the_tempo_priors_are_gaussians_in_octaves_around_120_bpm():
    from choreo.music.beats import _log_prior

    np.testing.assert_allclose(_log_prior(np.array([120.0, 240.0, 60.0, 170.0]), 0.7),
                               np.exp(-0.5 * (np.log2([1.0, 2.0, 0.5, 170 / 120]) / 0.7) ** 2), rtol=1e-12)


def designed_tempo(monkeypatch, peaks: dict) -> float:
    """estimate_tempo when the metrical salience is zero except at ``peaks`` {bpm: salience}."""
    import choreo.music.beats as beats

    def salience(correlation, fps):
        bpms = np.arange(50.0, 260.125, 0.25)
        values = np.zeros(len(bpms))
        for bpm, value in peaks.items():
            values[np.argmin(np.abs(bpms - bpm))] = value
        return bpms, values

    monkeypatch.setattr(beats, "metrical_salience", salience)
    return beats.estimate_tempo(np.random.default_rng(0).random(2000), FPS)


@pytest.mark.survivor
def test_the_octave_can_halve_the_metrical_family(monkeypatch):
    # family (weak prior): 200 (1.0 x 0.886) over 100 (0.8 x 0.985); octave (strong prior): 100 wins
    assert designed_tempo(monkeypatch, {100.0: 0.8, 200.0: 1.0}) == 100.0


@pytest.mark.survivor
def test_the_octave_can_double_the_metrical_family(monkeypatch):
    # family: 55 (5.0 x 0.754) over 110 (2.0 x 0.997); octave: 110 (2.0 x 0.984) over 55 (5.0 x 0.274)
    assert designed_tempo(monkeypatch, {55.0: 5.0, 110.0: 2.0}) == 110.0


@pytest.mark.survivor
def test_the_octave_takes_the_salience_peak_within_one_bpm(monkeypatch):
    # half of the family (200) is 100: the peak at 101 is within 1 bpm of it, the one at 101.75 is not
    assert designed_tempo(monkeypatch, {101.0: 0.8, 101.75: 0.85, 200.0: 1.0}) == 101.0


@pytest.mark.survivor
def test_the_beat_envelope_listens_below_7_khz():
    from choreo.music.beats import onset_envelopes

    sr = 15360
    t = np.arange(4 * sr) / sr
    gate = np.zeros_like(t)
    window = np.hanning(int(0.08 * sr))  # smooth bursts: no broadband clicks at their edges
    for start in np.arange(0.25, 3.8, 0.5):
        gate[int(start * sr): int(start * sr) + len(window)] = window
    high, low = (onset_envelopes((np.sin(2 * np.pi * f * t) * gate).astype(np.float32), sr)[0].max() for f in (7400, 1000))
    assert low > 20 * high  # measured: 22.5 against 0.57 (with the mel bands up to 7.68 kHz: 2.7)


@pytest.mark.survivor
def test_the_onset_envelope_compares_spectra_two_frames_apart():
    from choreo.music.beats import ENVELOPE_FFT, ONSET_LAG, _onset_strength
    from choreo.music.spectrum import onset_strength, power_to_db

    assert ONSET_LAG == 2
    power = np.zeros((64, 40))
    power[:, 20:] = 1.0  # everything switches on at frame 20
    envelope = _onset_strength(power, 15360)
    lag1 = onset_strength(power_to_db(power), ENVELOPE_FFT, 160, lag=1)
    np.testing.assert_allclose(envelope, onset_strength(power_to_db(power), ENVELOPE_FFT, 160, lag=2))
    assert np.count_nonzero(envelope) == 2 * np.count_nonzero(lag1)  # the step is seen from two frames back
