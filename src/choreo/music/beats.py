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
"""

from __future__ import annotations

import librosa
import numpy as np
import scipy.ndimage

BEAT_HOP = 160  # samples at 15360 Hz: 96 envelope frames per second
ENVELOPE_MELS = 64
ENVELOPE_FFT = 1024
ENVELOPE_FMAX = 7000.0
ONSET_LAG = 2  # frames between the spectra an onset compares (21 ms)
HPSS_KERNEL = (9, 31)  # (mel bands, frames): percussive = broadband and short

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
    mel = librosa.feature.melspectrogram(y=samples, sr=sr, n_fft=ENVELOPE_FFT, hop_length=BEAT_HOP,
                                         n_mels=ENVELOPE_MELS, fmax=ENVELOPE_FMAX)
    _, percussive = librosa.decompose.hpss(mel, kernel_size=HPSS_KERNEL)
    return np.stack([_onset_strength(mel, sr), _onset_strength(percussive, sr)]).astype(np.float32)


def _onset_strength(mel_power: np.ndarray, sr: int) -> np.ndarray:
    log_mel = librosa.power_to_db(mel_power, ref=1.0, amin=1e-10, top_db=None)  # fixed floor: blocks agree
    return librosa.onset.onset_strength(S=log_mel, sr=sr, hop_length=BEAT_HOP, n_fft=ENVELOPE_FFT, lag=ONSET_LAG)


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
    _, frames = librosa.beat.beat_track(onset_envelope=full, sr=fps * BEAT_HOP, hop_length=BEAT_HOP, bpm=tempo,
                                        tightness=TIGHTNESS, units="frames")
    frames = np.asarray(frames, dtype=np.float64)
    if len(frames) >= 2:
        between = frames + np.append(np.diff(frames), np.median(np.diff(frames))) / 2
        between = between[between < len(full) - 1]
        if _mean_at(percussive, between) > _mean_at(percussive, frames):
            frames = between  # the grid sat on the off-beats
    return tempo, np.maximum(frames - ENVELOPE_LATENCY, 0) / fps


def _mean_at(envelope: np.ndarray, frames: np.ndarray) -> float:
    return float(np.interp(frames, np.arange(len(envelope)), envelope).mean()) if len(frames) else 0.0


def beat_frames_at(beat_times: np.ndarray, fps: float, num_frames: int, keep: bool = False) -> np.ndarray:
    """Beat times mapped to the nearest of ``num_frames`` frames at ``fps`` (unique, sorted), or
    with ``keep`` the mask of the times that land on one of those frames."""
    frames = np.round(np.asarray(beat_times) * fps).astype(int)
    inside = (frames >= 0) & (frames < num_frames)
    return inside if keep else np.unique(frames[inside])


def onset_peaks(onset_envelope: np.ndarray, fps: float) -> np.ndarray:
    """Frame indices of onset peaks (librosa's peak picking on the normalised envelope)."""
    if not np.asarray(onset_envelope).any():
        return np.zeros(0, dtype=int)
    peaks = librosa.onset.onset_detect(onset_envelope=np.asarray(onset_envelope, dtype=np.float64),
                                       sr=fps * 512, hop_length=512, units="frames")
    return np.asarray(peaks, dtype=int)
