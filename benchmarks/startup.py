"""Start-up: what a fresh `choreo` process costs before and around the dance, side by side.

    python benchmarks/startup.py [--repeats 3]

Each row is a fresh process (median of ``--repeats``), timed as wall seconds and as CPU seconds
(user + system of the child: less sensitive to other load on the machine than wall time). The
"as before" rows run the same command in a process that first imports the two librosa modules the
music analysis used to load (``librosa.beat``, whose numba kernel is compiled in every process,
and ``librosa.decompose``, which imports scikit-learn); their ratio to the row above is what
choreo's own beat tracker and HPSS (``choreo.music.beats``) saved. Since the third session of
2026-12-02 commands that need only the rhythm (``info song``, ``render``, ``eval``) and ChoreoGraph
analyse songs without MFCC and chroma and never import librosa; their "as before" rows first pay
for what every analysis used to: librosa's chroma (a constant-Q transform) and mel spectrogram.
Since 2026-12-03 reading a motion file never imports torch (rotations and forward kinematics are
written against the array API); the "as before" row of `info dance.bvh` imports torch first.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import write_song

CLI = "import sys; {imports}from choreo.cli import main; sys.exit(main(sys.argv[1:]))"
AS_BEFORE = "import librosa.beat, librosa.decompose; "
TIMBRE = ("import numpy, librosa; y = numpy.random.rand(30720).astype('float32'); "
          "librosa.feature.chroma_cens(y=y, sr=15360); librosa.feature.melspectrogram(y=y, sr=15360); "
          "librosa.onset.onset_detect(onset_envelope=numpy.random.rand(64)); ")


def run_once(args: list[str], imports: str = "") -> tuple[float, float]:
    """(wall s, CPU s) of one `choreo ARGS` in a fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    result = subprocess.run([sys.executable, "-c", CLI.format(imports=imports), *map(str, args)],
                            capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode != 0:
        raise SystemExit(f"choreo {' '.join(map(str, args))} failed: {result.stderr.strip()[-300:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def measure(args: list[str], repeats: int, imports: str = "") -> tuple[float, float]:
    runs = [run_once(args, imports) for _ in range(repeats)]
    return statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        song = write_song(Path(folder), 60.0)
        dance = Path(folder) / "dance.bvh"
        run_once(["generate", song, "-o", dance])  # warm the file cache and write a dance for `info`
        cases = [
            ("choreo --help", ["--help"], ""),
            ("choreo info dance.bvh", ["info", dance], ""),
            ("  as before", ["info", dance], "import torch; "),
            ("choreo info song.wav (music analysis)", ["info", song], ""),
            ("  as before", ["info", song], AS_BEFORE + TIMBRE),
            ("choreo generate 60 s song", ["generate", song, "-o", dance], ""),
            ("  as before", ["generate", song, "-o", dance], AS_BEFORE),
            ("choreo graph 60 s song", ["graph", song, "-o", dance], ""),
            ("  as before", ["graph", song, "-o", dance], AS_BEFORE + TIMBRE),
        ]
        print("| command | wall (s) | CPU (s) | CPU / row above |")
        print("| --- | ---: | ---: | ---: |")
        previous = None
        for name, case_args, imports in cases:
            wall, cpu = measure(case_args, args.repeats, imports)
            ratio = f"{cpu / previous:.2f}" if imports and previous else ""
            print(f"| {name} | {wall:.2f} | {cpu:.2f} | {ratio} |", flush=True)
            previous = cpu


if __name__ == "__main__":
    main()
