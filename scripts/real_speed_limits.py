"""How fast real dancers move: the limits `choreo.finishing.speed_limit` keeps every dance within,
and the paces `choreo.finishing.pace` brings dances toward.

    python scripts/real_speed_limits.py [--data ../shared/data/m2d]

Over every M2D clip at 30 fps: the fastest joint's speed in each frame and the root's travel on
the floor per frame, as percentiles (the speed limit uses the 99.9th), with the fastest frame.
Then the train split's pace along the ground track (choreo.motion.travel), the median per genre
and over all clips, and how far excerpts of 5-40 s (half-overlapping) stray from their genre's
median: the length from which a pace is a property of the dance. Last, the train split's feet by
genre (choreo.metrics.stepping): the planted share and foot~root the footsteps' strength is set by.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from choreo.datasets import TRAIN, load_dataset

REPO = Path(__file__).resolve().parents[1]
FPS = 30.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    args = parser.parse_args()
    fastest_joint, floor_step = [], []
    for clip in load_dataset(args.data):
        motion = clip.motion if abs(clip.motion.fps - FPS) < 1e-6 else clip.motion.resample(FPS)
        positions = motion.joint_positions()
        fastest_joint.append(np.linalg.norm(np.diff(positions, axis=0), axis=-1).max(-1) * FPS)
        floor_step.append(np.linalg.norm(np.diff(positions[:, 0, [0, 2]], axis=0), axis=-1))
    for name, values in (("fastest joint (m/s)", fastest_joint), ("root travel on the floor (m per frame)", floor_step)):
        values = np.concatenate(values)
        p99, p999 = np.percentile(values, [99, 99.9])
        print(f"{name}: 99th percentile {p99:.3f}, 99.9th {p999:.3f}, fastest {values.max():.3f} ({len(values)} frames)")
    train = [clip for clip in load_dataset(args.data) if clip.split == TRAIN]
    print_paces(train)
    print_feet(train)


def print_paces(clips) -> None:
    from choreo.motion.travel import pace

    paces = {clip.name: pace(clip.motion.root_positions, clip.motion.fps) for clip in clips}
    genres = sorted({clip.genre for clip in clips})
    medians = {g: float(np.median([paces[c.name] for c in clips if c.genre == g])) for g in genres}
    print("train pace m/s (median): " + ", ".join(f"{g} {medians[g]:.3f}" for g in genres)
          + f", all clips {np.median(list(paces.values())):.3f}")
    for seconds in (5, 10, 20, 30, 40):
        ratios = [pace(clip.motion.root_positions[start:start + seconds * 30], 30.0) / medians[clip.genre]
                  for clip in clips if clip.genre != "tango"
                  for start in range(0, clip.motion.num_frames - seconds * 30 + 1, seconds * 15)]
        low, high = np.percentile(ratios, [10, 90])
        within = np.mean(np.abs(np.asarray(ratios) - 1) <= 0.2)
        print(f"{seconds} s excerpts: {low:.2f}-{high:.2f} x the genre's median (10th-90th percentile), "
              f"{100 * within:.0f} % within 20 % ({len(ratios)} excerpts)")


def print_feet(clips) -> None:
    from choreo.metrics.stepping import stepping

    for genre in sorted({clip.genre for clip in clips}):
        feet = [stepping(c.motion.joint_positions(), c.motion.fps) for c in clips if c.genre == genre]
        planted, foot_root = [f.planted_share for f in feet], [f.foot_root_correlation for f in feet]
        print(f"train {genre} feet ({len(feet)} clips), median [range]: planted {np.median(planted):.2f} "
              f"[{min(planted):.2f}-{max(planted):.2f}], foot~root {np.median(foot_root):.2f} "
              f"[{min(foot_root):.2f}-{max(foot_root):.2f}]")


if __name__ == "__main__":
    main()
