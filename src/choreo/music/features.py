"""The 35-d "baseline" music features at 30 fps, computed block by block.

Columns (EDGE's librosa set): onset envelope (1) | MFCC (20) | chroma_cens (12) | onset-peak
one-hot (1) | beat one-hot (1). Audio is resampled to 15360 Hz = 30 x 512 so that one hop of 512
samples is one motion frame at 30 fps; frame t describes the music at time t / 30 s and a song of
d seconds has exactly floor(d * 30) frames.

Per-frame features (onset strength, MFCC, chroma) and the 96 fps onset envelopes the beat tracker
reads (choreo.music.beats) are computed on blocks of audio with enough context on both sides that
the result equals a whole-song computation; peaks and beats are then found on the full-length
envelopes, which are small (one float per frame). Two deliberate
differences from calling librosa on a whole file, both so a frame's value cannot depend on how
much of the song was in view: decibels use a fixed floor (amin 1e-10, no top_db clipping relative
to the loudest frame) and chroma uses tuning 0 instead of a per-file tuning estimate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from ..errors import AudioError
from .audio import MIN_DURATION, SILENCE_RMS
from .chroma import chroma_cens
from .beat_source import BeatSource
from .beats import BEAT_HOP, beat_frames_at, onset_envelopes, onset_peaks
from .spectrum import mel_power, mfcc, onset_strength, power_to_db

FPS = 30
HOP_LENGTH = 512
SAMPLE_RATE = FPS * HOP_LENGTH  # 15360 Hz
N_MFCC = 20
N_CHROMA = 12

FEATURE_NAMES = (
    ("onset_envelope",)
    + tuple(f"mfcc_{i}" for i in range(N_MFCC))
    + tuple(f"chroma_{i}" for i in range(N_CHROMA))
    + ("onset_peak", "beat")
)
FEATURE_DIM = len(FEATURE_NAMES)  # 35
ONSET_COLUMN = 0
MFCC_COLUMNS = slice(1, 1 + N_MFCC)
CHROMA_COLUMNS = slice(1 + N_MFCC, 1 + N_MFCC + N_CHROMA)
PEAK_COLUMN = FEATURE_DIM - 2
BEAT_COLUMN = FEATURE_DIM - 1


@dataclass(frozen=True)
class BlockConfig:
    block_frames: int = 30 * 60  # frames computed per block (60 s of music)
    context_frames: int = 30 * 4  # extra frames of audio on each side; CQT and CENS reach ~1.6 s


def frame_features(samples: np.ndarray, sr: int = SAMPLE_RATE, hop_length: int = HOP_LENGTH,
                   timbre: bool = True) -> np.ndarray:
    """(F, 33) onset envelope, MFCC and chroma_cens for centred frames at every ``hop_length``.

    F = 1 + len(samples) // hop_length, as librosa frames a signal with center=True. Without
    ``timbre`` the MFCC and chroma columns are zeros and the constant-Q transform is skipped (the
    commands that need only the rhythm: render, eval, ChoreoGraph).
    """
    log_mel = power_to_db(mel_power(samples, sr, 2048, hop_length, 128))  # librosa's melspectrogram defaults
    onset = onset_strength(log_mel, 2048, hop_length)
    if not timbre:
        return np.concatenate([onset[:, None], np.zeros((len(onset), N_MFCC + N_CHROMA))], axis=1).astype(np.float32)
    cepstrum = mfcc(log_mel, N_MFCC)
    chroma = chroma_cens(samples, sr, hop_length)
    frames = min(onset.shape[-1], cepstrum.shape[-1], chroma.shape[-1])
    return np.concatenate([onset[None, :frames], cepstrum[:, :frames], chroma[:, :frames]], axis=0).T.astype(np.float32)


class _BlockFeaturizer:
    """Consumes audio blocks of any size; emits per-frame features for finished frame ranges."""

    def __init__(self, config: BlockConfig, hop_length: int, sr: int, timbre: bool = True):
        self.config, self.hop, self.sr, self.timbre = config, hop_length, sr, timbre
        self.buffer = np.zeros(0, np.float32)
        self.buffer_start = 0  # global sample index of buffer[0]
        self.next_frame = 0  # first frame not yet emitted
        self.next_beat_frame = 0  # first 96 fps envelope frame not yet emitted
        self.envelopes: list[np.ndarray] = []
        self.total_samples = 0
        self.sum_squares = 0.0

    def push(self, samples: np.ndarray) -> list[np.ndarray]:
        self.buffer = np.concatenate([self.buffer, samples])
        self.total_samples += len(samples)
        self.sum_squares += float(np.square(samples, dtype=np.float64).sum())
        out = []
        context = self.config.context_frames * self.hop
        while (self.next_frame + self.config.block_frames) * self.hop + context <= self.total_samples:
            out.append(self._emit(self.next_frame + self.config.block_frames))
        return out

    def finish(self) -> list[np.ndarray]:
        last_frame = self.total_samples // self.hop
        return [self._emit(last_frame, final=True)] if last_frame > self.next_frame else []

    def beat_envelopes(self) -> np.ndarray:
        """(2, H) the 96 fps onset envelopes of everything emitted so far."""
        return np.concatenate(self.envelopes, axis=1) if self.envelopes else np.zeros((2, 0), np.float32)

    def _emit_envelopes(self, window: np.ndarray, first_sample: int, stop_sample: int) -> None:
        """Envelope frames whose centres fall before ``stop_sample``, from a window that starts at
        ``first_sample`` (moved up to a multiple of BEAT_HOP, so frames sit where a whole-song
        analysis puts them; the few samples skipped are context, not frames)."""
        aligned = -(-first_sample // BEAT_HOP) * BEAT_HOP
        envelopes = onset_envelopes(window[aligned - first_sample:], self.sr)
        stop = min(-(-stop_sample // BEAT_HOP), aligned // BEAT_HOP + envelopes.shape[1])
        self.envelopes.append(envelopes[:, self.next_beat_frame - aligned // BEAT_HOP: stop - aligned // BEAT_HOP])
        self.next_beat_frame = stop

    def _emit(self, stop_frame: int, final: bool = False) -> np.ndarray:
        """Features of frames [next_frame, stop_frame), computed with context on both sides."""
        context = self.config.context_frames * self.hop
        first_sample = max(0, self.next_frame * self.hop - context)
        last_sample = min(self.total_samples, stop_frame * self.hop + context)
        window = self.buffer[first_sample - self.buffer_start: last_sample - self.buffer_start]
        # Left of the song there is nothing: librosa's zero padding there matches the whole-song case.
        # In the middle, frames are centred on samples inside the window, so context makes them exact.
        features = frame_features(window, self.sr, self.hop, self.timbre)
        self._emit_envelopes(window, first_sample, self.total_samples if final else stop_frame * self.hop)
        offset = (self.next_frame * self.hop - first_sample) // self.hop
        block = features[offset: offset + stop_frame - self.next_frame]
        self.next_frame = stop_frame
        keep_from = max(0, self.next_frame * self.hop - context)
        self.buffer = self.buffer[keep_from - self.buffer_start:]
        self.buffer_start = keep_from
        return block


def stream_features(blocks: Iterable[np.ndarray], name: str, sr: int = SAMPLE_RATE, hop_length: int = HOP_LENGTH,
                    config: BlockConfig = BlockConfig(),
                    progress: Callable[[float], None] | None = None,
                    timbre: bool = True, beats: BeatSource = BeatSource()) -> tuple[np.ndarray, float, np.ndarray]:
    """Featurise a stream of mono blocks at ``sr``.

    Returns (features (T, 35) float32, tempo in bpm, beat times in seconds), T = samples // hop_length.
    ``timbre=False``: MFCC and chroma columns left at zero (frame_features). ``beats``: where the
    beats come from (default: the tracker).
    """
    featurizer = _BlockFeaturizer(config, hop_length, sr, timbre)
    parts: list[np.ndarray] = []
    for block in blocks:
        parts.extend(featurizer.push(block))
        if progress is not None:
            progress(featurizer.total_samples / sr)
    parts.extend(featurizer.finish())
    seconds = featurizer.total_samples / sr
    if seconds < MIN_DURATION:
        raise AudioError(f"{name} is too short ({seconds:.2f} s; need at least {MIN_DURATION} s)")
    if np.sqrt(featurizer.sum_squares / max(featurizer.total_samples, 1)) < SILENCE_RMS:
        raise AudioError(f"{name} is silent")
    per_frame = np.concatenate(parts)
    if not np.isfinite(per_frame).all():
        raise AudioError(f"{name} produced invalid features (damaged audio?)")
    return assemble_features(per_frame, sr / hop_length, featurizer.beat_envelopes(), sr / BEAT_HOP, beats)


def assemble_features(per_frame: np.ndarray, fps: float, envelopes: np.ndarray, envelope_fps: float,
                      beats: BeatSource = BeatSource()) -> tuple[np.ndarray, float, np.ndarray]:
    """Add the onset-peak and beat one-hot columns to (T, 33) per-frame features; the beats are
    the tracker's, or the user's (``beats``): the one place they enter a song's analysis.

    Returns (features, tempo in bpm, beat times in seconds, those that fall on one of the T frames).
    """
    onset = per_frame[:, ONSET_COLUMN]
    tempo, beat_times = beats.place(envelopes, envelope_fps)
    beat_times = beat_times[beat_frames_at(beat_times, fps, len(per_frame), keep=True)]
    beat_frames = beat_frames_at(beat_times, fps, len(per_frame))
    peak_frames = onset_peaks(onset, fps)
    one_hots = np.zeros((len(per_frame), 2), np.float32)
    one_hots[peak_frames, 0] = 1.0
    one_hots[beat_frames, 1] = 1.0
    return np.concatenate([per_frame, one_hots], axis=1), tempo, beat_times
