"""Does the music tell how fast a real dancer travels? Each M2D clip's pace against its song's tempo.

    python scripts/experiments/pace_and_tempo.py [--data ../shared/data/m2d]

Issue 45 (docs/results.md, "What the feet and the beats still miss"): the pace pass pulls a whole
song's travel toward its genre's median pace; a dancer far from that median (M2D's DANCE_W_8) is
then missed. If the song's tempo predicted the pace, the pass could aim at it. Per genre: the
correlation over clips of the tempo choreo hears with the pace along the ground track, and each
clip's pair, slowest tempo first.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from choreo.datasets import load_dataset
from choreo.motion.travel import ground_track, track_pace

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "scripts"))
from evaluate_whole_songs import FPS, song_of  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    by_genre: dict[str, list[tuple[str, float, float]]] = {}
    for clip in load_dataset(parser.parse_args().data):
        music = song_of(clip)
        positions = clip.motion.joint_positions()[: len(music.features)]
        by_genre.setdefault(clip.genre, []).append((clip.name, float(music.tempo),
                                                    track_pace(ground_track(positions[:, 0], FPS), FPS)))
    for genre, clips in sorted(by_genre.items()):
        tempo, pace = np.array([c[1] for c in clips]), np.array([c[2] for c in clips])
        correlation = np.corrcoef(tempo, pace)[0, 1] if len(clips) > 2 else float("nan")
        print(f"{genre}: {len(clips)} clips, tempo {tempo.min():.0f}-{tempo.max():.0f} bpm, pace "
              f"{pace.min():.3f}-{pace.max():.3f} m/s, correlation {correlation:.2f}")
        print("   " + ", ".join(f"{name} {bpm:.0f} bpm {speed:.3f}" for name, bpm, speed in sorted(clips, key=lambda c: c[1])))


if __name__ == "__main__":
    main()
