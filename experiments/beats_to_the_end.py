"""How well a whole song's last minutes keep the beat, with the tracker's old trim and today's.

    python -m experiments.beats_to_the_end [--song EsoXLB-CPU.wav] [--bpm 128] [--start 150] [--end 224]

Until 2026-12-05 the default tracker took a song's quieter last minutes for a fade-out and heard no
beat there (LMMS's EsoXLB-CPU: none after 146 of its 236 s), so the beat lock left them alone
(docs/results.md, "Beat tracking"). Both generators dance the song (cha-cha, seeds 0-1) with the
old trim threshold (twice today's) and with today's, and the dances' motion beats between
``--start`` and ``--end`` are scored (BeatAlign) against the song's stated grid, not against what
the tracker hears.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import choreo
import choreo.music.beats as beats
from choreo.metrics import beat_align_score, motion_beats
from choreo.music import Music

SONG = Path.home() / ".cache/choreo/lmms-songs/EsoXLB-CPU.wav"  # rendered by benchmarks/outside_songs.py


def stated_grid_score(dance, bpm: float, start: float, end: float) -> float:
    """BeatAlign of the dance's motion beats in [start, end) s against beats every 60 / bpm s from 0."""
    first, last = int(start * dance.fps), int(end * dance.fps)
    found = motion_beats(dance.joint_positions())
    found = found[(found >= first) & (found < last)] - first
    grid = np.arange(0.0, end, 60.0 / bpm)
    grid = np.round(grid[grid >= start] * dance.fps).astype(int) - first
    return beat_align_score(grid, found)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--song", type=Path, default=SONG)
    parser.add_argument("--bpm", type=float, default=128.0, help="the song's stated tempo")
    parser.add_argument("--start", type=float, default=150.0)
    parser.add_argument("--end", type=float, default=224.0)
    args = parser.parse_args()
    today = beats._fade_threshold
    for generator in ("sgmd", "graph"):
        backend = choreo.load_backend(generator)
        for label, threshold in (("old trim", lambda local, found: 2 * today(local, found)), ("today's trim", today)):
            beats._fade_threshold = threshold
            music = Music.from_file(args.song)
            scores = [stated_grid_score(choreo.dance(music, backend, style="cha-cha", seed=seed), args.bpm,
                                        args.start, args.end) for seed in (0, 1)]
            print(f"{generator:5s} {label:12s} beats heard {len(music.beat_times):4d}, last at "
                  f"{music.beat_times[-1]:6.1f} s; BeatAlign {args.start:.0f}-{args.end:.0f} s against the stated "
                  f"grid, seeds 0-1: {' '.join(f'{s:.3f}' for s in scores)}", flush=True)
        beats._fade_threshold = today


if __name__ == "__main__":
    main()
