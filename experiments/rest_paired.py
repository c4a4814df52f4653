"""A song's whole-dance figures with and without the rest pass, on one render and one seed.

    python -m experiments.rest_paired EsoXLB-CPU.wav [--generator sgmd] [--styles cha-cha waltz] [--seed 0]

docs/results.md, "Finishing passes" (Rest): what standing still through a song's closing silence
does to the whole-song figures (scripts/evaluate_whole_songs.py's).
"""

from __future__ import annotations

import argparse

import choreo
from choreo.music import Music
from choreo.pipeline import Finishing

from choreo.metrics.songs import figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("song")
    parser.add_argument("--generator", default="sgmd")
    parser.add_argument("--styles", nargs="+", default=["cha-cha", "waltz"])
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    music = Music.from_file(args.song, log_mel=True, timbre=True)
    first, stop = music.audible
    print(f"music {first / music.fps:.1f}-{stop / music.fps:.1f} s of {music.duration:.1f} s")
    backend = choreo.load_backend(args.generator)
    for style in args.styles:
        for rest in (True, False):
            dance = choreo.dance(music, backend, style=style, seed=args.seed, finishing=Finishing(rest=rest))
            row = {key: round(float(value), 3) for key, value in figures(dance.joint_positions(), music).items()}
            print(args.generator, style, "rest" if rest else "no rest", row, flush=True)


if __name__ == "__main__":
    main()
