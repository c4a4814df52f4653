"""The finishing pass on a long song, side by side: BeatAlign, PFC, jerk, the seconds it adds,
and the fastest joint against real M2D motion (the "no limb flips" check).

    python benchmarks/finishing_long_song.py [--minutes 10] [--m2d ../shared/data/m2d]

The song is the example loop tiled; both bundled generators dance it once (seed 0), and the
same dance is scored as it comes, after the speed limit alone, finished without footsteps (speed
limit, beat lock, speed limit) and as `choreo generate` writes it (footsteps too).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from common import write_song

from choreo.finishing import beat_lock, finish, speed_limit
from choreo.pipeline import Finishing
from choreo.generator import GenerationRequest
from choreo.metrics import beat_align_score, foot_contact_score, motion_beats
from choreo.music import Music


def fastest_joint(positions: np.ndarray, fps: float) -> np.ndarray:
    """(T-1,) the speed of the fastest joint between consecutive frames, m/s."""
    return np.linalg.norm(np.diff(positions, axis=0), axis=-1).max(axis=1) * fps


def main() -> None:
    from choreo import load_backend

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--m2d", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "data" / "m2d")
    args = parser.parse_args()
    limit = None
    if args.m2d.is_dir():
        from choreo.datasets import load_dataset

        real = np.concatenate([fastest_joint(c.motion.joint_positions(), c.motion.fps) for c in load_dataset(args.m2d)])
        limit = float(np.percentile(real, 99.9))
        print(f"real M2D: fastest joint per frame, 99.9th percentile {limit:.2f} m/s (max {real.max():.2f})")
    folder = tempfile.TemporaryDirectory()  # kept to the end: the graph backend reads the song again
    music = Music.from_file(write_song(Path(folder.name), args.minutes * 60))
    print(f"song: {args.minutes:g} min, heard at {music.tempo:.1f} bpm")
    print("| generator | dance | BeatAlign | PFC | mean jerk (mm/frame^3) | fastest joint (m/s) | frames above real 99.9 % |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for name, backend in (("SGMD", load_backend("sgmd")), ("ChoreoGraph", load_backend("graph"))):  # the bundled models
        raw = backend.generate(GenerationRequest(music, seed=0))
        started = time.perf_counter()
        limited = speed_limit(raw)
        limit_spent = time.perf_counter() - started
        started = time.perf_counter()
        locked = beat_lock(raw, music.beat_frames)
        spent = time.perf_counter() - started
        started = time.perf_counter()
        unstepped = finish(raw, music.beat_frames, Finishing(footsteps=False))
        unstepped_spent = time.perf_counter() - started
        started = time.perf_counter()
        finished = finish(raw, music.beat_frames)
        finish_spent = time.perf_counter() - started
        for label, motion in (("as it comes", raw), ("speed limit", limited), ("beat lock alone", locked.motion),
                              ("finished without footsteps", unstepped), ("finished (speed limit, beat lock, footsteps)", finished)):
            p = motion.joint_positions()
            speed = fastest_joint(p, motion.fps)
            above = "-" if limit is None else f"{int((speed > limit).sum())}"
            print(f"| {name} | {label} | {beat_align_score(music.beat_frames, motion_beats(p)):.3f} | "
                  f"{foot_contact_score(p) * 1e4:.3f} | {np.abs(np.diff(p, 3, axis=0)).mean() * 1e3:.3f} | "
                  f"{speed.max():.2f} | {above} |")
        print(f"| {name} | beat lock took {spent:.2f} s ({60 * spent / raw.duration:.3f} s per minute), "
              f"{len(locked.pairs)} of {locked.motion_beats} motion beats paired; the speed limit "
              f"{limit_spent:.2f} s; the whole finish {finish_spent:.2f} s ({60 * finish_spent / raw.duration:.3f} s per "
              f"minute), {unstepped_spent:.2f} s without footsteps ({finish_spent / unstepped_spent:.2f} x) | | | | | |")
    folder.cleanup()


if __name__ == "__main__":
    main()
