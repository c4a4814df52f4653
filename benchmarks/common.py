"""What every benchmark here shares: songs of any length and the peak memory of a CLI run."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import soundfile as sf

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "drum_and_bass_174bpm.wav"
TARGET_SECONDS = 3.0  # both generators: 60 s of dance in at most 3 s on the 2-core CPU

# VmHWM, the process's own high-water mark: getrusage's ru_maxrss would carry over the parent's
# peak through fork and exec, so a benchmark holding a dataset would report its own size.
RSS_PROBE = """
import re, sys
from choreo.cli import main
code = main(sys.argv[1:])
status = open("/proc/self/status").read()
print(code, int(re.search(r"VmHWM:\\s+(\\d+) kB", status).group(1)) / 1024)
"""


def song_of(seconds: float) -> tuple[np.ndarray, int]:
    """The example loop tiled to ``seconds``."""
    audio, rate = sf.read(EXAMPLE, dtype="float32")
    repeats = int(np.ceil(seconds * rate / len(audio)))
    return np.tile(audio, repeats)[: int(seconds * rate)], rate


def write_song(folder: Path, seconds: float) -> Path:
    song = Path(folder) / f"song{seconds:.0f}.wav"
    sf.write(song, *song_of(seconds))
    return song


def cli_peak_rss(args: list[str]) -> tuple[float, float]:
    """(peak RSS in MiB, wall seconds) of one `choreo ARGS...` run in a fresh process."""
    started = time.perf_counter()
    result = subprocess.run([sys.executable, "-c", RSS_PROBE, *map(str, args)], capture_output=True, text=True)
    wall = time.perf_counter() - started
    code, rss = result.stdout.split()[-2:]
    if code != "0":
        raise SystemExit(f"choreo {' '.join(map(str, args))} failed: {result.stderr}")
    return float(rss), wall
