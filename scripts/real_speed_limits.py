"""How fast real dancers move: the limits `choreo.finishing.speed_limit` keeps every dance within.

    python scripts/real_speed_limits.py [--data ../shared/data/m2d]

Over every M2D clip at 30 fps: the fastest joint's speed in each frame and the root's travel on
the floor per frame, as percentiles (the speed limit uses the 99.9th), with the fastest frame.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from choreo.datasets import load_dataset

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


if __name__ == "__main__":
    main()
