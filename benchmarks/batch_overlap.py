"""Does a batch gain by analysing the next song while this one samples? Side by side, one process.

    python benchmarks/batch_overlap.py [--songs 20]

Songs of 20 s, 21 s, ... (synthetic, benchmarks/common.py), the bundled SGMD model loaded once,
each song analysed, danced (sampling and finishing, `choreo.dance`) and written as the CLI's batch
does. Rows: the dances alone (songs analysed beforehand, 2 threads), then the batch sequential or
with the next song's analysis in a second thread, each with 2 or 1 sampling threads. Issue 37,
item 3 (2026-12-04: the overlap loses on two cores; docs/results.md, "Jobs side by side").
"""

from __future__ import annotations

import argparse
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import choreo
from choreo.formats import write_motion
from choreo.music import Music

from common import write_song


def batch(songs: list[Path], backend, out: Path, overlap: bool, threads: int) -> tuple[float, float]:
    """(wall seconds, seconds spent dancing) of one batch."""
    def analyse(song: Path) -> Music:
        return Music.from_file(song, timbre=backend.reads_timbre)

    dancing, started = 0.0, time.perf_counter()
    with ThreadPoolExecutor(1) as pool:
        ahead = pool.submit(analyse, songs[0]) if overlap else None
        for i, song in enumerate(songs):
            music = ahead.result() if overlap else analyse(song)
            if overlap and i + 1 < len(songs):
                ahead = pool.submit(analyse, songs[i + 1])
            begun = time.perf_counter()
            motion = choreo.dance(music, backend, threads=threads)
            dancing += time.perf_counter() - begun
            write_motion(motion, out / f"{song.stem}.npz")
    return time.perf_counter() - started, dancing


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--songs", type=int, default=20)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        songs = [write_song(folder, 20.0 + i) for i in range(args.songs)]
        backend = choreo.load_backend("sgmd")
        choreo.dance(Music.from_file(songs[0]), backend, threads=2)  # warm-up
        alone = 0.0
        for music in [Music.from_file(song, timbre=backend.reads_timbre) for song in songs]:
            begun = time.perf_counter()
            choreo.dance(music, backend, threads=2)
            alone += time.perf_counter() - begun
        print(f"{args.songs} songs; their dances alone (analysed beforehand, 2 threads): {alone:.1f} s\n")
        print("| batch | sampling threads | wall s | dancing s | wall / dances alone |\n| --- | ---: | ---: | ---: | ---: |")
        for overlap, threads in ((False, 2), (True, 2), (True, 1), (False, 1)):
            wall, dancing = batch(songs, backend, folder, overlap, threads)
            print(f"| {'next song analysed alongside' if overlap else 'sequential'} | {threads} | {wall:.1f} | "
                  f"{dancing:.1f} | {wall / alone:.2f} |", flush=True)


if __name__ == "__main__":
    main()
