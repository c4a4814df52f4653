"""Songs made here: a click track on a quiet tone, written as a sound file."""

from pathlib import Path

import numpy as np
import soundfile as sf


def click_track(bpm: float, seconds: float, sr: int = 22050) -> np.ndarray:
    """Short decaying noise bursts exactly on the beat, over a quiet tone so no frame is silent."""
    rng = np.random.default_rng(0)
    signal = 0.01 * np.sin(2 * np.pi * 220 * np.arange(int(seconds * sr)) / sr)
    burst = rng.normal(size=int(0.03 * sr)) * np.exp(-np.arange(int(0.03 * sr)) / (0.005 * sr))
    for beat in np.arange(0, seconds, 60.0 / bpm):
        start = int(beat * sr)
        end = min(len(signal), start + len(burst))
        signal[start:end] += burst[: end - start]
    return signal.astype(np.float32)


def write_song(path: Path, seconds: float, sr: int = 22050, bpm: float = 120.0, **kwargs) -> Path:
    sf.write(path, click_track(bpm, seconds, sr), sr, **kwargs)
    return path
