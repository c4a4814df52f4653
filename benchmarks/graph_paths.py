"""The graph backend following a root path on whole songs: how far its walk strays from the path
before the displacement map bends it on, and what the bending costs the feet, with the path
cost off and on, side by side.

    python benchmarks/graph_paths.py [--songs 8] [--seconds 60] [--costs 0 4 16 64]

Songs: the LMMS demo songs (benchmarks/outside_songs.py; their cached renders are used when LMMS
itself is not installed), else the example loop. Paths, stretched over each song: a circle of
2 m radius, a 4 m line walked there and back, a figure of eight 3 m across.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from choreo import load_backend
from choreo.constraints import Constraints
from choreo.generator import GenerationRequest
from choreo.metrics.pfc import physical_foot_contact
from choreo.music import Music

from common import EXAMPLE
from outside_songs import CACHE, outside_songs


WINDOW = 150  # PFC is scored on 5 s windows, as in every quality table here
TOES = (10, 11)  # SMPL l_foot, r_foot
SKATE_HEIGHT, SKATE_STEP = 0.05, 0.025  # metres: on the floor, and sliding (a common foot-skating rule)


def paths(num_frames: int) -> dict[str, np.ndarray]:
    turn = np.linspace(0, 2 * np.pi, num_frames)
    return {
        "circle 2 m": 2.0 * np.stack([np.cos(turn) - 1, np.sin(turn)], -1),
        "line 4 m, there and back": np.stack([4.0 * np.sin(turn / 2), np.zeros(num_frames)], -1),
        "figure of eight": 1.5 * np.stack([np.sin(turn), np.sin(turn) * np.cos(turn)], -1),
    }


def windowed_pfc(positions: np.ndarray) -> float:
    return physical_foot_contact([positions[i : i + WINDOW] for i in range(0, len(positions) - WINDOW + 1, WINDOW)])


def skating_ratio(positions: np.ndarray) -> float:
    """Share of frames where a foot on the floor (toe within 5 cm of the dance's lowest toe
    height) slides more than 2.5 cm to the next frame: the bending's cost to the feet. (PFC cannot
    show it: it weighs sliding by the root's acceleration, which a smooth path lowers.)"""
    toes = positions[:, list(TOES)]
    grounded = toes[:-1, :, 1] < toes[:, :, 1].min() + SKATE_HEIGHT
    slide = np.linalg.norm(np.diff(toes[:, :, [0, 2]], axis=0), axis=-1) > SKATE_STEP
    return float((grounded & slide).any(1).mean())


def measured(dance, walk_error: float, seconds: float) -> tuple[float, ...]:
    positions = dance.joint_positions()
    return walk_error, windowed_pfc(positions), skating_ratio(positions), seconds


def songs(count: int) -> list:
    found = [s.path for s in outside_songs()] or sorted(CACHE.glob("*.wav"))
    return found[:count] or [EXAMPLE]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--songs", type=int, default=8)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--costs", type=float, nargs="+", default=[0.0, 4.0, 16.0, 64.0])
    args = parser.parse_args()
    graph = load_backend("graph")
    results = {}  # (path, cost) -> [(walk error, PFC, seconds)]
    chosen = songs(args.songs)
    for song in chosen:
        music = Music.from_file(song, end=args.seconds, log_mel=True, timbre=False)
        free = graph.generate(GenerationRequest(music))
        results.setdefault(("no path (reference)", None), []).append(measured(free, np.nan, np.nan))
        for name, path in paths(music.num_frames).items():
            constraints = Constraints.none(music.num_frames, music.fps).fix_root_path(path)
            for cost in args.costs:
                started = time.perf_counter()
                dance = graph.generate(GenerationRequest(music, constraints=constraints, options={"path_cost": cost}))
                elapsed = time.perf_counter() - started
                results.setdefault((name, cost), []).append(measured(dance, dance.metadata["walk_root_error_m"], elapsed))
        print(f"  {song.name}", flush=True)
    print(f"\n{len(chosen)} songs, first {args.seconds:g} s each; mean over songs (walk error: the walk's own "
          "distance from the path before bending)\n")
    print("| path | path cost | walk error (m) | PFC (5 s windows) | foot skating (share of frames) | seconds |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for (name, cost), rows in results.items():
        error, score, skating, seconds = np.mean(rows, axis=0)
        print(f"| {name} | {'-' if cost is None else f'{cost:g}'} | {error:.2f} | {score:.2f} | {skating:.3f} | {seconds:.1f} |")
    for cost in args.costs[1:]:
        ratio = np.mean([np.mean([r[0] for r in results[(n, cost)]]) / np.mean([r[0] for r in results[(n, args.costs[0])]])
                         for n in paths(2)])
        print(f"\nwalk error at path cost {cost:g} / at {args.costs[0]:g}: {ratio:.2f} (mean over the paths)")


if __name__ == "__main__":
    main()
