"""The step planner's settings scored on one set of generated test windows (docs/results.md, "Feet").

    python scripts/experiments/footsteps_settings.py [CHECKPOINT] --settings 0.06:0.25:0.04:0.6 0.12:0.3:0.04:1

The bundled SGMD model (or CHECKPOINT) dances every M2D test window once (seed 0, DDIM 10); each
dance is finished as `choreo generate` finished it before footsteps (speed limit, beat lock), then
each setting (trigger m : swing s : lift m : strength) plans steps on the same finished dances.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

from choreo import load_backend
from choreo.datasets import load_dataset
from choreo.finishing import StepConfig, finish, planted_steps
from choreo.metrics.evaluate import Dance
from choreo.metrics.protocol import TABLE_HEADER, ScoringSet, generate_window_motions, music_beats, score, table_row

REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint", nargs="?", default=None)
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--settings", nargs="+", default=["0.06:0.25:0.04:0.6"])
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    scoring = ScoringSet.from_clips(load_dataset(args.data))
    motions = generate_window_motions(load_backend("sgmd", args.checkpoint), scoring.windows, seed=0, options={"steps": 10})
    finished = [finish(m, music_beats(w.features), footsteps=False) for w, m in zip(scoring.windows, motions)]

    def row(label: str, dances) -> None:
        as_dances = [Dance(w.clip, m.joint_positions(), music_beats(w.features)) for w, m in zip(scoring.windows, dances)]
        print(table_row(label, score(as_dances, scoring.reference)), flush=True)

    print(TABLE_HEADER.format(label="setting"))
    row("none (finished)", finished)
    for setting in args.settings:
        trigger, swing, lift, strength = map(float, setting.split(":"))
        config = StepConfig(trigger=trigger, swing_seconds=swing, lift=lift, strength=strength)
        started = time.perf_counter()
        stepped = [planted_steps(m, config=config) for m in finished]
        row(f"{setting} ({time.perf_counter() - started:.1f} s)", stepped)


if __name__ == "__main__":
    main()
