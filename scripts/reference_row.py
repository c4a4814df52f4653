"""The reference row: M2D's own test split scored against its train split as ground truth.

    python scripts/reference_row.py [--data ../shared/data/m2d]

5 s windows at 30 fps with a 2.5 s stride on both splits (choreo.metrics.protocol). BeatAlign uses
each window's music beats (the beat column of the clip's features). Prints a markdown table; every
later quality table compares with it.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from choreo.datasets import TEST, TRAIN, load_dataset
from choreo.metrics.protocol import TABLE_HEADER, score, table_row, windows_as_dances

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    args = parser.parse_args()
    started = time.time()
    clips = load_dataset(args.data)
    test = windows_as_dances([c for c in clips if c.split == TEST])
    train = windows_as_dances([c for c in clips if c.split == TRAIN])
    report, train_self = score(test, train), score(train, train)
    print(TABLE_HEADER.format(label="set"))
    print(table_row("M2D test (ground truth motion)", report))
    print(table_row("M2D train (the ground-truth set)", train_self))
    print(f"\n{len(test)} test and {len(train)} train windows of 5 s at 30 fps (stride 2.5 s); "
          f"{time.time() - started:.0f} s")


if __name__ == "__main__":
    main()
