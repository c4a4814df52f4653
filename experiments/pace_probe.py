"""How far a pace-conditioned SGMD checkpoint follows the pace it is asked for.

    python -m experiments.pace_probe runs/holdout-pace-scratch/last.pt [--raw] \
        [--songs DANCE_W_18 DANCE_C_2] [--paces 0.25 genre 0.8]

docs/sgmd.md, "Pace". Each validation song is danced whole (seed 0, every default, the clip's genre
as the style) once per asked pace (m/s; ``genre``: the genre's real pace, what ``choreo generate``
asks), and the model's own pace is printed: the ground track's pace before the pace pass
(metadata ``pace["model"]``). ``--raw`` dances with the training weights instead of their EMA,
which lags a young run by about a thousand steps.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import torch

import choreo
from choreo.datasets import load_dataset

from choreo.metrics.songs import song_of



def raw_weights(checkpoint: Path, folder: Path) -> Path:
    """A copy of the checkpoint whose EMA weights are its training weights."""
    state = torch.load(checkpoint, map_location="cpu", weights_only=False)
    state["ema_state_dict"] = state["state_dict"]
    path = folder / checkpoint.name
    torch.save(state, path)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint", type=Path)
    parser.add_argument("--raw", action="store_true", help="the training weights, not their EMA")
    parser.add_argument("--songs", nargs="+", default=["DANCE_W_18", "DANCE_C_2"])
    parser.add_argument("--paces", nargs="+", default=["0.25", "genre", "0.8"])
    parser.add_argument("--data", default="../shared/data/m2d")
    args = parser.parse_args()
    clips = {clip.name: clip for clip in load_dataset(args.data)}
    with tempfile.TemporaryDirectory() as folder:
        checkpoint = raw_weights(args.checkpoint, Path(folder)) if args.raw else args.checkpoint
        backend = choreo.load_backend("sgmd", checkpoint)
        for name in args.songs:
            clip, row = clips[name], []
            for asked in args.paces:
                options = {} if asked == "genre" else {"pace": float(asked)}
                dance = choreo.dance(song_of(clip), backend, style=clip.genre, seed=0, options=options)
                row.append(f"asked {dance.metadata.get('pace_asked')}: {dance.metadata['pace']['model']:.3f}")
            print(f"{name} ({clip.genre}) " + " | ".join(row), flush=True)


if __name__ == "__main__":
    main()
