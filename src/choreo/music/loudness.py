"""Loudness at the motion frame rate, and the span of a song where there is music to dance to.

Many songs open with a moment of silence or end on seconds of it (a reverb dying away, a
renderer's padding): 15 of the 25 LMMS demo songs end on a second or more of it. A dancer
waits through the first and comes to rest in the second (choreo.finishing.rest); this module
finds them. Frame t's loudness is the RMS of samples [t * hop, (t + 1) * hop) in dBFS, so a song of
n samples has n // hop frames, like its features.
"""

from __future__ import annotations

import numpy as np

from .features import FPS, HOP_LENGTH

FLOOR_DB = -120.0  # digital silence reads as this, not minus infinity
QUIET_BELOW_PEAK_DB = 40.0  # quieter than the song's loud parts by this much: no music to dance to
LOUD_PERCENTILE = 95  # the song's loud level: louder than 95 % of its frames (a single click is not it)
SMOOTHING_SECONDS = 0.5  # loudness is taken as the loudest frame this close, so a rest between notes is not silence


def frame_loudness(samples: np.ndarray, hop: int = HOP_LENGTH) -> np.ndarray:
    """(len(samples) // hop,) float32 RMS loudness in dBFS of each hop of ``samples``."""
    frames = len(samples) // hop
    power = np.square(np.asarray(samples[: frames * hop], np.float64)).reshape(frames, hop).mean(axis=1)
    return np.maximum(10.0 * np.log10(np.maximum(power, 1e-30)), FLOOR_DB).astype(np.float32)


class LoudnessStream:
    """:func:`frame_loudness` of a signal pushed block by block (a sink beside the other analyses
    of one decode, as choreo.music.mel.LogMelStream); equal to the whole-signal computation."""

    def __init__(self, hop: int = HOP_LENGTH):
        self.hop, self.pending, self.out = hop, np.zeros(0, np.float32), []

    def push(self, block: np.ndarray) -> None:
        self.pending = np.concatenate([self.pending, np.asarray(block, np.float32)])
        whole = len(self.pending) // self.hop * self.hop
        if whole:
            self.out.append(frame_loudness(self.pending[:whole], self.hop))
            self.pending = self.pending[whole:]

    def finish(self) -> np.ndarray:
        return np.concatenate(self.out) if self.out else np.zeros(0, np.float32)


def audible_span(loudness: np.ndarray, fps: float = FPS) -> tuple[int, int]:
    """Frames [first, stop) from the first to the last moment with music to dance to: louder than
    the song's loud level less QUIET_BELOW_PEAK_DB, loudness taken over SMOOTHING_SECONDS. The whole
    song when nothing is that loud (a quiet song throughout is still music)."""
    if len(loudness) == 0:
        return 0, 0
    from scipy.ndimage import maximum_filter1d

    smoothed = maximum_filter1d(np.asarray(loudness, np.float64), max(1, round(SMOOTHING_SECONDS * fps)))
    loud = np.flatnonzero(smoothed > np.percentile(loudness, LOUD_PERCENTILE) - QUIET_BELOW_PEAK_DB)
    if len(loud) == 0:
        return 0, len(loudness)
    return int(loud[0]), int(loud[-1]) + 1
