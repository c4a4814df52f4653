"""Tempo and beats, heard on a 96 fps onset envelope and mapped to 30 fps frames afterwards.

Why not the 30 fps features' envelope: at 30 fps the autocorrelation lags give tempi in coarse
steps (128.6, 138.5, 150 bpm...), so a 132 bpm song drifts a whole beat in 38 beats. At 96 fps
(hop 160 at 15360 Hz) a lag step is under 1.5 bpm at 130 bpm, and the lag is interpolated.

The tempo is chosen in two stages, each on evidence from the whole song:
1. metrical family: a period is credited with the autocorrelation at one, two and four periods
   (or one, three and six, for triple metre), so a grid whose multiples keep landing on the bars
   beats one at 2/3 or 4/3 of the tempo that only matches at its own lag (the confusion the
   30 fps tracker made on a third of outside songs);
2. octave: half, the same or double tempo, by the same score under a prior centred on 120 bpm.
Beats are then placed by dynamic programming (Ellis 2007, librosa's beat_track) at that tempo,
and the grid is moved by half a beat when the percussive part of the music (median-filter
harmonic/percussive separation of the mel spectrogram) is stronger between the beats than on them.
A tempo the user gives (``choreo generate --bpm``) replaces the estimate: :func:`beats_at_tempo`.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.ndimage

from .spectrum import mel_power, onset_strength, power_to_db

BEAT_HOP = 160  # samples at 15360 Hz: 96 envelope frames per second
ENVELOPE_MELS = 64
ENVELOPE_FFT = 1024
ENVELOPE_FMAX = 7000.0
ONSET_LAG = 2  # frames between the spectra an onset compares (21 ms)
HPSS_KERNEL = (9, 31)  # medians over 9 frames (harmonic: steady) and 31 mel bands (percussive: broadband)

MIN_BPM, MAX_BPM, BPM_STEP = 50.0, 260.0, 0.25
PRIOR_BPM = 120.0
FAMILY_SIGMA = 1.5  # octaves: weak prior while choosing the metrical family (2:3 and 3:4 decided by evidence)
OCTAVE_SIGMA = 0.7  # octaves: the prior that picks half, same or double tempo
MAX_LAG_SECONDS = 12.0  # four bars at 80 bpm: enough for the six-period (triple metre) evidence
TIGHTNESS = 1600.0  # how strictly beats keep the tempo: a song's tempo is known well by now
ENVELOPE_LATENCY = 1  # frames the envelope's peak trails an onset (10 ms, measured on noise-burst clicks)


def onset_envelopes(samples: np.ndarray, sr: int) -> np.ndarray:
    """(2, H) onset strength at sr / BEAT_HOP frames per second: of the whole mix and of its
    percussive part. Frame h describes time h * BEAT_HOP / sr (centred analysis)."""
    mel = mel_power(samples, sr, ENVELOPE_FFT, BEAT_HOP, ENVELOPE_MELS, ENVELOPE_FMAX)
    percussive = percussive_part(mel)
    return np.stack([_onset_strength(mel, sr), _onset_strength(percussive, sr)]).astype(np.float32)


def percussive_part(power: np.ndarray, kernel: tuple[int, int] = HPSS_KERNEL) -> np.ndarray:
    """Median-filter harmonic/percussive separation (Fitzgerald 2010), percussive part, with a
    Wiener-like soft mask of power 2: librosa's ``decompose.hpss`` (equal outputs, tested), whose
    module imports scikit-learn on the way to every dance. ``kernel`` = (frames of the harmonic
    median, bins of the percussive one), in librosa's order."""
    harmonic = scipy.ndimage.median_filter(power, size=(1, kernel[0]), mode="reflect")
    percussive = scipy.ndimage.median_filter(power, size=(kernel[1], 1), mode="reflect")
    total = np.maximum(harmonic, percussive)
    silent = total < np.finfo(power.dtype).tiny
    total[silent] = 1.0
    mask = (percussive / total) ** 2
    np.divide(mask, mask + (harmonic / total) ** 2, out=mask, where=~silent)
    mask[silent] = 0.0
    return power * mask


def _onset_strength(mel_power: np.ndarray, sr: int) -> np.ndarray:
    log_mel = power_to_db(mel_power)  # fixed floor: blocks agree
    return onset_strength(log_mel, ENVELOPE_FFT, BEAT_HOP, lag=ONSET_LAG)


