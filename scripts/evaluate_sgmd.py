"""Score SGMD checkpoints on the M2D test split against the train split (the reference row's setup).

    python scripts/evaluate_sgmd.py CHECKPOINT [CHECKPOINT ...] [--guidance 1 2] [--steps 20 50] [--no-style] [--finished]

One 5 s dance per test window (2.5 s stride), generated from that window's music and the clip's
genre; one markdown row per checkpoint x guidance x steps, beside the reference row's columns.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from choreo.datasets import TEST, TRAIN, load_dataset
from choreo.metrics.protocol import TABLE_HEADER, score, scoring_windows, table_row, windows_as_dances
from choreo_sgmd.evaluation import generate_window_dances
from choreo_sgmd.generator import SGMDGenerator
from choreo_sgmd.sampling import SamplingOptions

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoints", nargs="+")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--guidance", type=float, nargs="+", default=[2.0])
    parser.add_argument("--steps", type=int, nargs="+", default=[50])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-style", action="store_true")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--finished", action="store_true",
                        help="also score each dance after the beat lock (choreo.finishing), side by side")
    parser.add_argument("--foot-lock", action="store_true", help="with --finished: the foot lock too")
    args = parser.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)
    clips = load_dataset(args.data)
    test_clips = [c for c in clips if c.split == TEST]
    windows, train = scoring_windows(test_clips), windows_as_dances([c for c in clips if c.split == TRAIN])
    print(TABLE_HEADER.format(label="model"), flush=True)
    for checkpoint in args.checkpoints:
        generator = SGMDGenerator(checkpoint)
        for guidance in args.guidance:
            for steps in args.steps:
                started = time.time()
                label = (f"{Path(checkpoint).name} step {generator.trained_steps}, w={guidance:g}, DDIM {steps}"
                         + (", no style" if args.no_style else ""))
                for finished in (False, True) if args.finished else (False,):
                    options = SamplingOptions(steps=steps, guidance=guidance, seed=args.seed)  # same noise both times
                    dances = generate_window_dances(generator, windows, options, not args.no_style, finished,
                                                    args.foot_lock)
                    print(table_row(label + (", finished" if finished else ""), score(dances, train))
                          + f" <!-- {time.time() - started:.0f} s -->", flush=True)


if __name__ == "__main__":
    main()
