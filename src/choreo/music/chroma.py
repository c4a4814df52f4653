"""Chroma energy-normalised statistics (CENS) in numpy, equal to librosa 0.11's ``chroma_cens``.

Why not librosa's: its first chroma_cens in a process costs seconds (lazy imports, numba kernels),
and every ``choreo generate`` is a fresh process. The bundled models were trained on librosa's
values, so this reproduces its arithmetic step by step, down to the dtype of each intermediate
(float32 audio is analysed in complex64 with some steps in float64, as librosa does) and the
library doing each sum (scipy's FFT and sparse product, numpy's einsum): a change of the last bit
can move a value across one of the CENS quantisation thresholds, which changes the output by up
to a few hundredths, so "close" is not enough. tests/music/test_chroma.py checks bit equality with the
installed librosa.

Only what choreo uses is here: ``tuning=0``, 12 chroma from a constant-Q transform at librosa's
defaults (fmin C1, 7 octaves of 36 bins, Hann wavelets, filter scale 1, L1-normalised filters,
sparsity 0.01, ``soxr_hq`` halving from octave to octave), 41-frame Hann smoothing, L2 output.
"""

from __future__ import annotations

import functools
import math

import numpy as np

N_CHROMA = 12
BINS_PER_OCTAVE = 36
N_OCTAVES = 7
FMIN_C1 = 440.0 * 2.0 ** ((24 - 69.0) / 12.0)  # C1, midi note 24, at A440 (librosa.note_to_hz("C1"))
HANN_BANDWIDTH = 1.50018310546875  # equivalent noise bandwidth of a Hann window in bins (librosa's table)
SPARSITY = 0.01  # fraction of each filter's spectral magnitude dropped to make the basis sparse
CENS_STEPS = (0.4, 0.2, 0.1, 0.05)  # "log-like" thresholds on L1-normalised chroma, each worth 0.25
SMOOTHING_FRAMES = 41


def chroma_cens(samples: np.ndarray, sr: int, hop_length: int) -> np.ndarray:
    """(12, 1 + len(samples) // hop_length) CENS chroma of mono ``samples``, frames centred on
    sample t * hop_length (librosa.feature.chroma_cens(y=samples, sr=sr, hop_length=hop_length,
    tuning=0.0) with every other argument at its default)."""
    samples = np.asarray(samples)
    if not np.issubdtype(samples.dtype, np.floating):
        samples = samples.astype(np.float32)
    if samples.ndim != 1 or not np.isfinite(samples).all():
        raise ValueError("chroma_cens needs a finite mono signal")
    # np.einsum, not a plain matrix product: librosa sums this way, and the two differ in the last bit
    chroma = np.einsum("cf,ft->ct", cq_to_chroma_matrix(N_OCTAVES * BINS_PER_OCTAVE),
                       cqt_magnitude(samples, sr, hop_length), optimize=True)
    quantised = _quantise(normalize_columns(chroma, 1))
    return normalize_columns(_smooth(quantised), 2)


# --- the constant-Q filter bank ---------------------------------------------------------------


def _cqt_frequencies(n_bins: int = N_OCTAVES * BINS_PER_OCTAVE, fmin: float = FMIN_C1,
                     bins_per_octave: int = BINS_PER_OCTAVE) -> np.ndarray:
    """Centre frequencies in Hz, equal temperament from ``fmin``; computed as octave x ratio so
    the values are librosa's to the last bit (the filters and their lengths depend on them)."""
    ratios = 2.0 ** ((0.0 + np.arange(0, bins_per_octave, dtype=float)) / bins_per_octave)
    octaves = 2.0 ** np.arange(np.ceil(n_bins / bins_per_octave))
    return np.sort(np.multiply.outer(octaves, ratios).flatten()[:n_bins]) * fmin


