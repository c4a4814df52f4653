"""choreo's numpy mel spectrogram, onset strength and MFCC against librosa's, on real-ish audio."""

import numpy as np
import pytest

from choreo.music.spectrum import mel_filterbank, mel_power, mfcc, onset_strength, power_spectrogram, power_to_db

librosa = pytest.importorskip("librosa")
SR = 15360


def _song(seconds=3.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * SR)) / SR
    clicks = (np.sin(2 * np.pi * 2 * t) > 0.95) * rng.normal(size=t.size)  # a click train
    return (0.3 * np.sin(2 * np.pi * 220 * t) + 0.2 * clicks + 0.01 * rng.normal(size=t.size)).astype(np.float32)


@pytest.mark.parametrize("n_fft, hop, n_mels, fmax", [(2048, 512, 128, None), (1024, 160, 64, 7000.0), (2048, 512, 96, None)])
def test_mel_spectrogram_equals_librosa(n_fft, hop, n_mels, fmax):
    y = _song()
    ours = mel_power(y, SR, n_fft, hop, n_mels, fmax)
    theirs = librosa.feature.melspectrogram(y=y, sr=SR, n_fft=n_fft, hop_length=hop, n_mels=n_mels, fmax=fmax)
    assert ours.shape == theirs.shape
    np.testing.assert_allclose(ours, theirs, rtol=2e-4, atol=1e-6 * theirs.max())
    np.testing.assert_allclose(mel_filterbank(SR, n_fft, n_mels, 0.0, fmax),
                               librosa.filters.mel(sr=SR, n_fft=n_fft, n_mels=n_mels, fmax=fmax), rtol=1e-5, atol=1e-8)


def test_uncentred_frames_and_short_signals_equal_librosa():
    y = _song(1.0)
    theirs = librosa.feature.melspectrogram(y=y, sr=SR, n_fft=2048, hop_length=512, n_mels=96, center=False)
    np.testing.assert_allclose(mel_power(y, SR, 2048, 512, 96, center=False), theirs, rtol=2e-4, atol=1e-6 * theirs.max())
    assert power_spectrogram(y[:100], 2048, 512, center=False).shape == (1025, 0)


def test_onset_strength_and_mfcc_equal_librosa():
    y = _song()
    log_mel = power_to_db(mel_power(y, SR, 1024, 160, 64, 7000.0))
    theirs = librosa.onset.onset_strength(S=log_mel, sr=SR, hop_length=160, n_fft=1024, lag=2)
    np.testing.assert_allclose(onset_strength(log_mel, 1024, 160, lag=2), theirs, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(power_to_db(log_mel * 0 + 1e-12), -100.0)  # the fixed floor
    np.testing.assert_allclose(mfcc(log_mel, 20), librosa.feature.mfcc(S=log_mel, sr=SR, n_mfcc=20), rtol=1e-4, atol=1e-3)


@pytest.mark.parametrize("seed", range(6))
def test_onset_peaks_equal_librosa_onset_detect(seed):
    from choreo.music.beats import onset_peaks

    rng = np.random.default_rng(seed)
    envelope = np.abs(rng.normal(size=400)) * (rng.random(400) < 0.3) + 0.05 * rng.random(400)
    if seed == 5:
        envelope[:3] = [5.0, 0.0, 0.0]  # a peak on the first frame
    expected = librosa.onset.onset_detect(onset_envelope=envelope, sr=30 * 512, hop_length=512, units="frames")
    np.testing.assert_array_equal(onset_peaks(envelope, 30.0), expected)
    assert onset_peaks(np.zeros(10), 30.0).size == 0


def test_a_rhythm_only_analysis_has_the_same_rhythm_and_never_imports_librosa(tmp_path):
    import subprocess
    import sys

    import soundfile as sf

    from choreo.music import BEAT_COLUMN, PEAK_COLUMN, Music

    y = np.tile(_song(2.0), 4)
    path = tmp_path / "song.wav"
    sf.write(path, y, SR)
    full, rhythm = Music.from_file(path), Music.from_file(path, timbre=False)
    assert full.timbre and not rhythm.timbre
    np.testing.assert_array_equal(rhythm.beat_times, full.beat_times)
    for column in (0, PEAK_COLUMN, BEAT_COLUMN):  # onset envelope, onset peaks, beats: equal
        np.testing.assert_array_equal(rhythm.features[:, column], full.features[:, column])
    assert not rhythm.features[:, 1:PEAK_COLUMN].any() and full.features[:, 1:PEAK_COLUMN].any()
    code = ("import sys; from choreo.music import Music; "
            f"Music.from_file({str(path)!r}, timbre=False, log_mel=True); print('librosa' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"


def test_sgmd_refuses_music_analysed_without_timbre(tiny_generator):
    from choreo.errors import ParameterError
    from choreo.generator import GenerationRequest
    from choreo.music import Music

    music = Music.from_array(np.tile(_song(2.0), 3), SR, timbre=False)
    with pytest.raises(ParameterError, match="MFCC and chroma"):
        tiny_generator.generate(GenerationRequest(music))


def test_the_mel_scale_equals_librosa_on_both_sides_of_1_khz():
    from choreo.music.spectrum import _hz_to_mel, _mel_to_hz

    hz = np.array([0.0, 10.0, 440.0, 999.0, 1000.0, 1000.5, 1001.0, 4000.0, 7680.0])
    np.testing.assert_allclose(_hz_to_mel(hz), librosa.hz_to_mel(hz), rtol=1e-12, atol=1e-12)
    mel = np.linspace(0.0, 45.0, 19)
    np.testing.assert_allclose(_mel_to_hz(mel), librosa.mel_to_hz(mel), rtol=1e-12, atol=1e-9)
    mel_filterbank.cache_clear()  # built again here, from the functions above (not from a cached copy)
    np.testing.assert_allclose(mel_filterbank(SR, 512, 40, 20.0, 6000.0),
                               librosa.filters.mel(sr=SR, n_fft=512, n_mels=40, fmin=20.0, fmax=6000.0), rtol=1e-5, atol=1e-8)


def test_outputs_are_float32_whatever_the_input_and_edges_are_exact():
    y = _song(0.5).astype(np.float64)
    assert power_spectrogram(y, 512, 128).dtype == np.float32
    assert power_spectrogram(y[:10], 512, 128, center=False).dtype == np.float32
    exact = power_spectrogram(y[:512], 512, 128, center=False)  # a signal exactly one window long: one frame
    np.testing.assert_allclose(exact, np.abs(librosa.stft(y[:512].astype(np.float32), n_fft=512, hop_length=128, center=False)) ** 2,
                               rtol=2e-4, atol=1e-6)
    log_mel = power_to_db(mel_power(y, SR, 512, 128, 40))
    assert log_mel.dtype == np.float32 and onset_strength(log_mel, 512, 128).dtype == np.float32


def test_defaults_are_librosas():
    y = _song(0.5)
    centred = np.abs(librosa.stft(y, n_fft=512, hop_length=128, pad_mode="constant")) ** 2
    np.testing.assert_allclose(power_spectrogram(y, 512, 128), centred, rtol=2e-4, atol=1e-6 * centred.max())
    log_mel = power_to_db(mel_power(y, SR, 512, 128, 40))
    np.testing.assert_allclose(onset_strength(log_mel, 512, 128), librosa.onset.onset_strength(S=log_mel, sr=SR, hop_length=128, n_fft=512),
                               rtol=1e-5, atol=1e-5)  # lag 1
