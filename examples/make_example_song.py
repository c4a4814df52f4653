"""Synthesise the bundled example song: an 8-bar drum-and-bass loop at exactly 174 bpm.

Deterministic (fixed seed), about 11 s, mono 22.05 kHz, 16-bit WAV. Kick on beats 1 and 3
(with a syncopated ghost kick), snare on 2 and 4, sixteenth-note hi-hats and a sub-bass line.
Run from the repository root:  python examples/make_example_song.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import soundfile as sf

SR = 22050
BPM = 174.0
BARS = 8
BEAT_SECONDS = 60.0 / BPM
OUT = Path(__file__).with_name("drum_and_bass_174bpm.wav")


def decaying(duration: float, decay: float) -> np.ndarray:
    t = np.arange(int(duration * SR)) / SR
    return np.exp(-t / decay), t


def kick() -> np.ndarray:
    env, t = decaying(0.35, 0.08)
    pitch = 50 + 90 * np.exp(-t / 0.03)  # the downward sweep that makes a kick thump
    return 0.9 * env * np.sin(2 * np.pi * np.cumsum(pitch) / SR)


def snare(rng: np.random.Generator) -> np.ndarray:
    env, t = decaying(0.25, 0.06)
    return 0.5 * env * (rng.normal(size=t.size) * 0.7 + np.sin(2 * np.pi * 190 * t) * 0.5)


def hat(rng: np.random.Generator) -> np.ndarray:
    env, t = decaying(0.05, 0.012)
    noise = rng.normal(size=t.size)
    return 0.15 * env * np.diff(noise, prepend=0.0)  # differenced noise: a bright, high hat


def bass_note(freq: float, duration: float) -> np.ndarray:
    t = np.arange(int(duration * SR)) / SR
    env = np.minimum(1.0, t / 0.01) * np.exp(-t / (duration * 0.8))
    return 0.35 * env * np.tanh(2.0 * np.sin(2 * np.pi * freq * t))


def place(track: np.ndarray, sound: np.ndarray, at_seconds: float) -> None:
    start = int(round(at_seconds * SR))
    end = min(len(track), start + len(sound))
    track[start:end] += sound[: end - start]


def make_loop(seed: int = 174) -> np.ndarray:
    rng = np.random.default_rng(seed)
    beats = BARS * 4
    track = np.zeros(int((beats * BEAT_SECONDS + 0.5) * SR))
    bass_line = [55.0, 55.0, 65.41, 49.0]  # A1, A1, C2, G1: one note per bar, repeating
    for beat in range(beats):
        at = beat * BEAT_SECONDS
        if beat % 4 in (0, 2):
            place(track, kick(), at)
        if beat % 4 in (1, 3):
            place(track, snare(rng), at)
        if beat % 8 == 5:
            place(track, kick() * 0.6, at + BEAT_SECONDS / 2)  # the two-step's syncopated kick
        for sixteenth in range(4):
            place(track, hat(rng) * (1.0 if sixteenth % 2 == 0 else 0.6), at + sixteenth * BEAT_SECONDS / 4)
        if beat % 4 == 0:
            place(track, bass_note(bass_line[(beat // 4) % 4], 4 * BEAT_SECONDS), at)
    return (track / np.abs(track).max() * 0.9).astype(np.float32)


if __name__ == "__main__":
    sf.write(OUT, make_loop(), SR, subtype="PCM_16")
    print(f"wrote {OUT} ({BARS * 4} beats at {BPM:g} bpm)")
