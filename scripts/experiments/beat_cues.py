"""Could the default tracker tell the beat from the half-beat, or a fast song from half of it?

    python scripts/experiments/beat_cues.py [--m2d ../shared/data/m2d]

Issue 36, part 3 (docs/results.md, "What the default tracker still gets wrong"). On the LMMS songs
(benchmarks/outside_songs.py; the stated grid is the truth) each phase cue is the mean of a band's
onset strength on the grid's beats over its mean half a beat later (the strongest value 1 frame
before to 4 after each point, since rendered onsets trail the grid by 8-26 ms): above 1 the cue
picks the right phase. Cues: the percussive part's onsets (what choreo uses), the harmonic part's,
chord changes (chroma of the half-beat before against the half-beat after) and the lowest 8 mel
bands (kick and bass). The octave cue is the percussive onset on the beats choreo tracks at twice
the tempo it hears, over the onset between them: a song heard at half its tempo has real beats
between, so the ratio is low. ``--m2d`` prints the octave cue for the M2D songs too (ballroom,
which must not be doubled).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import librosa
import numpy as np

from choreo.datasets import load_dataset
from choreo.music import BEAT_HOP, estimate_beats, load_audio, onset_envelopes
from choreo.music.beats import ENVELOPE_FFT, ENVELOPE_FMAX, ENVELOPE_MELS, ONSET_LAG, percussive_part, track_beats
from choreo.music.spectrum import mel_power, onset_strength, power_to_db

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "benchmarks"))
from outside_songs import outside_songs  # noqa: E402

SR = 15360
FPS = SR / BEAT_HOP


def peak_mean(envelope: np.ndarray, points: np.ndarray) -> float:
    """Mean over ``points`` of the envelope's largest value from 1 frame before to 4 after."""
    index = np.round(points).astype(int)
    near = np.stack([envelope[np.clip(index + d, 0, len(envelope) - 1)] for d in range(-1, 5)])
    return float(near.max(axis=0).mean())


def chord_change(samples: np.ndarray, frames: int, half_beat: int) -> np.ndarray:
    """(frames,) 1 - cosine between the mean chroma of the half-beat before and the one after."""
    power = np.abs(librosa.stft(samples, n_fft=4096, hop_length=BEAT_HOP)) ** 2
    chroma = librosa.feature.chroma_stft(S=power, sr=SR)[:, :frames]
    chroma /= np.linalg.norm(chroma, axis=0, keepdims=True) + 1e-9
    total = np.cumsum(np.pad(chroma, ((0, 0), (1, 0))), axis=1)
    at = np.arange(chroma.shape[1])
    before = total[:, at] - total[:, np.clip(at - half_beat, 0, None)]
    after = total[:, np.clip(at + half_beat, None, chroma.shape[1])] - total[:, at]
    cosine = (before * after).sum(0) / (np.linalg.norm(before, axis=0) * np.linalg.norm(after, axis=0) + 1e-9)
    return 1.0 - cosine


def phase_cues(samples: np.ndarray, bpm: float) -> dict[str, float]:
    mel = mel_power(samples, SR, ENVELOPE_FFT, BEAT_HOP, ENVELOPE_MELS, ENVELOPE_FMAX)
    period = 60.0 / bpm * FPS
    beats = np.arange(period, mel.shape[1] - period - 1, period)
    between = beats + period / 2
    percussive = percussive_part(mel)
    bands = {"percussive": percussive, "harmonic": np.maximum(mel - percussive, 0.0), "low bands": mel[:8]}
    cues = {}
    for name, power in bands.items():
        onsets = onset_strength(power_to_db(power), ENVELOPE_FFT, BEAT_HOP, ONSET_LAG)
        cues[name] = peak_mean(onsets, beats) / peak_mean(onsets, between)
    change = chord_change(samples, mel.shape[1], round(period / 2))
    cues["chord change"] = change[np.round(beats).astype(int)].mean() / change[np.round(between).astype(int)].mean()
    return cues


def octave_cue(samples: np.ndarray) -> tuple[float, float]:
    """(tempo choreo hears, percussive onset on the beats at twice it over the onset between them)."""
    full, percussive = onset_envelopes(samples, SR).astype(np.float64)
    tempo, _ = estimate_beats(np.stack([full, percussive]), FPS)
    frames = track_beats(full, FPS, 2 * tempo).astype(np.float64)
    between = frames[:-1] + np.diff(frames) / 2
    on, off = (float(np.interp(f, np.arange(len(percussive)), percussive).mean()) for f in (frames, between))
    return tempo, on / max(off, 1e-9)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--m2d", default=None, help="also the octave cue on these M2D songs")
    args = parser.parse_args()
    songs = outside_songs()
    if not songs:
        sys.exit("needs LMMS (apt-get install lmms) to render the outside songs")
    right: dict[str, int] = {}
    print("| song | stated bpm | heard bpm | octave cue | " + " | ".join(["percussive", "harmonic", "low bands", "chord change"]) + " |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for song in songs:
        samples = load_audio(song.path, SR)
        cues = phase_cues(samples, song.bpm)
        heard, octave = octave_cue(samples)
        for name, value in cues.items():
            right[name] = right.get(name, 0) + (value > 1)
        print(f"| {song.name} | {song.bpm:.0f} | {heard:.1f} | {octave:.2f} | " + " | ".join(f"{v:.2f}" for v in cues.values()) + " |",
              flush=True)
    print("\nright phase: " + ", ".join(f"{name} {count}/{len(songs)}" for name, count in right.items()))
    if args.m2d:
        print("\n| M2D song | heard bpm | octave cue |\n| --- | ---: | ---: |")
        for clip in (c for c in load_dataset(args.m2d) if c.audio_path):
            samples = load_audio(clip.audio_path, SR, clip.audio_offset, clip.audio_offset + clip.motion.duration)
            heard, octave = octave_cue(samples)
            print(f"| {clip.name} | {heard:.1f} | {octave:.2f} |", flush=True)


if __name__ == "__main__":
    main()
