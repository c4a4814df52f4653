"""Decoding audio files into mono blocks at a target sample rate, without loading whole songs.

soundfile (libsndfile >= 1.1) decodes wav, flac, ogg/vorbis, opus and mp3; soxr resamples in a
stream. A song of any length passes through in blocks, so memory does not depend on its length.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Iterator

import numpy as np
import soundfile as sf
import soxr

from ..errors import AudioError

SUPPORTED_EXTENSIONS = (".wav", ".mp3", ".ogg", ".flac", ".opus")
MIN_DURATION = 0.5  # seconds; shorter audio has no usable beat or feature window
SILENCE_RMS = 1e-5  # below this (about -100 dBFS) a whole song counts as silent
READ_BLOCK_SECONDS = 10.0
MIN_SAMPLE_RATE, MAX_SAMPLE_RATE = 4000, 768_000  # Hz: outside, a header is damaged (2 Hz made 19 kB an 80-min song)
MAX_SAMPLE = 1e4  # full scale is 1: a float WAV 80 dB over it is damaged, and would overflow the spectra


def _check_path(path: Path) -> None:
    if not path.exists():
        raise AudioError(f"{path}: no such file")
    if path.is_dir():
        raise AudioError(f"{path} is a folder, expected an audio file")
    if path.suffix.lower() not in SUPPORTED_EXTENSIONS:
        raise AudioError(f"{path}: unsupported audio type {path.suffix or '(none)'!r} "
                         f"(supported: {', '.join(SUPPORTED_EXTENSIONS)})")
    if path.stat().st_size == 0:
        raise AudioError(f"{path} is empty")


@contextlib.contextmanager
def _decoder_notes_silenced() -> Iterator[None]:
    """Send C-level stderr to /dev/null while libsndfile's mp3 decoder (mpg123) runs: it prints
    "Note: Illegal Audio-MPEG-Header..." and the like straight to file descriptor 2, which would
    break the CLI's promise of one line per error. Python-level output is unaffected in content
    (a progress-bar refresh that lands inside a decoder call is simply skipped)."""
    try:
        saved = os.dup(2)
    except OSError:  # no stderr at all
        yield
        return
    with open(os.devnull, "wb") as null:
        os.dup2(null.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def _open(path: Path) -> sf.SoundFile:
    try:
        with _decoder_notes_silenced():
            handle = sf.SoundFile(os.fsencode(path))  # bytes: names that are not valid UTF-8 open too
    except Exception as error:  # libsndfile reports every decoding problem this way
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
        if "does not exist" in reason or "Error opening" in reason:  # libsndfile's words for a bad mp3 or text
            reason = "damaged, truncated or not audio"
        raise AudioError(f"{path} is not a readable audio file ({reason})") from None
    if not MIN_SAMPLE_RATE <= handle.samplerate <= MAX_SAMPLE_RATE:
        handle.close()
        raise AudioError(f"{path} claims a sample rate of {handle.samplerate} Hz (music has "
                         f"{MIN_SAMPLE_RATE}-{MAX_SAMPLE_RATE} Hz): a damaged header?")
    return handle


def audio_duration(path: str | os.PathLike) -> float:
    """Duration in seconds, from the file header where the format has one."""
    path = Path(path)
    _check_path(path)
    with _open(path) as handle:
        if handle.frames > 0:
            return handle.frames / handle.samplerate
    return sum(len(block) for block in iter_audio_blocks(path, 8000)) / 8000


def iter_audio_blocks(path: str | os.PathLike, sr: int, start: float | None = None, end: float | None = None,
                      block_seconds: float = READ_BLOCK_SECONDS) -> Iterator[np.ndarray]:
    """Yield consecutive mono float32 blocks of the file resampled to ``sr``.

    ``start``/``end`` (seconds) cut an excerpt; the first block begins exactly at ``start``.
    Raises AudioError on decoding failure, including failures halfway through a damaged file.
    """
    path = Path(path)
    _check_path(path)
    with _open(path) as handle:
        native_sr = handle.samplerate
        first = int(round((start or 0.0) * native_sr))
        last = None if end is None else int(round(end * native_sr))
        if first > 0:
            try:
                handle.seek(first)
            except Exception:
                raise AudioError(f"{path}: cannot seek to {start:.2f} s (file too short or damaged)") from None
        resampler = None if native_sr == sr else soxr.ResampleStream(native_sr, sr, 1, dtype="float32")
        position = first
        block_frames = max(1, int(block_seconds * native_sr))
        while last is None or position < last:
            want = block_frames if last is None else min(block_frames, last - position)
            try:
                with _decoder_notes_silenced():
                    data = handle.read(want, dtype="float32", always_2d=True)
            except Exception as error:
                raise AudioError(f"{path}: decoding failed at {position / native_sr:.1f} s ({error})") from None
            done = len(data) < want
            if not np.isfinite(data).all():  # float WAVs can hold NaN or inf; nothing downstream could use them
                raise AudioError(f"{path} contains invalid (NaN or infinite) samples near {position / native_sr:.1f} s")
            if len(data) and np.abs(data).max() > MAX_SAMPLE:
                raise AudioError(f"{path} has samples beyond +-{MAX_SAMPLE:g} (full scale is 1) near "
                                 f"{position / native_sr:.1f} s: a damaged float file")
            position += len(data)
            mono = data.mean(axis=1) if len(data) else np.zeros(0, np.float32)
            out = mono if resampler is None else resampler.resample_chunk(mono, last=done)
            if len(out):
                yield out.astype(np.float32, copy=False)
            if done:
                return
        if resampler is not None:
            tail = resampler.resample_chunk(np.zeros(0, np.float32), last=True)
            if len(tail):
                yield tail.astype(np.float32, copy=False)


def load_audio(path: str | os.PathLike, sr: int, start: float | None = None, end: float | None = None) -> np.ndarray:
    """The whole (excerpt of the) file as one mono float32 array at ``sr``; for short audio."""
    blocks = list(iter_audio_blocks(path, sr, start, end))
    samples = np.concatenate(blocks) if blocks else np.zeros(0, np.float32)
    check_usable(samples, sr, str(path))
    return samples


def check_usable(samples: np.ndarray, sr: int, name: str) -> None:
    """Reject audio too short or too quiet to dance to."""
    if len(samples) < MIN_DURATION * sr:
        raise AudioError(f"{name} is too short ({len(samples) / sr:.2f} s; need at least {MIN_DURATION} s)")
    if not np.isfinite(samples).all():
        raise AudioError(f"{name} contains invalid (NaN or infinite) samples")
    if float(np.sqrt(np.mean(np.square(samples, dtype=np.float64)))) < SILENCE_RMS:
        raise AudioError(f"{name} is silent")
