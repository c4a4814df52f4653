"""The reference row: M2D's own test split scored against its train split as ground truth.

    python scripts/reference_row.py [--data ../shared/data/m2d]

5 s windows at 30 fps with a 2.5 s stride on both splits (as papers score AIST++). BeatAlign uses
each window's music beats (the beat column of the clip's features). Prints a markdown table; every
later quality table compares with it.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from choreo.datasets import TEST, TRAIN, WindowConfig, WindowedDataset, load_dataset
from choreo.metrics import Dance, MetricWarning, evaluate
from choreo.music import BEAT_COLUMN

REPO = Path(__file__).resolve().parents[1]
WINDOWS = WindowConfig(seconds=5.0, stride_seconds=2.5, fps=30.0)


def windows_as_dances(clips) -> list[Dance]:
    dances = []
    for window in WindowedDataset(clips, WINDOWS):
        beats = np.flatnonzero(window.features[:, BEAT_COLUMN] > 0.5)
        dances.append(Dance(f"{window.clip}@{window.start_frame}", window.motion.joint_positions(), beats))
    return dances


def fmt(value) -> str:
    return "-" if value is None else f"{value:.3f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    args = parser.parse_args()
    started = time.time()
    clips = load_dataset(args.data)
    test = windows_as_dances([c for c in clips if c.split == TEST])
    train = windows_as_dances([c for c in clips if c.split == TRAIN])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        report = evaluate(test, train, fps=WINDOWS.fps)
        train_self = evaluate(train, train, fps=WINDOWS.fps)
    print("| set | clips | BeatAlign | PFC | FID_k | FID_g | Div_k | Div_g | beat dist motion->music | music->motion |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    print(f"| M2D test (ground truth motion) | {report.generated_count} | {fmt(report.beat_align)} | {fmt(report.pfc)} | "
          f"{fmt(report.fid_k)} | {fmt(report.fid_g)} | {fmt(report.div_k)} | {fmt(report.div_g)} | "
          f"{fmt(report.motion_to_music)} | {fmt(report.music_to_motion)} |")
    print(f"| M2D train (the ground-truth set) | {train_self.generated_count} | {fmt(train_self.beat_align)} | "
          f"{fmt(train_self.pfc)} | 0 | 0 | {fmt(train_self.div_k)} | {fmt(train_self.div_g)} | "
          f"{fmt(train_self.motion_to_music)} | {fmt(train_self.music_to_motion)} |")
    print(f"\n{len(test)} test and {len(train)} train windows of 5 s at 30 fps (stride 2.5 s); "
          f"{time.time() - started:.0f} s")


if __name__ == "__main__":
    main()
