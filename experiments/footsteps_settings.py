"""Footsteps' settings scored on one set of generated test windows (docs/results.md, "Feet").

    python -m experiments.footsteps_settings [CHECKPOINT] [--generator graph] [--seed 0] --settings 0.06:0.25:0.04:0.6 0.12:0.3:0.04:1

The bundled SGMD model (or CHECKPOINT) dances every M2D test window once (seed 0, DDIM 10, the
window's genre as the style), or the bundled ChoreoGraph does (no style, as scripts/evaluate_graph.py
scores it); the same dances are finished as `choreo generate` finishes them (speed limit,
footsteps, beat lock, speed limit) once per setting of footsteps (trigger m : swing s :
lift m : strength), and once without footsteps. Each row ends with the median root speed and the
foot-root correlation per genre (real in brackets).
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

from choreo import load_backend
from choreo.datasets import load_dataset
from choreo.finishing import FootstepsConfig, finish
from choreo.pipeline import Finishing
from choreo.metrics.evaluate import Dance
from choreo.datasets import TEST, select_split
from choreo.metrics.protocol import (TABLE_HEADER, ScoringSet, generate_window_motions, music_beats, score, table_row,
                                     windows_as_dances)
from choreo.metrics.stepping import pace_and_feet_by_genre

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint", nargs="?", default=None)
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--generator", choices=["sgmd", "graph"], default="sgmd")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--settings", nargs="+", default=["0.06:0.25:0.04:0.6"])
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    clips = load_dataset(args.data)
    scoring = ScoringSet.from_clips(clips)
    backend = load_backend(args.generator, args.checkpoint)
    sgmd = args.generator == "sgmd"
    motions = generate_window_motions(backend, scoring.windows, with_style=sgmd, seed=args.seed,
                                      options={"steps": 10} if sgmd else {},
                                      log_mels=scoring.log_mels() if backend.listens_to_spectrum else None)
    genres = [w.genre for w in scoring.windows]
    real = [d.positions for d in windows_as_dances(select_split(clips, TEST))]

    def row(label: str, dances) -> None:
        as_dances = [Dance(w.clip, m.joint_positions(), music_beats(w.features)) for w, m in zip(scoring.windows, dances)]
        print(table_row(label, score(as_dances, scoring.reference))
              + f" <!-- {pace_and_feet_by_genre([d.positions for d in as_dances], real, genres, 30.0)} -->", flush=True)

    print(TABLE_HEADER.format(label="setting"))
    row("none (finished)", [finish(m, music_beats(w.features), Finishing(footsteps=False)) for w, m in zip(scoring.windows, motions)])
    for setting in args.settings:
        trigger, swing, lift, strength = map(float, setting.split(":"))
        config = FootstepsConfig(trigger=trigger, swing_seconds=swing, lift=lift, strength=strength)
        started = time.perf_counter()
        stepped = [finish(m, music_beats(w.features), Finishing(configs={"footsteps": config})) for w, m in zip(scoring.windows, motions)]
        row(f"{setting} ({time.perf_counter() - started:.1f} s)", stepped)


if __name__ == "__main__":
    main()
