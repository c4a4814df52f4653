"""Rhythm a model can use: where in the beat each frame is, and how fast the beats come.

The 35-d features mark beats with a one-frame spike, which a network sees on one frame in
fifteen. Beat phase as (sin, cos) is smooth and tells every frame how far it is from the next
beat; log tempo says how fast to move. Both are derived from the beat column alone, on whatever
excerpt is given (edges extrapolate with the median beat period), so training windows, scoring
windows and whole songs are treated alike.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .features import BEAT_COLUMN, FEATURE_DIM, PEAK_COLUMN

RHYTHM_NAMES = ("beat_phase_sin", "beat_phase_cos", "log2_tempo_over_120")
RHYTHM_DIM = len(RHYTHM_NAMES)
REFERENCE_BPM = 120.0


def beat_phase(beat_frames: np.ndarray, num_frames: int) -> np.ndarray | None:
    """(T,) phase in [0, 1) of each frame within its beat, or None with fewer than two beats.

    Linear between consecutive beats; before the first and after the last beat the median
    beat period continues the grid.
    """
    beats = np.unique(np.asarray(beat_frames, dtype=np.float64))
    if len(beats) < 2:
        return None
    period = float(np.median(np.diff(beats)))
    frames = np.arange(num_frames, dtype=np.float64)
    phase = np.interp(frames, beats, np.arange(len(beats), dtype=np.float64)) % 1.0
    outside = (frames < beats[0]) | (frames > beats[-1])
    phase[outside] = ((frames[outside] - beats[0]) / period) % 1.0
    return phase


def rhythm_channels(features: np.ndarray, fps: float = 30.0) -> np.ndarray:
    """(T, 3) beat phase (sin, cos) and log2(tempo / 120) from the features' beat column.

    Zeros where the excerpt has fewer than two beats (no rhythm to speak of).
    """
    features = np.asarray(features)
    if features.ndim != 2 or features.shape[1] != FEATURE_DIM:
        raise ParameterError(f"music features must have shape (T, {FEATURE_DIM}), got {features.shape}")
    channels = np.zeros((len(features), RHYTHM_DIM), np.float32)
    beats = np.flatnonzero(features[:, BEAT_COLUMN] > 0.5)
    phase = beat_phase(beats, len(features))
    if phase is None:
        return channels
    channels[:, 0] = np.sin(2 * np.pi * phase)
    channels[:, 1] = np.cos(2 * np.pi * phase)
    bpm = 60.0 * fps / float(np.median(np.diff(beats)))
    channels[:, 2] = np.log2(bpm / REFERENCE_BPM)
    return channels


def stretch_features(features: np.ndarray, factor: float) -> np.ndarray:
    """Features of the same music played ``factor`` times as fast, frame i reading source frame
    i * factor (as :func:`choreo.motion.augment.stretched` reads motion).

    Continuous columns (onset strength, MFCC, chroma) are interpolated: a time-stretch keeps
    timbre and pitch, so a frame's values move in time but do not change. The onset-peak and
    beat spikes move to the nearest frame of their new time, so beats stay on beats.
    """
    features = np.asarray(features, dtype=np.float32)
    if not 0.25 <= factor <= 4.0:
        raise ParameterError(f"stretch factor must be within [0.25, 4], got {factor}")
    num_frames = int(np.floor((len(features) - 1) / factor)) + 1
    source = np.arange(num_frames) * factor
    out = np.empty((num_frames, features.shape[1]), np.float32)
    frames = np.arange(len(features))
    for column in range(features.shape[1]):
        out[:, column] = np.interp(source, frames, features[:, column])
    for column in (PEAK_COLUMN, BEAT_COLUMN):
        out[:, column] = 0.0
        spikes = np.round(np.flatnonzero(features[:, column] > 0.5) / factor).astype(int)
        out[spikes[spikes < num_frames], column] = 1.0
    return out
