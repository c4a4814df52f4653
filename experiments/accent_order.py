"""Where the accent goes among the finishing passes: after all of them, or before the footsteps.

    python -m experiments.accent_order [--checkpoint runs/holdout/last.pt] [--seeds 0] [--depths 0.1 0.2 0.3]

Issue 45 (docs/results.md, "Finishing passes", "Accent"). Each validation clip's song is danced
whole by SGMD (genre as the style); the raw dance is finished with every pass but the accent, then
accented after all of them, or accented after the pace pass and finished by the footsteps and the
beat lock (where choreo.finishing.finish runs it). Printed per song: the beat dip, foot~root,
planted share and whole-body jerk of each, the real dancer's first.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import choreo
from choreo.datasets import load_dataset
from choreo.finishing import AccentConfig, accent, finish
from choreo.metrics.whole_song import whole_song
from choreo.pipeline import Finishing

from choreo.metrics.songs import FPS, song_of, split_clips

REPO = Path(__file__).resolve().parents[1]

RAW = Finishing(speed_limit=False, root_path=False, pace=False, accent=False, footsteps=False, beat_lock=False)
UP_TO_PACE = Finishing(accent=False, footsteps=False, beat_lock=False)
FROM_FOOTSTEPS = Finishing(root_path=False, pace=False, accent=False)


def figures(label: str, positions: np.ndarray) -> str:
    w = whole_song(positions, FPS)
    return f"{label}: dip {w.beat_dip:.3f} foot~root {w.foot_root:.2f} planted {w.planted:.2f} jerk {w.jerk:.0f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkpoint", default=str(REPO / "runs" / "holdout" / "last.pt"))
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--depths", type=float, nargs="+", default=[0.1, 0.2, 0.3])
    args = parser.parse_args()
    backend = choreo.load_backend("sgmd", args.checkpoint)
    for clip in split_clips(load_dataset(args.data), "validation"):
        music = song_of(clip)
        print(clip.name, figures("real", clip.motion.joint_positions()[: len(music.features)]), flush=True)
        for seed in args.seeds:
            raw = choreo.dance(music, backend, style=clip.genre, seed=seed, finishing=RAW)
            paced = finish(raw, music.beat_frames, UP_TO_PACE)
            finished = finish(paced, music.beat_frames, FROM_FOOTSTEPS)
            print(f"  seed {seed}", figures("no accent", finished.joint_positions()), flush=True)
            for depth in args.depths:
                config = AccentConfig(depth=depth)
                last = accent(finished, None, config).joint_positions()
                before_feet = finish(accent(paced, None, config), music.beat_frames, FROM_FOOTSTEPS).joint_positions()
                print(f"    depth {depth}", figures("last", last), "|", figures("before the footsteps", before_feet),
                      flush=True)


if __name__ == "__main__":
    main()
