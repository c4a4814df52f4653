"""Where a fresh `choreo generate` of a 60 s song spends its time, stage by stage, in one process.

    python benchmarks/generate_stages.py [--style cha-cha] [--repeats 2]

Each repeat is a fresh Python process that imports, loads, analyses, samples, finishes and writes
one after the other (no overlap, unlike the CLI, which loads the backend while it analyses: see
benchmarks/startup.py), printing the seconds of each stage: what a faster start would have to
remove, and what no runtime change can (the sampling).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

from common import write_song

STAGES = r'''
import sys, time
started = last = time.perf_counter()
def lap(name):
    global last
    now = time.perf_counter(); print(f"{name}\t{now - last:.3f}", flush=True); last = now
import numpy; lap("numpy")
import choreo.cli; lap("choreo's CLI")
import torch; lap("import torch")
from choreo.pipeline import load_backend
backend = load_backend("sgmd"); lap("backend (modules, weights)")
from choreo.music import Music
music = Music.from_file(sys.argv[1]); lap("music analysis")
from choreo.generator import GenerationRequest
motion = backend.generate(GenerationRequest(music, style=sys.argv[3] or None, seed=0)); lap("sampling")
from choreo.finishing import finish
motion = finish(motion, music.beat_frames); lap("finishing passes")
from choreo.formats import write_motion
write_motion(motion, sys.argv[2]); lap("writing the BVH")
print(f"total\t{time.perf_counter() - started:.3f}")
'''


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--style", default="")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        song = write_song(Path(folder), 60.0)
        runs = []
        for _ in range(args.repeats):
            done = subprocess.run([sys.executable, "-c", STAGES, str(song), str(Path(folder) / "d.bvh"), args.style],
                                  capture_output=True, text=True, check=True)
            runs.append([line.split("\t") for line in done.stdout.strip().splitlines()])
    print("| stage | " + " | ".join(f"run {i + 1} (s)" for i in range(len(runs))) + " |")
    print("| --- |" + " ---: |" * len(runs))
    for row in zip(*runs):
        print(f"| {row[0][0]} | " + " | ".join(cell[1] for cell in row) + " |")


if __name__ == "__main__":
    main()
