"""Is an augmentation honest for this data? Score the M2D test split's real motion, transformed
(mirrored, or danced faster or slower), against the train split exactly like a generator.

    python scripts/transformed_reference.py [--data ../shared/data/m2d]

A transformation whose real-motion FID stays near the reference row's produces dances like the
corpus's; one far above it teaches the model something the corpus never does.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from choreo.datasets import TEST, TRAIN, load_dataset
from choreo.metrics import Dance
from choreo.metrics.protocol import TABLE_HEADER, music_beats, score, scoring_windows, table_row, windows_as_dances
from choreo.motion import mirrored, stretched

REPO = Path(__file__).resolve().parents[1]
PACES = (0.85, 1.18)
COMMON_FRAMES = 120  # 4 s: what every window still has after the fastest pace


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    args = parser.parse_args()
    clips = load_dataset(args.data)
    train = windows_as_dances([c for c in clips if c.split == TRAIN])
    windows = scoring_windows([c for c in clips if c.split == TEST])
    print(TABLE_HEADER.format(label="real test motion"), flush=True)
    print(table_row("as it is", score(windows_as_dances([c for c in clips if c.split == TEST]), train)), flush=True)
    mirror = [Dance(f"{w.clip}@{w.start_frame}", mirrored(w.motion).joint_positions(), music_beats(w.features))
              for w in windows]
    print(table_row("mirrored", score(mirror, train)), flush=True)
    for pace in PACES:  # beats are not stretched here: read FID and diversity only
        paced = [Dance(f"{w.clip}@{w.start_frame}", stretched(w.motion, pace).joint_positions()[:COMMON_FRAMES],
                       music_beats(w.features)[:0]) for w in windows]
        print(table_row(f"danced {pace:g} x as fast (first 4 s)", score(paced, train)), flush=True)


if __name__ == "__main__":
    main()