def _relative_bandwidths(freqs: np.ndarray) -> np.ndarray:
    """alpha = bandwidth / centre frequency of each filter, from the local spacing of log2(freqs)
    (one-sided at the two ends); 1 / alpha is the Q factor."""
    logf = np.log2(freqs)
    bins_per_octave = np.empty_like(freqs)
    bins_per_octave[0] = 1 / (logf[1] - logf[0])
    bins_per_octave[-1] = 1 / (logf[-1] - logf[-2])
    bins_per_octave[1:-1] = 2 / (logf[2:] - logf[:-2])
    return (2.0 ** (2 / bins_per_octave) - 1) / (2.0 ** (2 / bins_per_octave) + 1)


def _filter_lengths(freqs: np.ndarray, alpha: np.ndarray, sr: float) -> np.ndarray:
    """Fractional filter lengths in samples: Q periods of each centre frequency."""
    q = 1.0 / alpha
    return q * sr / freqs


def _filter_cutoff(freqs: np.ndarray, alpha: np.ndarray) -> float:
    """The highest frequency any filter reaches (centre + half its Hann bandwidth): decides how
    far the signal may be downsampled before the first octave."""
    q = 1.0 / alpha
    return float(max(freqs * (1 + 0.5 * HANN_BANDWIDTH / q)))


def _hann(length: int, periodic: bool) -> np.ndarray:
    """scipy.signal's Hann window (periodic for FFT use, symmetric for smoothing), computed as it
    does so the values match to the last bit without importing scipy.signal (slow)."""
    if length <= 1:
        return np.ones(length)
    points = length + 1 if periodic else length
    angles = np.linspace(-np.pi, np.pi, points, dtype=np.float64)
    window = np.zeros(points, dtype=np.float64)
    window += 0.5 * np.cos(0 * angles)
    window += 0.5 * np.cos(1 * angles)
    return window[:-1] if periodic else window


