"""How much of the real dancers' figures is their capture: noise, and waltz's 5.9 fps keyframes.

    python scripts/experiments/real_capture.py [--data ../shared/data/m2d]

Issue 45 (docs/results.md, "What the feet and the beats still miss"). Every cha-cha and rumba clip
of M2D (captured at 25 fps), whole, as it is; low-passed at 10, 6 and 4 Hz (is the low foot~root
of real Latin dancers capture noise, which would decorrelate the feet from the root?); and sampled
at 5.9 fps then linearly interpolated back, as M2D's waltz was captured (is waltz's deep beat dip
or its high foot~root an artefact of that?). Then every waltz clip as it is.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.interpolate import interp1d

from choreo.datasets import load_dataset
from choreo.metrics.whole_song import whole_song
from choreo.motion.filters import low_pass

FPS = 30.0
WALTZ_CAPTURE_FPS = 5.9
REPO = Path(__file__).resolve().parents[2]


def keyframed(positions: np.ndarray, key_fps: float = WALTZ_CAPTURE_FPS) -> np.ndarray:
    """The dance sampled at ``key_fps`` and linearly interpolated back to 30 fps (up to its last key)."""
    t = np.arange(len(positions)) / FPS
    keys = np.arange(0, t[-1], 1 / key_fps)
    poses = interp1d(t, positions, axis=0)(keys)
    return interp1d(keys, poses, axis=0)(t[t <= keys[-1]])


def figures(label: str, positions: np.ndarray) -> str:
    w = whole_song(positions, FPS)
    return f"{label}: foot~root {w.foot_root:.2f} planted {w.planted:.2f} jerk {w.jerk:.0f} dip {w.beat_dip:.3f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    clips = load_dataset(parser.parse_args().data)
    for clip in clips:
        if clip.genre in ("cha-cha", "rumba"):
            p = clip.motion.joint_positions()
            variants = [("as is", p), *((f"{hz} Hz", low_pass(p, FPS, hz)) for hz in (10, 6, 4)),
                        ("5.9 fps keys", keyframed(p))]
            print(clip.name, " | ".join(figures(label, q) for label, q in variants), flush=True)
    for clip in clips:
        if clip.genre == "waltz":
            print(clip.name, figures("as is", clip.motion.joint_positions()), flush=True)


if __name__ == "__main__":
    main()
