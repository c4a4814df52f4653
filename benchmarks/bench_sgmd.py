"""How fast, how big and how good is SGMD generation on this CPU?

    python benchmarks/bench_sgmd.py [--checkpoint PATH] [--steps 5 10 20 50] [--memory-minutes 1 10 60] [--no-quality]

1. Speed: seconds and network evaluations to dance 60 s of music (the example loop tiled to
   60 s), per number of DDIM steps, without guidance, with guidance on the music, and on music and
   style, against the 3 s target.
2. Memory: peak RSS of a whole `choreo generate` run (fresh process, default settings) for songs
   of 1 and 10 minutes (and an hour with --memory-minutes 1 10 60), side by side.
3. Quality against the number of steps: the M2D test windows scored like the reference row, for
   each step count (skipped without ../shared/data/m2d or with --no-quality).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import torch

from choreo import load_backend
from choreo.generator import GenerationRequest, Generator
from choreo.music import Music
from choreo_sgmd import DEFAULT_CHECKPOINT

from common import REPO, TARGET_SECONDS, cli_peak_rss, song_of, write_song


GUIDANCE_PAIRS = ((1.0, 1.0), (2.0, 1.0), (2.0, 2.0))  # (music, style): none, music only, both


def speed(generator: Generator, steps_list: list[int]) -> None:
    audio, rate = song_of(60.0)
    started = time.perf_counter()
    music = Music.from_array(audio, rate)
    analysis = time.perf_counter() - started
    print(f"\n## Speed: 60 s of music, {torch.get_num_threads()} threads (music analysis {analysis:.2f} s, "
          "not included below)\n")
    print("| sampler | steps | guidance (music, style) | network evaluations per window | seconds | x 3 s target |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    generator.generate(GenerationRequest(music, style="cha-cha", options={"steps": 2}))  # warm-up
    for steps in steps_list:
        for guidance, style_guidance in GUIDANCE_PAIRS:
            options = {"steps": steps, "guidance": guidance, "style_guidance": style_guidance}
            started = time.perf_counter()
            motion = generator.generate(GenerationRequest(music, style="cha-cha", options=options))
            seconds = time.perf_counter() - started
            print(f"| DDIM | {steps} | {guidance:g}, {style_guidance:g} | {motion.metadata['network_evaluations']} | "
                  f"{seconds:.2f} | {seconds / TARGET_SECONDS:.2f} |", flush=True)


def memory(minutes: list[float]) -> None:
    print("\n## Peak memory of `choreo generate` (fresh process, default settings)\n")
    print("| song | peak RSS (MiB) | wall (s) |")
    print("| --- | ---: | ---: |")
    with tempfile.TemporaryDirectory() as folder:
        for seconds in (60.0 * m for m in minutes):
            song = write_song(Path(folder), seconds)
            rss, wall = cli_peak_rss(["generate", song, "-o", Path(folder) / "out.npz", "--style", "cha-cha"])
            print(f"| {seconds / 60:g} min | {rss:.0f} | {wall:.1f} |", flush=True)


def quality(checkpoint: Path, steps_list: list[int]) -> None:
    from choreo.datasets import load_dataset
    from choreo.metrics.protocol import TABLE_HEADER, ScoringSet, score, score_generator, table_row, windows_as_dances

    data = REPO.parent / "shared" / "data" / "m2d"
    if not data.is_dir():
        print(f"\n(quality skipped: {data} not found)")
        return
    generator = load_backend("sgmd", checkpoint)
    scoring = ScoringSet.from_clips(load_dataset(data))
    print("\n## Quality against the number of DDIM steps (M2D test windows, guidance 2)\n")
    print(TABLE_HEADER.format(label="steps"))
    print(table_row("real test motion", score(windows_as_dances(scoring.clips), scoring.reference)))
    for steps in steps_list:
        report, _ = score_generator(generator, scoring, options={"steps": steps, "guidance": 2.0})
        print(table_row(f"DDIM {steps}", report), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkpoint", type=Path, default=DEFAULT_CHECKPOINT)
    parser.add_argument("--steps", type=int, nargs="+", default=[5, 10, 20, 50])
    parser.add_argument("--no-quality", action="store_true")
    parser.add_argument("--memory-minutes", type=float, nargs="*", default=[1, 10],
                        help="song lengths for the peak-RSS runs (none to skip), e.g. 1 10 60")
    args = parser.parse_args()
    generator = load_backend("sgmd", args.checkpoint)
    print(f"checkpoint {args.checkpoint.name}: {generator.trained_steps} training steps")
    speed(generator, args.steps)
    if args.memory_minutes:
        memory(args.memory_minutes)
    if not args.no_quality:
        quality(args.checkpoint, args.steps)


if __name__ == "__main__":
    main()
