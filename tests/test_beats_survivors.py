"""What the beat tracker's mutation run (scripts/mutation_score.py beats) found untested: the
peak picker's windows, ties and spacing, the onset-peak normalisation, the half-beat move of the
grid when the percussion sits between the beats, and the rhythm channels' edges (irregular grids,
shapes, bounds, half-marked frames)."""

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.music import BEAT_COLUMN, FEATURE_DIM, PEAK_COLUMN, beat_phase, rhythm_channels, stretch_features
from choreo.music.beats import ENVELOPE_LATENCY, estimate_beats, onset_peaks, pick_peaks, track_beats

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


@pytest.mark.parametrize("pre_max, post_max, pre_avg, post_avg, delta, wait",
                         [(1, 1, 3, 4, 0.0, 0), (3, 1, 2, 2, 0.1, 2), (1, 3, 5, 1, 0.05, 1), (2, 2, 1, 6, 0.0, 4)])
def test_pick_peaks_follows_the_definition_on_coarse_values_with_ties(pre_max, post_max, pre_avg, post_avg, delta, wait):
    rng = np.random.default_rng(pre_max * 10 + wait)
    for _ in range(40):
        x = rng.integers(0, 4, size=int(rng.integers(1, 30))) / 4.0  # quarters: ties everywhere
        found = pick_peaks(x, pre_max, post_max, pre_avg, post_avg, delta, wait)
        assert found.dtype.kind == "i"
        assert found.tolist() == peaks_by_definition(x, pre_max, post_max, pre_avg, post_avg, delta, wait)


def test_pick_peaks_by_hand():
    x = np.array([0.0, 1.0, 0.0, 0.9, 0.0, 0.0, 0.8, 0.0])
    assert pick_peaks(x, 1, 2, 1, 2, 0.0, 0).tolist() == [1, 3, 6]
    assert pick_peaks(x, 1, 2, 1, 2, 0.0, 1).tolist() == [1, 3, 6]  # two frames apart is more than one
    assert pick_peaks(x, 1, 2, 1, 2, 0.0, 2).tolist() == [1, 6]  # 3 is only two after 1
    assert pick_peaks(x, 3, 1, 1, 2, 0.0, 0).tolist() == [1]  # 1.0 is two frames before 0.9, 0.9 three before 0.8
    assert pick_peaks(np.array([0.5, 0.5]), 1, 1, 1, 1, 0.0, 0).tolist() == [0, 1]  # equal to the mean is enough
    assert pick_peaks(np.zeros(0), 1, 1, 1, 1, 0.0, 0).tolist() == []


def test_onset_peaks_ignore_offset_and_scale_and_take_integer_envelopes():
    envelope = np.zeros(200)
    envelope[[20, 50, 90, 140]] = [3.0, 1.0, 2.0, 4.0]
    peaks = onset_peaks(envelope, 30.0)
    assert peaks.tolist() == [20, 50, 90, 140]
    assert onset_peaks(envelope + 7.0, 30.0).tolist() == peaks.tolist()
    assert onset_peaks(5.0 * envelope, 30.0).tolist() == peaks.tolist()
    assert onset_peaks(envelope.astype(int), 30.0).tolist() == peaks.tolist()


def test_onset_peaks_of_a_flat_or_broken_envelope_are_none():
    for envelope in (np.zeros(50), np.r_[np.ones(10), np.nan, np.ones(10)], np.r_[np.ones(5), np.inf]):
        peaks = onset_peaks(envelope, 30.0)
        assert peaks.shape == (0,) and peaks.dtype.kind == "i"


def impulses(length: int, frames) -> np.ndarray:
    envelope = np.zeros(length)
    envelope[list(frames)] = 1.0
    return envelope


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


def test_two_beats_are_enough_to_move_the_grid():
    full = impulses(130, [20, 68])
    _, on_beats = estimate_beats(np.stack([full, full]), FPS)
    _, moved = estimate_beats(np.stack([full, impulses(130, [44, 92])]), FPS)
    np.testing.assert_allclose(on_beats * FPS, [19, 67])
    np.testing.assert_allclose(moved * FPS, [43, 91])


def test_a_beat_on_the_first_frames_is_at_time_zero():
    full = impulses(300, range(1, 300, 48))
    _, beats = estimate_beats(np.stack([full, full]), FPS)
    assert beats[0] == 0.0 and beats[1] == pytest.approx(48 / FPS)


def test_no_tempo_means_no_beats():
    for envelope in (np.zeros(500), np.ones(500)):  # silence; a constant hum has no rises
        tempo, beats = estimate_beats(np.stack([envelope, envelope]), FPS)
        assert tempo == 0.0 and beats.shape == (0,)


# -- rhythm.py --------------------------------------------------------------------------------------

def test_two_beats_give_a_phase():
    phase = beat_phase(np.array([10, 20]), 30)
    assert phase is not None and phase[15] == pytest.approx(0.5) and phase[25] == pytest.approx(0.5)