def envelope_autocorrelation(envelope: np.ndarray, fps: float) -> np.ndarray:
    """Normalised autocorrelation (lag 0 = 1) of the envelope's rises above its 1 s local mean."""
    envelope = np.asarray(envelope, dtype=np.float64)
    rises = np.maximum(envelope - scipy.ndimage.uniform_filter1d(envelope, max(1, int(fps))), 0.0)
    max_lag = min(int(MAX_LAG_SECONDS * fps), len(rises) - 1)
    spectrum = np.fft.rfft(rises, 2 * len(rises))
    correlation = np.fft.irfft(spectrum * np.conj(spectrum))[: max_lag + 1]
    correlation /= len(rises) - np.arange(max_lag + 1)  # unbiased: long lags are not penalised
    return correlation / correlation[0] if correlation[0] > 0 else np.zeros_like(correlation)


def metrical_salience(autocorrelation: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """(bpms, salience): each beat period credited with the autocorrelation at 1, 2 and 4 periods,
    or at 1, 3 and 6 for triple metre, whichever is larger."""
    bpms = np.arange(MIN_BPM, MAX_BPM + BPM_STEP / 2, BPM_STEP)
    period = 60.0 * fps / bpms

    def at(multiple: int) -> np.ndarray:
        lags = np.arange(len(autocorrelation))
        return np.interp(multiple * period, lags, autocorrelation, right=0.0)

    return bpms, at(1) + np.maximum(at(2) + at(4), at(3) + at(6))


def _log_prior(bpms: np.ndarray, sigma_octaves: float) -> np.ndarray:
    return np.exp(-0.5 * (np.log2(bpms / PRIOR_BPM) / sigma_octaves) ** 2)


def estimate_tempo(envelope: np.ndarray, fps: float) -> float:
    """Global tempo in bpm (0 when the envelope is flat): metrical family first, then octave."""
    correlation = envelope_autocorrelation(envelope, fps)
    if not correlation.any():
        return 0.0
    bpms, salience = metrical_salience(correlation, fps)
    family = bpms[np.argmax(salience * _log_prior(bpms, FAMILY_SIGMA))]
    best, best_score = 0.0, -np.inf
    for candidate in (family / 2, family, family * 2):
        near = np.flatnonzero(np.abs(bpms - candidate) <= 1.0)  # the local peak of the salience
        if len(near) == 0:
            continue
        peak = near[np.argmax(salience[near])]
        score = salience[peak] * _log_prior(bpms[peak:peak + 1], OCTAVE_SIGMA)[0]
        if score > best_score:
            best, best_score = float(bpms[peak]), score
    return best


def estimate_beats(envelopes: np.ndarray, fps: float) -> tuple[float, np.ndarray]:
    """(tempo in bpm, beat times in seconds) from :func:`onset_envelopes`' (2, H) output."""
    full, percussive = (np.asarray(e, dtype=np.float64) for e in envelopes)
    if not full.any():
        return 0.0, np.zeros(0)
    tempo = estimate_tempo(full, fps)
    if tempo <= 0:
        return 0.0, np.zeros(0)
    return tempo, _beats_on_the_beat(full, percussive, fps, tempo)


def beats_at_tempo(envelopes: np.ndarray, fps: float, bpm: float) -> np.ndarray:
    """Beat times in seconds exactly 60 / ``bpm`` apart (a tempo the user knows), phased onto the
    song's onsets: the tracker runs at that tempo instead of an estimated one, and the grid goes
    through its beats (circular mean of their phase), from its first beat to its last. Why a
    grid and not the tracked beats themselves: a user who gives the tempo wants it kept to the
    sample, not bent by the tracker towards the onsets it hears."""
    full, percussive = (np.asarray(e, dtype=np.float64) for e in envelopes)
    period = 60.0 / bpm
    tracked = _beats_on_the_beat(full, percussive, fps, bpm) if full.any() else np.zeros(0)
    if len(tracked) == 0:  # nothing to phase on: the grid starts with the song
        return np.arange(0.0, len(full) / fps, period)
    phase = np.angle(np.exp(2j * np.pi * tracked / period).mean()) / (2 * np.pi) * period
    first, last = np.round((tracked[[0, -1]] - phase) / period).astype(int)
    grid = phase + np.arange(first, last + 1) * period
    return grid[(grid >= 0) & (grid <= len(full) / fps)]


def _beats_on_the_beat(full: np.ndarray, percussive: np.ndarray, fps: float, bpm: float) -> np.ndarray:
    """Beat times tracked at ``bpm``, moved by half a beat when the percussion sits between them."""
    frames = track_beats(full, fps, bpm).astype(np.float64)
    if len(frames) >= 2:
        between = frames + np.append(np.diff(frames), np.median(np.diff(frames))) / 2
        between = between[between < len(full) - 1]
        if _mean_at(percussive, between) > _mean_at(percussive, frames):
            frames = between  # the grid sat on the off-beats
    return np.maximum(frames - ENVELOPE_LATENCY, 0) / fps


def track_beats(envelope: np.ndarray, fps: float, bpm: float, tightness: float = TIGHTNESS) -> np.ndarray:
    """Beat frames at a known tempo by dynamic programming (Ellis 2007): each beat is credited with
    the onset strength near it and charged for how far its distance to the previous beat strays
    from the beat period, in log time. The same programme as librosa's ``beat_track`` (its results
    match frame for frame before the trim, tested), written in numpy: librosa's beat module compiles
    a numba kernel in every fresh process (3.5 s here), which dominated a short song's whole run.
    The beats of a fade-in and a fade-out are dropped (:func:`_fade_threshold`)."""
    envelope = np.asarray(envelope, dtype=np.float64)
    if len(envelope) < 2 or not envelope.any() or bpm <= 0:
        return np.zeros(0, dtype=int)
    period = float(np.round(fps * 60.0 / bpm))
    local = _beat_local_score(envelope / (envelope.std(ddof=1) + np.finfo(np.float64).tiny), period)
    backlink, cumulative = _best_predecessors(local, period, tightness)
    beats = np.zeros(len(local), dtype=bool)
    beat = _last_beat(cumulative)
    while beat >= 0:
        beats[beat] = True
        beat = backlink[beat]
    return np.flatnonzero(_trim_weak_ends(local, beats, _fade_threshold(local, beats)))


def _beat_local_score(envelope: np.ndarray, period: float) -> np.ndarray:
    """Onset strength smoothed by a Gaussian of width period / 32, spanning one period each side."""
    offsets = np.arange(-period, period + 1)
    window = np.exp(-0.5 * (offsets * 32.0 / period) ** 2)
    envelope = np.concatenate([[0.0], envelope[1:]])  # librosa's sum never reaches frame 0; match it
    return np.convolve(envelope, window, mode="same") if len(envelope) >= len(window) else \
        np.convolve(envelope, window, mode="full")[len(window) // 2: len(window) // 2 + len(envelope)]


def _best_predecessors(local: np.ndarray, period: float, tightness: float) -> tuple[np.ndarray, np.ndarray]:
    """For every frame: the best previous beat (half to two periods back; -1: none) and the best
    cumulative score of a beat sequence ending there. Leading frames weaker than 1 % of the
    strongest cannot link back, so the sequence starts where the music does."""
    nearest, farthest = int(np.round(period / 2)), int(2 * period)
    gaps = np.arange(nearest, farthest + 1)  # ties go to the nearest predecessor, as librosa's loop does
    penalty = tightness * (np.log(gaps) - np.log(period)) ** 2
    backlink = np.full(len(local), -1, dtype=np.int64)
    cumulative = np.empty(len(local))
    started, threshold = False, 0.01 * local.max()
    for i, score in enumerate(local.tolist()):
        best = -1
        if i >= nearest:
            reach = min(i, farthest) - nearest + 1  # gaps that stay inside the song
            candidates = cumulative[i - nearest - reach + 1: i - nearest + 1][::-1] - penalty[:reach]
            pick = int(candidates.argmax())
            best, score = i - nearest - pick, score + candidates[pick]
        cumulative[i] = score
        if started or local[i] >= threshold:
            backlink[i], started = best, True
    return backlink, cumulative


def _last_beat(cumulative: np.ndarray) -> int:
    """The last local maximum of the cumulative score that reaches half the median local maximum."""
    peaks = np.zeros(len(cumulative), dtype=bool)
    peaks[1:-1] = (cumulative[1:-1] > cumulative[:-2]) & (cumulative[1:-1] >= cumulative[2:])
    peaks[-1] = cumulative[-1] > cumulative[-2]
    if not peaks.any():
        return len(cumulative) - 1
    qualified = np.flatnonzero(peaks & (cumulative >= 0.5 * np.median(cumulative[peaks])))
    return int(qualified[-1]) if len(qualified) else len(cumulative) - 1


def _fade_threshold(local: np.ndarray, beats: np.ndarray) -> float:
    """Half the RMS of the beats' (Hann-smoothed) local scores: weaker leading and trailing frames
    are a fade-in or a fade-out, not beats.

    librosa's rule, but with the smoothing window summing to one: librosa's sums to two, so its
    threshold is the whole RMS, and a song whose last minutes are quieter than its first lost every
    beat there (LMMS's EsoXLB-CPU heard none after 146 of its 236 s; beat F over the 25 LMMS songs
    0.731 -> 0.751, none lower: docs/results.md, "Beat tracking")."""
    window = np.hanning(5) / np.hanning(5).sum()
    smoothed = np.convolve(local[beats], window)[2:]  # librosa keeps the two trailing values too
    return 0.5 * np.sqrt(np.mean(smoothed ** 2)) if len(smoothed) else 0.0


def _trim_weak_ends(local: np.ndarray, beats: np.ndarray, threshold: float) -> np.ndarray:
    """The beats without those in the leading and trailing frames whose local score is at most ``threshold``."""
    trimmed = beats.copy()
    weak = local <= threshold
    lead = np.argmin(weak) if not weak.all() else len(local)
    trimmed[:lead] = False
    tail = len(local) - np.argmin(weak[::-1]) if not weak.all() else 0
    trimmed[tail:] = False
    return trimmed


def _mean_at(envelope: np.ndarray, frames: np.ndarray) -> float:
    return float(np.interp(frames, np.arange(len(envelope)), envelope).mean()) if len(frames) else 0.0


def beat_frames_at(beat_times: np.ndarray, fps: float, num_frames: int, keep: bool = False) -> np.ndarray:
    """Beat times mapped to the nearest of ``num_frames`` frames at ``fps`` (unique, sorted), or
    with ``keep`` the mask of the times that land on one of those frames."""
    frames = np.round(np.asarray(beat_times) * fps).astype(int)
    inside = (frames >= 0) & (frames < num_frames)
    return inside if keep else np.unique(frames[inside])


def onset_peaks(onset_envelope: np.ndarray, fps: float) -> np.ndarray:
    """Frame indices of onset peaks: librosa.onset.onset_detect's rule (tested equal), on the
    envelope scaled to [0, 1]: a frame is a peak if it is the maximum from 30 ms before it to
    itself and at least 0.07 above the mean from 100 ms before to 100 ms after."""
    envelope = np.asarray(onset_envelope, dtype=np.float64)
    if not envelope.any() or not np.isfinite(envelope).all():
        return np.zeros(0, dtype=int)
    envelope = envelope - envelope.min()
    envelope /= envelope.max() + np.finfo(envelope.dtype).tiny
    frames = lambda seconds: math.ceil(seconds * fps * 512 // 512)  # noqa: E731  (librosa's seconds * sr // hop, sr = fps * hop)
    return pick_peaks(envelope, frames(0.03), frames(0.0) + 1, frames(0.10), frames(0.10) + 1, 0.07, frames(0.03))


def pick_peaks(x: np.ndarray, pre_max: int, post_max: int, pre_avg: int, post_avg: int, delta: float,
               wait: int) -> np.ndarray:
    """Frames n with x[n] = max(x[n - pre_max : n + post_max]) and x[n] >= mean(x[n - pre_avg :
    n + post_avg]) + delta (windows cut at the ends), at least ``wait`` frames after the previous
    peak (librosa.util.peak_pick). Every frame is tested at once; only the spacing is sequential."""
    count = len(x)
    index = np.arange(count)
    lows, highs = np.maximum(index - pre_max, 0), np.minimum(index + post_max, count)
    is_max = np.array([x[n] == x[lo:hi].max() for n, lo, hi in zip(index, lows, highs)]) if count else np.zeros(0, bool)
    sums = np.concatenate([[0.0], np.cumsum(x)])
    lows, highs = np.maximum(index - pre_avg, 0), np.minimum(index + post_avg, count)
    above = x >= (sums[highs] - sums[lows]) / (highs - lows) + delta
    if count:  # librosa tests the first frame against the windows after it alone
        is_max[0] = x[0] >= x[: min(post_max, count)].max()
        above[0] = x[0] >= x[: min(post_avg, count)].mean() + delta
    peaks, next_allowed = [], 0
    for n in np.flatnonzero(is_max & above):
        if n >= next_allowed:
            peaks.append(n)
            next_allowed = n + wait + 1
    return np.asarray(peaks, dtype=int)
