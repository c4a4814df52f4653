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


CHORDS = {"C": (60, 64, 67), "G": (55, 59, 62), "Am": (57, 60, 64), "F": (53, 57, 60), "Dm": (62, 65, 69),
          "E": (52, 56, 59), "Bb": (58, 62, 65), "Eb": (51, 55, 58)}
SECTION_MUSIC = {"A": (("C", "G", "Am", "F"), 1.0), "B": (("Dm", "Bb", "E", "Eb"), 0.3), "C": (("F", "E", "C", "Dm"), 3.0)}


def form_song(form: str, bars_per_section: int = 8, bpm: float = 120.0, sr: int = 22050) -> np.ndarray:
    """A song whose sections (letters of ``form``) each play their own chord progression, one chord a
    bar, with their own timbre (how strong the upper harmonics are), over clicks on the beat."""
    bar = 4 * 60.0 / bpm
    sections = []
    for letter in form:
        chords, brightness = SECTION_MUSIC[letter]
        for index in range(bars_per_section):
            t = np.arange(int(bar * sr)) / sr
            notes = CHORDS[chords[index % len(chords)]]
            tone = sum(np.sin(2 * np.pi * 440 * 2 ** ((n - 69) / 12) * k * t) * brightness ** (k - 1) / k
                       for n in notes for k in range(1, 6))
            sections.append(0.05 * tone * np.minimum(1, 20 * t))  # a soft attack: no click at the bar line
    signal = np.concatenate(sections)
    return (signal + click_track(bpm, len(signal) / sr, sr)[: len(signal)]).astype(np.float32)
