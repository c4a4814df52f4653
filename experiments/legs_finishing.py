"""Which finishing pass changes the legs' figures, and by how much?

    python -m experiments.legs_finishing --checkpoint generators/choreo_sgmd/weights/sgmd-cpu-m2d-holdout.pt \
        [--songs DANCE_C_2 DANCE_R_2] [--seeds 0 1 2]

The legs issue asks that the finishing passes change the feet's speed around the pelvis, ankle
lift and the pelvis's speed by at most 10 % each, so that the legs come from the model. Each
validation song (default: the Latin ones) is danced once per seed by the backend, exactly as
`choreo generate` would (the clip's genre as style), and that one raw dance is finished several
ways: every pass off, every pass on (the CLI's defaults), and the defaults with one pass off at a
time. Printed per way: the legs figures (choreo.metrics.legs) and foot~root, as a ratio to the raw
dance's, pooled over songs and seeds.
"""

from __future__ import annotations

import argparse
import copy
from dataclasses import fields, replace

import numpy as np

import choreo
from choreo.datasets import load_dataset
from choreo.finishing import Finishing, finish
from choreo.generator import GenerationRequest
from choreo.metrics.songs import FPS, split_clips, song_of
from choreo.metrics.whole_song import whole_song

FIGURES = ("feet_speed", "ankle_lift", "pelvis_speed", "foot_root")
PASSES = [f.name for f in fields(Finishing) if f.type in (bool, "bool")]


def ways() -> dict[str, Finishing]:
    """Every pass off, the defaults, and the defaults without one pass at a time."""
    defaults = Finishing()
    chosen = {"raw": replace(defaults, **{name: False for name in PASSES}), "defaults": defaults}
    for name in PASSES:
        if getattr(defaults, name):
            chosen[f"without {name}"] = replace(defaults, **{name: False})
    return chosen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkpoint", default=None)
    parser.add_argument("--data", default="../shared/data/m2d")
    parser.add_argument("--songs", nargs="+", default=["DANCE_C_2", "DANCE_R_2"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    args = parser.parse_args()
    clips = [c for c in split_clips(load_dataset(args.data), "validation") if c.name in args.songs]
    backend = choreo.load_backend("sgmd", args.checkpoint)
    rows: dict[str, list[dict]] = {name: [] for name in ways()}
    real = []
    for clip in clips:
        music = song_of(clip)
        real.append(whole_song(clip.motion.joint_positions()[: len(music.features)], FPS).to_dict())
        for seed in args.seeds:
            raw = backend.generate(GenerationRequest(music, style=clip.genre, seed=seed))
            for name, finishing in ways().items():
                finished = finish(copy.deepcopy(raw), music.beat_frames, finishing, audible=music.audible)
                rows[name].append(whole_song(finished.joint_positions(), FPS).to_dict())
        print(f"{clip.name} done", flush=True)
    base = {key: np.array([r[key] for r in rows["raw"]]) for key in FIGURES}
    print("| finishing | " + " | ".join(FIGURES) + " | " + " | ".join(f"{key} / raw" for key in FIGURES) + " |")
    print("| --- |" + " ---: |" * (2 * len(FIGURES)))
    print("| real dancers | " + " | ".join(f"{np.mean([r[key] for r in real]):.3f}" for key in FIGURES) + " |" * (len(FIGURES) + 1))
    for name, finished in rows.items():
        values = {key: np.array([r[key] for r in finished]) for key in FIGURES}
        ratios = [float(np.mean(values[key]) / np.mean(base[key])) for key in FIGURES]
        print(f"| {name} | " + " | ".join(f"{np.mean(values[key]):.3f}" for key in FIGURES) + " | "
              + " | ".join(f"{ratio:.2f}" for ratio in ratios) + " |")


if __name__ == "__main__":
    main()
