"""Score SGMD checkpoints on the M2D test split against the train split (the reference row's setup).

    python scripts/evaluate_sgmd.py CHECKPOINT [CHECKPOINT ...] [--guidance 1 2] [--steps 20 50] [--no-style] [--finished]
    python scripts/evaluate_sgmd.py CHECKPOINT --by-genre   # also one row per genre, real motion beside it

One 5 s dance per test window (2.5 s stride), generated from that window's music and the clip's
genre; one markdown row per checkpoint x guidance x steps, beside the reference row's columns.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from choreo.datasets import TEST, TRAIN, load_dataset, select_split
from choreo import load_backend
from choreo.metrics.genre import GenreClassifier
from choreo_sgmd import MUSIC_GUIDANCE
from choreo.metrics.stepping import pace_and_feet_by_genre
from choreo.metrics.protocol import TABLE_HEADER, ScoringSet, score, score_generator, scoring_windows, table_row, windows_as_dances

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoints", nargs="+")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--guidance", type=float, nargs="+", default=[MUSIC_GUIDANCE],
                        help=f"guidance weights on the music (default {MUSIC_GUIDANCE:g}, the CLI's)")
    parser.add_argument("--steps", type=int, nargs="+", default=[50])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--intervals", nargs="+", default=["auto"],
                        help="noise-level intervals LOW:HIGH (t/T) where music guidance applies, e.g. 0.3:1 "
                             "(auto: the sampler's default)")
    parser.add_argument("--style-intervals", nargs="+", default=["0:1"],
                        help="noise-level intervals LOW:HIGH (t/T) where style guidance applies")
    parser.add_argument("--style-guidance", type=float, nargs="+", default=[None],
                        help="guidance weights on the style (1: none; default: the sampler's)")
    parser.add_argument("--no-style", action="store_true")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--finished", action="store_true",
                        help="also score each dance after the beat lock (choreo.finishing), side by side")
    parser.add_argument("--no-footsteps", action="store_true", help="with --finished: also score without footsteps (choreo.finishing.footsteps)")
    parser.add_argument("--foot-lock", action="store_true", help="with --finished: the foot lock too")
    parser.add_argument("--by-genre", action="store_true",
                        help="also score each genre's windows against the train windows of that genre")
    args = parser.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)
    clips = load_dataset(args.data)
    test_clips, train_clips = select_split(clips, TEST), select_split(clips, TRAIN)
    scoring = ScoringSet.from_clips(clips)
    windows, train_windows = scoring.windows, scoring_windows(train_clips)
    classifier = GenreClassifier.fit([w.motion.joint_positions() for w in train_windows], [w.genre for w in train_windows])
    genres = [w.genre for w in windows]
    real = windows_as_dances(test_clips)
    print(TABLE_HEADER.format(label="model"), flush=True)
    if args.by_genre:
        print_by_genre("real test motion", windows, real, train_clips)
    for checkpoint in args.checkpoints:
        generator = load_backend("sgmd", checkpoint)
        for guidance in args.guidance:
            for steps, interval, style_w, style_interval in [(s, i, g, si) for s in args.steps for i in args.intervals
                                                             for g in args.style_guidance for si in args.style_intervals]:
                started = time.time()
                bounds = None if interval == "auto" else tuple(float(b) for b in interval.split(":"))
                style_bounds = tuple(float(b) for b in style_interval.split(":"))
                label = (f"{Path(checkpoint).name} step {generator.trained_steps}, w={guidance:g}, DDIM {steps}"
                         + (f", guided on t/T {interval}" if bounds is not None else "")
                         + (f", style w={style_w:g}" if style_w not in (None, 1.0) else "")
                         + (f" on t/T {style_interval}" if style_w != 1.0 and style_bounds != (0.0, 1.0) else "")
                         + (", no style" if args.no_style else ""))
                for finished, footsteps in [(False, False), *([(True, False)] if args.finished and args.no_footsteps else []),
                                            *([(True, True)] if args.finished else [])]:
                    options = {"steps": steps, "guidance": guidance, "guidance_interval": bounds,
                               "style_guidance_interval": style_bounds}  # same noise both times
                    if style_w is not None:
                        options["style_guidance"] = style_w
                    report, dances = score_generator(generator, scoring, with_style=not args.no_style, seed=args.seed,
                                                     options=options, finished=finished, foot_lock=args.foot_lock,
                                                     footsteps=footsteps)
                    recognised = classifier.agreement([d.positions for d in dances], genres)
                    print(table_row(label + (", finished" if finished else "") + (", no footsteps" if finished and not footsteps else ""), report)
                          + f" <!-- genre recognised {100 * recognised:.1f} %, {pace_and_feet_by_genre([d.positions for d in dances], [d.positions for d in real], genres, 30.0)}, "
                          f"{time.time() - started:.0f} s -->", flush=True)
                    if args.by_genre:
                        print_by_genre(label + (", finished" if finished else ""), windows, dances, train_clips)


def print_by_genre(label: str, windows, dances, train_clips) -> None:
    """One row per genre: that genre's windows scored against the train windows of the same genre
    (is the gap to real motion everywhere, or in some genres?)."""
    for genre in sorted({w.genre for w in windows}):
        mine = [d for w, d in zip(windows, dances) if w.genre == genre]
        reference = windows_as_dances([c for c in train_clips if c.genre == genre])
        if len(mine) > 1 and len(reference) > 1:
            print(table_row(f"{label} [{genre}]", score(mine, reference)), flush=True)


if __name__ == "__main__":
    main()