def _wavelet(freq: float, length: float, sr: float) -> np.ndarray:
    """One complex128 periodic-Hann-windowed sinusoid of about ``length`` samples (an even count
    centred on 0), scaled to unit L1 norm.

    cos and sin come from the C library (math), as numba's compiled phasor does; numpy's
    vectorised versions can differ in the last bit."""
    angles = np.arange(-length // 2, length // 2, dtype=float) * 2 * np.pi * freq / sr
    wave = np.empty(len(angles), dtype=np.complex128)
    wave.real = np.fromiter(map(math.cos, angles.tolist()), dtype=np.float64, count=len(angles))
    wave.imag = np.fromiter(map(math.sin, angles.tolist()), dtype=np.float64, count=len(angles))
    wave *= _hann(len(wave), periodic=True)
    return wave / np.sum(np.abs(wave).astype(float))


def _pad_center(row: np.ndarray, size: int) -> np.ndarray:
    """Zero-pad to ``size`` with the row in the middle (one sample more on the right if odd), so
    each filter's phase reference stays at the centre of the FFT frame."""
    left = (size - len(row)) // 2
    return np.pad(row, (left, size - len(row) - left))


def _sparse_filter_fft(freqs: np.ndarray, alpha: np.ndarray, sr: float, complex_dtype: type):
    """(scipy.sparse CSR (bins, 1 + n_fft // 2), n_fft): the filters of one octave in the frequency
    domain, each zero-padded to a power of two and rescaled by length / n_fft; in each row the
    smallest magnitudes adding up to 1 % of the row's total are dropped.

    The response is computed as this sparse matrix times an STFT, with scipy.sparse, so that
    complex64 sums run in librosa's order."""
    import scipy.fft
    import scipy.sparse

    lengths = _filter_lengths(freqs, alpha, sr)
    n_fft = int(2.0 ** (np.ceil(np.log2(max(lengths)))))
    wavelets = [_pad_center(_wavelet(freq, length, sr), n_fft) for length, freq in zip(lengths, freqs)]
    basis = np.asarray(wavelets, dtype=complex_dtype)
    basis *= lengths[:, np.newaxis] / float(n_fft)
    spectrum = scipy.fft.fft(basis, n=n_fft, axis=1)[:, : n_fft // 2 + 1]
    magnitudes = np.abs(spectrum)
    ordered = np.sort(magnitudes, axis=1)
    cumulative = np.cumsum(ordered / np.sum(magnitudes, axis=1, keepdims=True), axis=1)
    smallest_kept = ordered[np.arange(len(ordered)), np.argmin(cumulative < SPARSITY, axis=1)]
    kept = np.where(magnitudes >= smallest_kept[:, None], spectrum, 0).astype(complex_dtype)
    return scipy.sparse.csr_matrix(kept, dtype=complex_dtype), n_fft


def _early_downsampling(sr: float, hop_length: int, cutoff: float) -> int:
    """How many times the signal can be halved before the top octave: while the filters stay well
    under the new Nyquist frequency and the hop stays divisible through all octaves."""
    by_bandwidth = max(0, int(np.ceil(np.log2(sr / 2.0 / cutoff)) - 1) - 1)
    twos = 0
    while hop_length > 0 and hop_length % 2 ** (twos + 1) == 0:
        twos += 1
    return min(by_bandwidth, max(0, twos - N_OCTAVES + 1))


@functools.lru_cache(maxsize=8)
def _octave_bank(sr: float, hop_length: int, complex_dtype: type):
    """Everything about the transform that does not depend on the signal, per (sr, hop, dtype):
    (halvings before the top octave, [(sparse filters, n_fft) top octave first], filter lengths
    at the analysis rate)."""
    freqs = _cqt_frequencies()
    alpha = _relative_bandwidths(freqs)
    if _filter_cutoff(freqs, alpha) > sr / 2.0:
        raise ValueError(f"a constant-Q transform up to {freqs[-1]:.0f} Hz needs a sample rate over {sr}")
    halvings = _early_downsampling(sr, hop_length, _filter_cutoff(freqs, alpha))
    sr = sr / float(2**halvings) if halvings else sr
    octaves, octave_sr, hop = [], sr, hop_length // 2**halvings
    for octave in range(N_OCTAVES):
        bins = slice(len(freqs) - BINS_PER_OCTAVE * (octave + 1), len(freqs) - BINS_PER_OCTAVE * octave)
        filters, n_fft = _sparse_filter_fft(freqs[bins], alpha[bins], octave_sr, complex_dtype)
        filters.data *= np.sqrt(sr / octave_sr)  # compensates the halvings' 1/sqrt(2) amplitude scaling
        octaves.append((filters, n_fft))
        if hop % 2 == 0:  # the signal is halved after this octave (see cqt_magnitude)
            hop, octave_sr = hop // 2, octave_sr / 2.0
    return halvings, tuple(octaves), _filter_lengths(freqs, alpha, sr)


# --- the transform ------------------------------------------------------------------------------


def _downsample(samples: np.ndarray, factor: int) -> np.ndarray:
    """soxr "HQ" decimation by ``factor``, trimmed or zero-padded to ceil(n / factor) samples and
    multiplied by sqrt(factor) (librosa.resample(..., res_type="soxr_hq", scale=True))."""
    import soxr

    target = int(np.ceil(len(samples) * (1.0 / factor)))
    out = soxr.resample(samples, factor, 1, quality="HQ")
    out = out[:target] if len(out) >= target else np.pad(out, (0, target - len(out)))
    out /= np.sqrt(1.0 / factor)
    return np.asarray(out, dtype=samples.dtype)


def _centred_stft(samples: np.ndarray, n_fft: int, hop_length: int, complex_dtype: type) -> np.ndarray:
    """(1 + n_fft // 2, 1 + len // hop) rectangular-window STFT, frames centred (zero padding);
    the FFT runs in float64 and is rounded to ``complex_dtype`` (librosa's window="ones" is
    float64, which promotes float32 frames). scipy's FFT, not numpy's: they differ in the last bit,
    and librosa uses scipy's."""
    import scipy.fft

    padded = np.pad(samples, n_fft // 2)
    frames = np.lib.stride_tricks.sliding_window_view(padded, n_fft)[::hop_length]
    return scipy.fft.rfft(frames.astype(np.float64), axis=-1).astype(complex_dtype).T


def cqt_magnitude(samples: np.ndarray, sr: float, hop_length: int) -> np.ndarray:
    """(252, frames) |constant-Q transform| (librosa.cqt(y, sr=sr, hop_length=hop_length,
    n_bins=252, bins_per_octave=36, tuning=0.0) in absolute value), F-ordered as librosa's is.

    Octave by octave from the top: filter the signal with the octave's sparse bank, then halve
    sample rate and hop; finally divide each bin by the square root of its filter length."""
    complex_dtype = np.complex64 if samples.dtype == np.float32 else np.complex128
    halvings, octaves, lengths = _octave_bank(float(sr), int(hop_length), complex_dtype)
    if halvings:
        if len(samples) < 2**halvings:
            raise ValueError(f"a signal of {len(samples)} samples is too short for a 7-octave CQT")
        samples = _downsample(samples, 2**halvings)
    hop = hop_length // 2**halvings
    responses = []
    for octave, (filters, n_fft) in enumerate(octaves):
        responses.append(filters.dot(_centred_stft(samples, n_fft, hop, complex_dtype)))
        if hop % 2 == 0 and octave < len(octaves) - 1:
            hop //= 2
            samples = _downsample(samples, 2)
    frames = min(response.shape[-1] for response in responses)
    cqt = np.empty((len(lengths), frames), dtype=complex_dtype, order="F")
    for octave, response in enumerate(responses):
        top = len(lengths) - BINS_PER_OCTAVE * octave
        cqt[top - response.shape[0]: top] = response[:, :frames]
    cqt /= np.sqrt(lengths)[:, np.newaxis]
    return np.abs(cqt)


# --- from constant-Q bins to CENS ---------------------------------------------------------------


@functools.lru_cache(maxsize=4)
def cq_to_chroma_matrix(n_input: int, bins_per_octave: int = BINS_PER_OCTAVE,
                        fmin: float = FMIN_C1) -> np.ndarray:
    """(12, n_input) float32 0/1 matrix summing the 3 constant-Q bins around each semitone (the
    bin on the note and its two neighbours) into its pitch class, C first."""
    merge = bins_per_octave // N_CHROMA
    one_octave = np.roll(np.repeat(np.eye(N_CHROMA), merge, axis=1), -(merge // 2), axis=1)
    matrix = np.tile(one_octave, int(np.ceil(n_input / bins_per_octave)))[:, :n_input]
    first_note = np.mod(12 * (np.log2(fmin) - np.log2(440.0)) + 69, 12)
    matrix = np.roll(matrix, int(np.round(first_note)), axis=0).astype(np.float32)
    matrix.flags.writeable = False  # shared by the cache
    return matrix


def normalize_columns(values: np.ndarray, norm: int) -> np.ndarray:
    """Each column divided by its L``norm`` norm (computed in float64, result in the input's
    dtype); columns whose norm is below the dtype's smallest normal number are left as they are
    (silence stays zero rather than becoming NaN)."""
    magnitudes = np.abs(values).astype(float)
    length = np.sum(magnitudes**norm, axis=-2, keepdims=True) ** (1.0 / norm)
    length[length < np.finfo(values.dtype).tiny] = 1.0
    out = np.empty_like(values)
    out[:] = values / length
    return out


def _quantise(chroma: np.ndarray) -> np.ndarray:
    """0.25 for each CENS threshold a normalised chroma value exceeds (0, 0.25, ..., 1)."""
    quantised = np.zeros_like(chroma)
    for step in CENS_STEPS:
        quantised += (chroma > step) * 0.25
    return quantised


def _smooth(chroma: np.ndarray) -> np.ndarray:
    """Centred moving average over time with a 41-frame Hann window (43 points with zero ends,
    summing to 1), zeros outside the signal (scipy.ndimage.convolve, mode "constant", which
    accumulates in float64 in its own order)."""
    import scipy.ndimage

    window = _hann(SMOOTHING_FRAMES + 2, periodic=False)
    window /= np.sum(window)
    return scipy.ndimage.convolve(chroma, window[np.newaxis, :], mode="constant")
