"""Tempo and beats from a 30 fps onset envelope (a song's worth fits in memory easily)."""

from __future__ import annotations

import librosa
import numpy as np

START_BPM = 120.0  # prior centre for the tempo estimate, as in the field's reference code
TIGHTNESS = 100.0  # how strictly beats keep the estimated tempo (librosa's default, EDGE's choice)
TEMPO_CHUNK_SECONDS = 120.0  # tempogram computed per chunk: memory stays flat for hour-long songs


def estimate_tempo(onset_envelope: np.ndarray, fps: float) -> float:
    """Global tempo (bpm) from the mean autocorrelation tempogram, accumulated chunk by chunk."""
    hop_length = 512
    sr = fps * hop_length
    chunk = int(TEMPO_CHUNK_SECONDS * fps)
    total, count = None, 0
    for start in range(0, len(onset_envelope), chunk):
        piece = onset_envelope[start: start + chunk]
        if len(piece) < fps * 2 and count:
            break  # a short remainder adds nothing but edge effects
        tempogram = librosa.feature.tempogram(onset_envelope=piece, sr=sr, hop_length=hop_length)
        summed = tempogram.sum(axis=1)
        total = summed if total is None else total + summed
        count += tempogram.shape[1]
    mean_tempogram = (total / max(count, 1))[:, None]
    tempo = librosa.feature.tempo(tg=mean_tempogram, sr=sr, hop_length=hop_length, start_bpm=START_BPM)
    return float(np.atleast_1d(tempo)[0])


def estimate_beats(onset_envelope: np.ndarray, fps: float) -> tuple[float, np.ndarray]:
    """(tempo in bpm, beat frame indices) by dynamic-programming beat tracking (Ellis 2007)."""
    onset_envelope = np.asarray(onset_envelope, dtype=np.float64)
    if not onset_envelope.any():
        return 0.0, np.zeros(0, dtype=int)
    tempo = estimate_tempo(onset_envelope, fps)
    if tempo <= 0:
        return 0.0, np.zeros(0, dtype=int)
    _, beats = librosa.beat.beat_track(onset_envelope=onset_envelope, sr=fps * 512, hop_length=512, bpm=tempo,
                                       tightness=TIGHTNESS, units="frames")
    return tempo, np.asarray(beats, dtype=int)


def onset_peaks(onset_envelope: np.ndarray, fps: float) -> np.ndarray:
    """Frame indices of onset peaks (librosa's peak picking on the normalised envelope)."""
    if not np.asarray(onset_envelope).any():
        return np.zeros(0, dtype=int)
    peaks = librosa.onset.onset_detect(onset_envelope=np.asarray(onset_envelope, dtype=np.float64),
                                       sr=fps * 512, hop_length=512, units="frames")
    return np.asarray(peaks, dtype=int)
