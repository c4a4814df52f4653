"""Mel spectrograms and onset strength in numpy, equal to librosa's (tested to float32 precision).

Why not librosa's: its spectral module compiles numba kernels and imports scipy.signal on first
use, several seconds in every fresh process, and the beats, the onset envelope, the MFCCs and
ChoreoGraph's log-mel need nothing more than a windowed FFT and a filter bank. (The chroma of the
35-d features, a constant-Q transform, is choreo.music.chroma.)
"""

from __future__ import annotations

import functools

import numpy as np


def power_spectrogram(samples: np.ndarray, n_fft: int, hop_length: int, center: bool = True) -> np.ndarray:
    """(1 + n_fft // 2, frames) |STFT|^2 with a periodic Hann window; ``center`` zero-pads
    n_fft // 2 samples on both sides so frame t is centred on sample t * hop_length (librosa's
    ``center=True, pad_mode="constant"``)."""
    samples = np.asarray(samples, dtype=np.float32)
    if center:
        samples = np.pad(samples, n_fft // 2)
    if len(samples) < n_fft:
        return np.zeros((1 + n_fft // 2, 0), np.float32)
    frames = np.lib.stride_tricks.sliding_window_view(samples, n_fft)[::hop_length]
    window = (0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n_fft) / n_fft)).astype(np.float32)
    spectrum = np.fft.rfft(frames * window, axis=-1)
    return (spectrum.real**2 + spectrum.imag**2).astype(np.float32).T


def _hz_to_mel(hz: np.ndarray) -> np.ndarray:
    """Slaney's mel scale: linear below 1 kHz, logarithmic above."""
    hz = np.asarray(hz, dtype=np.float64)
    linear = hz / (200.0 / 3)
    log_part = 15.0 + np.log(np.maximum(hz, 1e-10) / 1000.0) / (np.log(6.4) / 27.0)
    return np.where(hz >= 1000.0, log_part, linear)


def _mel_to_hz(mel: np.ndarray) -> np.ndarray:
    mel = np.asarray(mel, dtype=np.float64)
    return np.where(mel >= 15.0, 1000.0 * np.exp((np.log(6.4) / 27.0) * (mel - 15.0)), mel * (200.0 / 3))


@functools.lru_cache(maxsize=16)
def mel_filterbank(sr: int, n_fft: int, n_mels: int, fmin: float = 0.0, fmax: float | None = None) -> np.ndarray:
    """(n_mels, 1 + n_fft // 2) triangular Slaney-normalised filters (librosa.filters.mel's defaults)."""
    fmax = sr / 2 if fmax is None else fmax
    fft_hz = np.linspace(0, sr / 2, 1 + n_fft // 2)
    edges = _mel_to_hz(np.linspace(_hz_to_mel(fmin), _hz_to_mel(fmax), n_mels + 2))
    widths = np.diff(edges)
    ramps = edges[:, None] - fft_hz[None, :]
    rising = -ramps[:-2] / widths[:-1, None]
    falling = ramps[2:] / widths[1:, None]
    weights = np.maximum(0.0, np.minimum(rising, falling)) * (2.0 / (edges[2:] - edges[:-2]))[:, None]
    weights = weights.astype(np.float32)
    weights.flags.writeable = False  # shared by the cache
    return weights


def mel_power(samples: np.ndarray, sr: int, n_fft: int, hop_length: int, n_mels: int, fmax: float | None = None,
              center: bool = True) -> np.ndarray:
    """(n_mels, frames) mel power spectrogram (librosa.feature.melspectrogram with these arguments)."""
    return mel_filterbank(sr, n_fft, n_mels, 0.0, fmax) @ power_spectrogram(samples, n_fft, hop_length, center)


def power_to_db(power: np.ndarray, amin: float = 1e-10) -> np.ndarray:
    """10 log10(max(power, amin)), with no clipping relative to the loudest value (a fixed floor, so
    a block of a song gets the values the whole song would)."""
    return (10.0 * np.log10(np.maximum(power, amin))).astype(power.dtype, copy=False)


def onset_strength(log_mel: np.ndarray, n_fft: int, hop_length: int, lag: int = 1) -> np.ndarray:
    """(frames,) spectral flux of a (bands, frames) log-mel: the mean over bands of the rise since
    ``lag`` frames before, aligned to centred frames (librosa.onset.onset_strength of ``S=log_mel``)."""
    flux = np.maximum(0.0, log_mel[:, lag:] - log_mel[:, :-lag]).mean(axis=0)
    padded = np.concatenate([np.zeros(lag + n_fft // (2 * hop_length), flux.dtype), flux])
    return padded[: log_mel.shape[1]]


def mfcc(log_mel: np.ndarray, n_mfcc: int) -> np.ndarray:
    """(n_mfcc, frames) orthonormal DCT-II of a (bands, frames) log-mel (librosa.feature.mfcc of ``S``)."""
    import scipy.fft

    return scipy.fft.dct(log_mel, axis=0, type=2, norm="ortho")[:n_mfcc]
