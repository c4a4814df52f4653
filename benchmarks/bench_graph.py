"""How fast and how big is ChoreoGraph generation on this CPU?

    python benchmarks/bench_graph.py [--top-k 64 128 256 512] [--seconds 10 60 300] [--memory-minutes 1 5 10]

1. Speed: seconds to dance 10 s, 60 s and 5 min of music (the example loop tiled) for each K,
   with the bundled models and repertoire; the log-mel analysis is timed on its own column (the
   35-d feature analysis every command runs first is not included, as in bench_sgmd). Beside it,
   the same dance without the repeat cost, timed in the same run, and the ratio of the two.
2. Memory: peak RSS of a whole `choreo graph` run (fresh process, default settings) per song length.
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
from choreo.music.mel import music_log_mel
from choreo_graph import DEFAULT_CHECKPOINT, DEFAULT_REPERTOIRE

from common import TARGET_SECONDS, cli_peak_rss, write_song


def speed(generator: Generator, top_ks: list[int], durations: list[float], folder: Path) -> None:
    print(f"\n## Speed ({torch.get_num_threads()} threads, repertoire of {len(generator.repertoire)} clips)\n")
    print("| song | K | log-mel (s) | dance (s) | total (s) | x 3 s target (60 s song) | without repeat cost (s) | ratio |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for seconds in durations:
        music = Music.from_file(write_song(folder, seconds))
        started = time.perf_counter()
        music_log_mel(music)
        mel_seconds = time.perf_counter() - started
        for top_k in top_ks:
            total = timed(generator, {"top_k": top_k}, music)
            plain = timed(generator, {"top_k": top_k, "repeat_cost": 0.0}, music)
            ratio = f"{total / TARGET_SECONDS:.2f}" if seconds == 60 else "-"
            print(f"| {seconds:g} s | {top_k} | {mel_seconds:.2f} | {total - mel_seconds:.2f} | {total:.2f} | {ratio} "
                  f"| {plain:.2f} | {total / plain:.2f} |", flush=True)


def timed(generator: Generator, options: dict, music: Music, repeats: int = 2) -> float:
    """Best of ``repeats`` runs (the first run in a process also pays one-off start-up)."""
    best = float("inf")
    for _ in range(repeats):
        started = time.perf_counter()
        generator.generate(GenerationRequest(music, options=options))
        best = min(best, time.perf_counter() - started)
    return best


def memory(minutes: list[float], folder: Path) -> None:
    print("\n## Peak memory of `choreo graph` (fresh process, default settings)\n")
    print("| song | peak RSS (MiB) | wall (s) |")
    print("| --- | ---: | ---: |")
    for seconds in (60.0 * m for m in minutes):
        rss, wall = cli_peak_rss(["graph", write_song(folder, seconds), "-o", folder / "out.npz"])
        print(f"| {seconds / 60:g} min | {rss:.0f} | {wall:.1f} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkpoint", type=Path, default=DEFAULT_CHECKPOINT)
    parser.add_argument("--repertoire", type=Path, default=DEFAULT_REPERTOIRE)
    parser.add_argument("--top-k", type=int, nargs="+", default=[64, 128, 256, 512])
    parser.add_argument("--seconds", type=float, nargs="+", default=[10, 60, 300])
    parser.add_argument("--memory-minutes", type=float, nargs="*", default=[1, 10])
    args = parser.parse_args()
    generator = load_backend("graph", args.checkpoint, repertoire=args.repertoire)
    with tempfile.TemporaryDirectory() as folder:
        speed(generator, args.top_k, args.seconds, Path(folder))
        if args.memory_minutes:
            memory(args.memory_minutes, Path(folder))


if __name__ == "__main__":
    main()