def test_an_irregular_grid_is_interpolated_inside_and_continued_outside_from_the_first_beat():
    beats = np.array([13, 20, 30, 40])  # gaps 7, 10, 10: median period 10
    phase = beat_phase(beats, 50)
    assert phase[16] == pytest.approx(3 / 7)  # between the first two beats: linear, not the median grid
    assert phase[40] == pytest.approx(0.0)  # on the last beat
    assert phase[13] == pytest.approx(0.0)
    assert phase[5] == pytest.approx(0.2)  # (5 - 13) / 10, counted from the first beat
    assert phase[45] == pytest.approx(0.2)  # (45 - 13) / 10


def test_rhythm_channels_refuse_other_shapes_with_the_expected_one():
    with pytest.raises(ParameterError, match=rf"music features must have shape \(T, {FEATURE_DIM}\), got \(10, 34\)"):
        rhythm_channels(np.zeros((10, FEATURE_DIM - 1)))
    with pytest.raises(ParameterError, match="must have shape"):
        rhythm_channels(np.zeros(FEATURE_DIM))


def test_rhythm_channels_are_float32_and_a_half_marked_frame_is_no_beat():
    features = np.zeros((60, FEATURE_DIM))
    features[[0, 15, 30, 45], BEAT_COLUMN] = 1.0
    features[[7, 22], BEAT_COLUMN] = 0.5  # not above one half: no beat, still 120 bpm
    channels = rhythm_channels(features)
    assert channels.dtype == np.float32
    assert channels[0, 2] == pytest.approx(0.0, abs=1e-6)


def test_stretched_features_are_float32_with_unit_spikes_inside_the_song():
    features = np.zeros((100, FEATURE_DIM))  # float64 in
    features[[0, 40, 99], BEAT_COLUMN] = 1.0  # 99 / 1.6 = 61.9: rounds to 62, past the last frame (61)
    features[[10], PEAK_COLUMN] = 0.5  # not a spike
    fast = stretch_features(features, 1.6)
    assert fast.dtype == np.float32 and len(fast) == 62
    assert np.flatnonzero(fast[:, BEAT_COLUMN]).tolist() == [0, 25]
    assert set(fast[:, BEAT_COLUMN].tolist()) == {0.0, 1.0} and not fast[:, PEAK_COLUMN].any()


@pytest.mark.parametrize("factor", [0.25, 4.0])
def test_stretch_factors_at_the_bounds_are_taken(factor):
    assert len(stretch_features(np.zeros((9, FEATURE_DIM)), factor)) == int(np.floor(8 / factor)) + 1


@pytest.mark.parametrize("factor", [0.2499, 4.001, 5.0])
def test_stretch_factors_outside_the_bounds_are_refused(factor):
    with pytest.raises(ParameterError, match=rf"stretch factor must be within \[0.25, 4\], got {factor}"):
        stretch_features(np.zeros((9, FEATURE_DIM)), factor)


# -- the beat tracker's dynamic programme against librosa's, on inputs with ties and edges ----------

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


def test_track_beats_equals_librosa_on_awkward_envelopes():
    librosa = pytest.importorskip("librosa")
    for envelope, bpm in awkward_envelopes(100):
        _, expected = librosa.beat.beat_track(onset_envelope=envelope, sr=FPS * 160, hop_length=160, bpm=bpm,
                                              tightness=1600.0, units="frames")
        found = track_beats(envelope, FPS, bpm, tightness=1600.0)
        assert found.dtype.kind == "i"
        np.testing.assert_array_equal(found, expected, err_msg=f"{len(envelope)} frames at {bpm} bpm")


def test_track_beats_needs_two_frames_something_to_hear_and_a_tempo():
    assert track_beats(np.array([0.0, 1.0]), FPS, 120.0).dtype.kind == "i"
    for envelope, bpm in ((np.ones(1), 120.0), (np.zeros(300), 120.0), (np.ones(300), 0.0), (np.ones(300), -5.0)):
        beats = track_beats(envelope, FPS, bpm)
        assert beats.shape == (0,) and beats.dtype.kind == "i"


# -- tempo: the autocorrelation, the metrical salience, the two priors --------------------------------

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


def test_the_octave_can_halve_the_metrical_family(monkeypatch):
    # family (weak prior): 200 (1.0 x 0.886) over 100 (0.8 x 0.985); octave (strong prior): 100 wins
    assert designed_tempo(monkeypatch, {100.0: 0.8, 200.0: 1.0}) == 100.0


def test_the_octave_can_double_the_metrical_family(monkeypatch):
    # family: 55 (5.0 x 0.754) over 110 (2.0 x 0.997); octave: 110 (2.0 x 0.984) over 55 (5.0 x 0.274)
    assert designed_tempo(monkeypatch, {55.0: 5.0, 110.0: 2.0}) == 110.0


def test_the_octave_takes_the_salience_peak_within_one_bpm(monkeypatch):
    # half of the family (200) is 100: the peak at 101 is within 1 bpm of it, the one at 101.75 is not
    assert designed_tempo(monkeypatch, {101.0: 0.8, 101.75: 0.85, 200.0: 1.0}) == 101.0


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
