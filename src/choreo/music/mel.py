"""Log-mel spectrograms at the motion frame rate, for models that listen to the raw spectrum.

Same resampling as the 35-d features (15360 Hz, hop 512), so mel frame t is motion frame t at
30 fps. ChoreoGraph's style and tempo encoders read 96 bands; the paper used 60 frames per second,
here every model runs at the motion rate so no frame has to be re-timed.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

from ..errors import ParameterError
from .audio import iter_audio_blocks
from .features import HOP_LENGTH, SAMPLE_RATE
from .spectrum import mel_power, power_to_db

N_MELS = 96
N_FFT = 2048
DB_FLOOR = -80.0  # dB below full scale: where silence is clipped (values are then scaled to [0, 1])


def _scaled_mel(samples: np.ndarray, n_mels: int) -> np.ndarray:
    """Frames of ``samples`` taken every hop from sample 0 (no centring), as (T, n_mels) in [0, 1]."""
    db = power_to_db(mel_power(samples, SAMPLE_RATE, N_FFT, HOP_LENGTH, n_mels, center=False))
    return ((np.clip(db, DB_FLOOR, 0.0) - DB_FLOOR) / -DB_FLOOR).T.astype(np.float32)


class LogMelStream:
    """Log-mel of a signal pushed block by block, equal to the whole-signal (centred) computation.

    Only one block plus a window of audio is held at a time, so an hour of music costs its
    (small) spectrogram, not its samples. Frame t is centred on sample t * hop, zero-padded
    before the start and after the end like librosa's ``center=True``. Being a sink rather than a
    loop, it can listen to the same decode as the other analyses (``Music.from_file(log_mel=True)``).
    """

    def __init__(self, n_mels: int = N_MELS):
        self.n_mels = n_mels
        self.pending = np.zeros(N_FFT // 2, np.float32)
        self.done = self.total = 0
        self.out: list[np.ndarray] = []

    def push(self, block: np.ndarray) -> None:
        self.total += len(block)
        self.pending = np.concatenate([self.pending, np.asarray(block, np.float32)])
        count = (len(self.pending) - N_FFT) // HOP_LENGTH + 1
        if count > 0:
            self.out.append(_scaled_mel(self.pending[: (count - 1) * HOP_LENGTH + N_FFT], self.n_mels))
            self.pending, self.done = self.pending[count * HOP_LENGTH:], self.done + count

    def finish(self) -> np.ndarray:
        """(1 + samples // hop, n_mels) frames of everything pushed."""
        frames_wanted = 1 + self.total // HOP_LENGTH
        tail = np.concatenate([self.pending, np.zeros(N_FFT // 2 + N_FFT, np.float32)])
        return np.concatenate(self.out + [_scaled_mel(tail, self.n_mels)[: frames_wanted - self.done]])


def stream_log_mel(blocks: Iterable[np.ndarray], n_mels: int = N_MELS) -> np.ndarray:
    """Log-mel of a signal given block by block (see :class:`LogMelStream`)."""
    stream = LogMelStream(n_mels)
    for block in blocks:
        stream.push(block)
    return stream.finish()


def log_mel(samples: np.ndarray, num_frames: int | None = None, n_mels: int = N_MELS) -> np.ndarray:
    """(T, n_mels) float32 log-mel of a mono signal at SAMPLE_RATE, in [0, 1] (0 = DB_FLOOR).

    ``num_frames`` cuts or edge-pads the result to exactly that many frames (T = floor(d * 30)).
    """
    return fit_length(stream_log_mel([samples], n_mels), num_frames)


def fit_length(frames: np.ndarray, num_frames: int | None) -> np.ndarray:
    if num_frames is not None:
        frames = frames[:num_frames]
        if len(frames) < num_frames:
            frames = np.concatenate([frames, np.repeat(frames[-1:], num_frames - len(frames), axis=0)])
    return frames


def log_mel_from_file(path, start: float = 0.0, num_frames: int | None = None) -> np.ndarray:
    """Log-mel of ``path`` from ``start`` seconds (for ``num_frames`` frames, or to the end)."""
    end = None if num_frames is None else start + (num_frames + 1) * HOP_LENGTH / SAMPLE_RATE
    return fit_length(stream_log_mel(iter_audio_blocks(path, SAMPLE_RATE, start or None, end)), num_frames)


def music_log_mel(music) -> np.ndarray:
    """Log-mel frames aligned with ``music.features``: the ones analysed with it (``log_mel=True``),
    else decoded again from its file."""
    if getattr(music, "log_mel", None) is not None:
        return music.log_mel
    if music.path is None:
        raise ParameterError("this backend listens to the spectrum and needs the song's audio file")
    return log_mel_from_file(music.path, music.start, music.num_frames)
