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
Since the second session of 2026-12-03 SGMD's chroma is choreo's own (choreo.music.chroma): the
"as before" row of `generate` also pays librosa's first chroma_cens and the sympy import that a
random draw on torch's meta device brought (SGMD's weight check, fixed the same day). Since
2026-12-04 the backend loaded on a thread while the song was analysed, saving 2-5 %; it was removed
the same day (the load now follows the analysis). The "loaded first" rows import torch and that
backend's module before the command runs, as the code before the thread did. Last, a folder of
20 songs in one call against the sum of their sampling times.
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
CHROMA = ("import numpy, librosa; "  # what SGMD's features paid until choreo.music.chroma (2026-12-03)
          "librosa.feature.chroma_cens(y=numpy.random.rand(30720).astype('float32'), sr=15360); ")
META_DRAW = "import torch; torch.empty(1, device='meta').normal_(); "  # what SGMD's weight check imported until 2026-12-03 (sympy)
LOADED_FIRST = "import torch, choreo_{}.generator; "  # what a sequential load paid before the analysis, per backend
BATCH_SONGS = 20
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
            ("  loaded first", ["generate", song, "-o", dance], LOADED_FIRST.format("sgmd")),
            ("  as before", ["generate", song, "-o", dance], AS_BEFORE + CHROMA + META_DRAW),
            ("choreo graph 60 s song", ["graph", song, "-o", dance], ""),
            ("  loaded first", ["graph", song, "-o", dance], LOADED_FIRST.format("graph")),
            ("  as before", ["graph", song, "-o", dance], AS_BEFORE + TIMBRE),
        ]
        print("| command | wall (s) | CPU (s) | wall / command's | CPU / command's |")
        print("| --- | ---: | ---: | ---: | ---: |")
        command = None
        for name, case_args, imports in cases:
            wall, cpu = measure(case_args, args.repeats, imports)
            ratios = f"{wall / command[0]:.2f} | {cpu / command[1]:.2f}" if imports and command else " | "
            print(f"| {name} | {wall:.2f} | {cpu:.2f} | {ratios} |", flush=True)
            if not imports:
                command = wall, cpu
        batch_against_sampling(Path(folder))


def batch_against_sampling(folder: Path) -> None:
    """A folder of songs danced by one `choreo generate --out-dir` call, against the sum of the
    seconds SGMD spends sampling those songs' dances (measured in this process, model loaded
    once, each song analysed beforehand): what a batch pays beyond the sampling itself."""
    from choreo import load_backend
    from choreo.generator import GenerationRequest
    from choreo.music import Music
    from choreo.threads import use_threads

    songs = folder / "batch"
    songs.mkdir()
    paths = [write_song(songs, 20.0 + i) for i in range(BATCH_SONGS)]  # 20-39 s, one file each
    (folder / "out").mkdir()
    wall, cpu = run_once(["generate", *paths, "--out-dir", folder / "out"])
    generator, sampling = load_backend("sgmd"), 0.0  # the bundled model
    generator.generate(GenerationRequest(Music.from_file(paths[0]), seed=0))  # warm-up
    for path in paths:
        request = GenerationRequest(Music.from_file(path), seed=0)
        use_threads()  # as the CLI chooses them before each dance
        started = time.perf_counter()
        generator.generate(request)
        sampling += time.perf_counter() - started
    print(f"\n{BATCH_SONGS} songs ({sum(20.0 + i for i in range(BATCH_SONGS)) / 60:.1f} min of music) in one "
          f"`choreo generate --out-dir` call: {wall:.1f} s wall ({cpu:.1f} s CPU); SGMD's sampling of the same "
          f"songs: {sampling:.1f} s; ratio {wall / sampling:.2f} (issue 37: at most 1.15)")


if __name__ == "__main__":
    main()
