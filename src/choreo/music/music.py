"""`Music`: a song as the generators and metrics see it, features aligned with motion frames."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Iterator

import numpy as np

from ..errors import ParameterError
from .audio import check_usable, iter_audio_blocks
from . import madmom_tracker  # light: madmom itself loads only when asked for
from .beat_source import BeatSource
from .beats import BEAT_HOP, onset_envelopes
from .loudness import LoudnessStream, audible_span, frame_loudness
from .mel import LogMelStream, fit_length, log_mel as log_mel_of
from .features import BEAT_COLUMN, FEATURE_DIM, FPS, HOP_LENGTH, SAMPLE_RATE, assemble_features, frame_features, stream_features


@dataclass(frozen=True, eq=False)
class Music:
    """Features of a song (or an excerpt) at ``fps``.

    Attributes:
        path: the audio file, or None for music built from an array.
        duration: seconds of audio covered.
        fps: feature frames per second (30).
        features: (T, 35) float32, T = floor(duration * fps); see choreo.music.features for columns.
        beat_times: (B,) seconds from the start of the excerpt (at the tracker's 96 fps precision;
            the features' beat column marks the nearest 30 fps frames).
        tempo: global tempo in beats per minute: estimated, or the user's (0 when no beat was found).
        start: seconds into ``path`` at which frame 0 is (an excerpt's start).
        log_mel: (T, 96) log-mel frames (choreo.music.mel), when asked for at analysis
            (``log_mel=True``: the same decode feeds both); None otherwise.
        timbre: whether the features' MFCC and chroma columns were computed (``timbre=False`` at
            analysis leaves them at zero: commands and backends that read only the rhythm and
            the log-mel skip the constant-Q transform).
        beat_source: where the beats come from (BeatSource.label): "tracked", "bpm N" or the
            name of the beats file the user gave.
        loudness: (T,) dBFS per frame (choreo.music.loudness), or None for music rebuilt from
            stored features (then the whole song counts as audible).
    """

    path: Path | None
    duration: float
    fps: float
    features: np.ndarray
    beat_times: np.ndarray
    tempo: float
    start: float = 0.0  # seconds into ``path`` at which frame 0 is
    log_mel: np.ndarray | None = None  # (T, 96), for backends that listen to the spectrum
    timbre: bool = True  # False: MFCC and chroma columns are zeros (analysed for rhythm only)
    beat_source: str = "tracked"
    loudness: np.ndarray | None = None  # (T,) dBFS

    @property
    def num_frames(self) -> int:
        return len(self.features)

    @property
    def audible(self) -> tuple[int, int]:
        """Frames [first, stop) from the first to the last moment with music to dance to."""
        return (0, self.num_frames) if self.loudness is None else audible_span(self.loudness, self.fps)

    @property
    def beat_frames(self) -> np.ndarray:
        """Frame indices of the beats (the frames whose beat one-hot is set, the beat times rounded)."""
        return np.flatnonzero(self.features[:, BEAT_COLUMN] > 0.5)

    def slice_frames(self, start: int, stop: int) -> np.ndarray:
        """(stop - start, 35) features of frames [start, stop), zero-padded past the end."""
        if start < 0 or stop < start:
            raise ParameterError(f"bad frame range {start}:{stop}")
        window = self.features[start:stop]
        if len(window) < stop - start:
            pad = np.zeros((stop - start - len(window), FEATURE_DIM), np.float32)
            window = np.concatenate([window, pad])
        return window

    @classmethod
    def from_file(cls, path: str | os.PathLike, *, start: float | None = None, end: float | None = None,
                  progress: Callable[[float, float], None] | None = None, log_mel: bool = False,
                  timbre: bool = True, beats: BeatSource = BeatSource()) -> "Music":
        """Decode and featurise ``path`` (or its [start, end] seconds) in constant memory.

        ``progress(done_seconds, total_seconds)`` is called as blocks are processed. ``log_mel``
        also keeps the log-mel spectrogram, from the same decode; ``timbre=False`` skips the MFCC
        and chroma columns (see the class); ``beats``: the tracker's (default) or the user's, in
        the song's time.
        """
        path = Path(path)
        if start is not None and start < 0:
            raise ParameterError(f"start must be >= 0 seconds, got {start}")
        if end is not None and start is not None and end <= start:
            raise ParameterError(f"end ({end}) must come after start ({start})")
        report = None
        if progress is not None:
            from .audio import audio_duration

            total = (end if end is not None else audio_duration(path)) - (start or 0.0)
            report = lambda done: progress(min(done, total), total)  # noqa: E731
        blocks = iter_audio_blocks(path, SAMPLE_RATE, start, end)
        mel, loudness = LogMelStream() if log_mel else None, LoudnessStream()
        blocks = _also_into(blocks, loudness)
        if mel is not None:
            blocks = _also_into(blocks, mel)
        heard = beats.excerpt(start or 0.0, end).heard(lambda: madmom_tracker.track_file(path, start, end))
        features, tempo, beat_times = stream_features(blocks, str(path), progress=report, timbre=timbre, beats=heard)
        return cls(path=path, duration=_duration(features), fps=float(FPS), features=features, beat_times=beat_times,
                   tempo=tempo, start=start or 0.0,
                   log_mel=None if mel is None else fit_length(mel.finish(), len(features)), timbre=timbre,
                   beat_source=beats.label, loudness=loudness.finish()[: len(features)])

    @classmethod
    def from_array(cls, samples: np.ndarray, sr: int, log_mel: bool = False, timbre: bool = True,
                   beats: BeatSource = BeatSource()) -> "Music":
        """Featurise an in-memory mono signal (tests, synthesised audio); options as in from_file."""
        samples = np.asarray(samples, dtype=np.float32)
        if samples.ndim != 1:
            raise ParameterError("from_array expects a mono signal of shape (N,)")
        if sr != SAMPLE_RATE:
            import soxr

            samples = soxr.resample(samples, sr, SAMPLE_RATE).astype(np.float32)
        check_usable(samples, SAMPLE_RATE, "audio array")
        num_frames = len(samples) // HOP_LENGTH
        per_frame = frame_features(samples, timbre=timbre)[:num_frames]
        envelopes = onset_envelopes(samples, SAMPLE_RATE)[:, : len(samples) // BEAT_HOP]
        beats = beats.heard(lambda: madmom_tracker.track_array(samples, SAMPLE_RATE))
        features, tempo, beat_times = assemble_features(per_frame, FPS, envelopes, SAMPLE_RATE / BEAT_HOP, beats)
        return cls(path=None, duration=_duration(features), fps=float(FPS), features=features,
                   beat_times=beat_times, tempo=tempo,
                   log_mel=log_mel_of(samples, len(features)) if log_mel else None, timbre=timbre,
                   beat_source=beats.label, loudness=frame_loudness(samples)[: len(features)])


def _also_into(blocks: Iterable[np.ndarray], sink) -> Iterator[np.ndarray]:
    """The blocks, each also pushed into ``sink``: one decode for several analyses."""
    for block in blocks:
        sink.push(block)
        yield block


def _duration(features: np.ndarray) -> float:
    return len(features) / FPS
