"""Beat metrics: BeatAlign (Bailando/DGSDP) and ChoreoGraph's two beat distances.

Motion beats (choreo.motion.beats, re-exported here) are the moments the dancer nearly stops.
All times here are in frames of the motion's own frame rate.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.ndimage import gaussian_filter1d

from ..motion.beats import SPEED_SMOOTHING_SIGMA, mean_joint_speed, motion_beats  # noqa: F401 (re-exported)

BEAT_ALIGN_SIGMA = 3.0  # frames: 100 ms at 30 fps (50 ms at 60 fps)
METRICAL_RATIOS = (0.5, 1.0, 2.0)  # the same pulse, counted every other beat or twice per beat
LOCK_TOLERANCE = 0.04  # relative tempo difference still counted as the same (MIREX allows 8 %)
BEAT_TRAIN_SIGMA = 1.0  # frames


class MetricWarning(UserWarning):
    """A metric was computed on degenerate input and returned its defined fallback value."""


def motion_beat_train(joint_positions: np.ndarray) -> np.ndarray:
    """(T,) the dance's motion beats as narrow bumps (so a beat a frame off still correlates)."""
    train = np.zeros(len(joint_positions))
    train[motion_beats(joint_positions)] = 1.0
    return gaussian_filter1d(train, BEAT_TRAIN_SIGMA)


def beat_autocorrelation(joint_positions: np.ndarray, max_lag: int) -> np.ndarray:
    """(max_lag + 1,) normalised autocorrelation of a dance's motion-beat train (zeros without
    beats): computed once, it can be read at any tempo with ``salience_at``."""
    train = motion_beat_train(joint_positions)
    train = train - train.mean()
    if not train.any():
        return np.zeros(max_lag + 1)
    spectrum = np.fft.rfft(train, 2 * len(train))
    autocorrelation = np.fft.irfft(spectrum * np.conj(spectrum))[: max_lag + 1]
    return autocorrelation / autocorrelation[0]


def salience_at(autocorrelation: np.ndarray, fps: float, bpm: float) -> float:
    """A ``beat_autocorrelation`` read at one or two beat periods of ``bpm`` (the larger, lags
    interpolated); 0 where two periods lie past its last lag."""
    period = 60.0 * fps / bpm if bpm > 0 else np.inf
    if 2 * period > len(autocorrelation) - 1:
        return 0.0
    lags = np.arange(len(autocorrelation))
    return float(max(np.interp(m * period, lags, autocorrelation) for m in (1, 2)))


def tempo_salience(joint_positions: np.ndarray, fps: float, bpm: float) -> float:
    """How strongly a dance's motion beats recur at a tempo: the normalised autocorrelation of
    its motion-beat train at one or two beat periods of ``bpm``. 1 for beats exactly that far
    apart, near 0 for beats unrelated to it, 0 for a dance too short to show two periods."""
    if bpm <= 0 or len(joint_positions) <= 4 * 60.0 * fps / bpm:
        return 0.0
    return salience_at(beat_autocorrelation(joint_positions, int(2 * 60.0 * fps / bpm) + 1), fps, bpm)


def same_pulse(bpm: float, other_bpm: float, tolerance: float = LOCK_TOLERANCE) -> bool:
    """Whether two tempi are the same pulse: equal, half or double within ``tolerance``."""
    return other_bpm > 0 and any(abs(bpm / (ratio * other_bpm) - 1.0) <= tolerance for ratio in METRICAL_RATIOS)


def _nearest_distances(queries: np.ndarray, references: np.ndarray) -> np.ndarray:
    """|q - nearest reference| for every query (both sorted or not), vectorised."""
    references = np.sort(np.asarray(references, dtype=np.float64))
    queries = np.asarray(queries, dtype=np.float64)
    right = np.clip(np.searchsorted(references, queries), 0, len(references) - 1)
    left = np.clip(right - 1, 0, len(references) - 1)
    return np.minimum(np.abs(queries - references[left]), np.abs(queries - references[right]))


def beat_align_score(music_beats: np.ndarray, dance_beats: np.ndarray, sigma: float = BEAT_ALIGN_SIGMA) -> float:
    """Mean over MUSIC beats of exp(-d^2 / (2 sigma^2)), d = frames to the nearest motion beat.

    No music beat or no motion beat: 0.0 with a MetricWarning (nothing can be aligned).
    """
    if len(music_beats) == 0 or len(dance_beats) == 0:
        warnings.warn("BeatAlign: no music beats or no motion beats; scoring 0", MetricWarning, stacklevel=2)
        return 0.0
    distances = _nearest_distances(music_beats, dance_beats)
    return float(np.mean(np.exp(-(distances**2) / (2 * sigma**2))))


def beat_distances(music_beats: np.ndarray, dance_beats: np.ndarray) -> tuple[float, float]:
    """ChoreoGraph's (motion->music, music->motion) mean squared distances, in frames^2."""
    if len(music_beats) == 0 or len(dance_beats) == 0:
        warnings.warn("beat distances: no music beats or no motion beats; returning NaN", MetricWarning, stacklevel=2)
        return float("nan"), float("nan")
    motion_to_music = float(np.mean(_nearest_distances(dance_beats, music_beats) ** 2))
    music_to_motion = float(np.mean(_nearest_distances(music_beats, dance_beats) ** 2))
    return motion_to_music, music_to_motion
