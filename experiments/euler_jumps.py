"""How often a BVH rotation channel jumps by more than 180 degrees between two frames.

    python -m experiments.euler_jumps [--songs DANCE_C_4 DANCE_R_3 DANCE_W_4] [--seed 1]

Issue 47, part 1 (docs/formats.md, "BVH"). Each frame's ZXY angles solved on their own (as choreo
wrote them until 2026-12-05) against the continuous curves it writes now
(choreo.skeleton.continuous_euler), for both generators' whole dances to M2D test songs (genre as
style) and for the real dancers.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import choreo
from choreo.datasets import load_dataset
from choreo.formats.bvh import ROTATION_ORDER
from choreo.skeleton import continuous_euler, matrix_to_euler

from choreo.metrics.songs import song_of

REPO = Path(__file__).resolve().parents[1]


def jumps(rotation_matrices: np.ndarray) -> tuple[int, int]:
    """(jumps solved frame by frame, jumps in continuous curves): channels moving > 180 degrees."""
    solved = matrix_to_euler(rotation_matrices, ROTATION_ORDER)
    count = lambda angles: int((np.abs(np.diff(np.degrees(angles), axis=0)) > 180).sum())  # noqa: E731
    return count(solved), count(continuous_euler(solved))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--songs", nargs="+", default=["DANCE_C_4", "DANCE_R_3", "DANCE_W_4"])
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    clips = {c.name: c for c in load_dataset(args.data)}
    dancers = {"real dancers": None, "SGMD": choreo.load_backend("sgmd"), "ChoreoGraph": choreo.load_backend("graph")}
    print("| dancer | jumps a minute, solved per frame | continuous |")
    print("| --- | ---: | ---: |")
    for label, backend in dancers.items():
        counts, minutes = np.zeros(2), 0.0
        for name in args.songs:
            clip = clips[name]
            motion = clip.motion if backend is None else choreo.dance(song_of(clip), backend, style=clip.genre,
                                                                       seed=args.seed)
            counts += jumps(motion.rotation_matrices())
            minutes += motion.duration / 60
        print(f"| {label} | {counts[0] / minutes:.1f} | {counts[1] / minutes:.1f} |")


if __name__ == "__main__":
    main()
