"""Score ChoreoGraph on the M2D test split with a repertoire cut from the M2D train split.

    python scripts/evaluate_graph.py [CHECKPOINT] [--top-k 512] [--variants full no-retempo motion-graph no-repeat-cost] [--finished]
                                     [--stride 2] [--save-repertoire m2d_train.npz] [--whole-songs]

One 5 s dance per test window (2.5 s stride, as the reference row), danced from that window's
music alone; one markdown row per variant: the full method, the paper's two ablations (without
re-tempo: each clip's middle 4 s unwarped; motion graph: first node of each segment only) and
ours (no repeat cost; raw-warp: the DTW warps played unsmoothed, as the paper; smooth-4 / 16 / 32: other
smoothings; greedy: the paper's deterministic walk, no take variation; vary-0.3: three times the variation).
``--genre-style`` gives each window's genre as the style, so the graph dances that genre's clips only.
``--whole-songs`` also dances every test song whole and counts the seconds that replay what was
danced in the 30 s before, with and without the repeat cost.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from choreo import load_backend
from choreo.datasets import TEST, TRAIN, load_dataset, select_split
from choreo.generator import Generator
from choreo.metrics.protocol import TABLE_HEADER, ScoringSet, score_generator, table_row, windows_as_dances
from choreo.metrics.stepping import pace_and_feet_by_genre
from choreo_graph import (DEFAULT_CHECKPOINT, GraphConfig, dataset_generator, music_windows, replayed_nodes,
                          select_candidates)

REPO = Path(__file__).resolve().parents[1]
VARIANTS = {"full": {}, "no-retempo": {"retempo": False}, "motion-graph": {"dynamic": False},
            "no-repeat-cost": {"repeat_cost": 0.0}, "raw-warp": {"warp_smoothing": 0.0},
            "smooth-4": {"warp_smoothing": 4.0}, "smooth-16": {"warp_smoothing": 16.0},
            "smooth-32": {"warp_smoothing": 32.0}, "greedy": {"take_variation": 0.0}, "vary-0.3": {"take_variation": 0.3}}


def selector_genre_precision(generator: Generator, windows, mels, ks=(1, 64)) -> str:
    """How often the style-based selector's picks for a window's first 4 s share the clip's genre."""
    model, repertoire = generator.model, generator.repertoire
    chance = np.mean([np.mean(repertoire.genres == w.genre) for w in windows])
    shares = {k: [] for k in ks}
    for w in windows:
        music = music_windows(model, mels[w.clip][w.start_frame : w.start_frame + len(w.features)], range(1))
        for k in ks:
            picks = select_candidates(music, repertoire, k, model.config.style)
            shares[k].append(np.mean(repertoire.genres[picks] == w.genre))
    found = ", ".join(f"K={k}: {100 * np.mean(v):.1f} %" for k, v in shares.items())
    return f"selector picks of the test clip's genre: {found} (clips drawn at random: {100 * chance:.1f} %)"


def whole_song_replays(generator: Generator, mels: dict[str, np.ndarray], top_k: int) -> str:
    """Seconds of whole test songs that replay source frames danced in the 30 s before."""
    found = []
    for label, cost in (("repeat cost", GraphConfig.repeat_cost), ("no repeat cost", 0.0)):
        config = GraphConfig(top_k=top_k, repeat_cost=cost)
        paths = [generator.walk(mel, config) for mel in mels.values()]
        replayed = sum(replayed_nodes(p, generator.repertoire, config.repeat_memory) for p in paths)
        seconds = sum(len(p) for p in paths)
        clips = np.mean([len({n.clip for n in p}) / len(p) for p in paths])
        found.append(f"{label}: {replayed}/{seconds} s replayed ({100 * replayed / seconds:.1f} %), "
                     f"{clips:.2f} different clips per second")
    return f"whole test songs, K={top_k}: " + "; ".join(found)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint", nargs="?", default=str(DEFAULT_CHECKPOINT))
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--top-k", type=int, nargs="+", default=[512])
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--stride", type=float, default=2.0, help="seconds between repertoire clips")
    parser.add_argument("--save-repertoire", default=None)
    parser.add_argument("--repertoire", default=None, help="use this repertoire instead of cutting the train split")
    parser.add_argument("--whole-songs", action="store_true", help="count replayed seconds on whole test songs")
    parser.add_argument("--finished", action="store_true",
                        help="also score each dance after the beat lock (choreo.finishing), side by side")
    parser.add_argument("--foot-lock", action="store_true", help="with --finished: the foot lock too")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--genre-style", action="store_true",
                        help="give each window's genre as the style (the graph then dances only that genre's clips)")
    parser.add_argument("--no-footsteps", action="store_true", help="with --finished: also score without footsteps (choreo.finishing.footsteps)")
    args = parser.parse_args()

    clips = load_dataset(args.data)
    train = select_split(clips, TRAIN)
    started = time.perf_counter()  # the repertoire's time (it now includes loading the models: a fraction of a second)
    if args.repertoire:
        generator = load_backend("graph", args.checkpoint, repertoire=args.repertoire)
    else:
        generator = dataset_generator(train, round(args.stride * 30), "M2D train", args.checkpoint)
    repertoire = generator.repertoire
    print(f"repertoire: {len(repertoire)} clips of 8 s ({repertoire.source}, {time.perf_counter() - started:.1f} s)",
          flush=True)
    if args.save_repertoire:  # scored as read back from the file (its rotations are stored as float16)
        repertoire.save(args.save_repertoire)
        generator = load_backend("graph", args.checkpoint, repertoire=args.save_repertoire)

    scoring = ScoringSet.from_clips(clips)
    mels = scoring.log_mels()
    genres = [w.genre for w in scoring.windows]
    real = [d.positions for d in windows_as_dances(select_split(clips, TEST))]
    print(selector_genre_precision(generator, scoring.windows, mels), flush=True)
    if args.whole_songs:
        print(whole_song_replays(generator, mels, args.top_k[0]), flush=True)
    print(TABLE_HEADER.format(label="ChoreoGraph variant"), flush=True)
    for top_k in args.top_k:
        for variant in args.variants:
            options = {"top_k": top_k, **VARIANTS[variant]}
            for finished, footsteps in [(False, False), *([(True, False)] if args.finished and args.no_footsteps else []),
                                        *([(True, True)] if args.finished else [])]:
                started = time.perf_counter()
                report, dances = score_generator(generator, scoring, with_style=args.genre_style, seed=args.seed, options=options, finished=finished,
                                            foot_lock=args.foot_lock, footsteps=footsteps)
                label = (f"{variant}, K={top_k}{', finished' if finished else ''}{', no footsteps' if finished and not footsteps else ''} "
                         f"({time.perf_counter() - started:.0f} s)")
                print(table_row(label, report)
                      + f" <!-- {pace_and_feet_by_genre([d.positions for d in dances], real, genres, 30.0)} -->", flush=True)


if __name__ == "__main__":
    main()
