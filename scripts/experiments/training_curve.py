"""SGMD's metrics against training time, beside the issue's targets: how far each target is.

    python scripts/experiments/training_curve.py --start 2026-12-03T08:35:10 --out docs/report/sgmd_training_curve.png \
        CHECKPOINT@TIME[@SERIES] [CHECKPOINT@TIME[@SERIES] ...]

Each CHECKPOINT (a copy of a run's last.pt taken when it was written, TIME its ISO time or a Unix
time, or +HOURS for a run timed elsewhere; SERIES names its line, default --label) is scored like the reference row (M2D test windows against the train split; DDIM 10,
guidance 2, sampling seed 0) and placed at its wall-clock hours since --start. Prints one
markdown row per checkpoint and plots FID_k, FID_g, Div_k and PFC, each with its target line
(FID_k <= 2 x real, FID_g <= 15, Div_k >= 0.67 x real, PFC <= 1.2 x real).
"""

from __future__ import annotations

import argparse
from datetime import datetime
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from choreo import load_backend  # noqa: E402
from choreo.datasets import load_dataset  # noqa: E402
from choreo.metrics.protocol import TABLE_HEADER, ScoringSet, score_generator, table_row  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
REAL = {"fid_k": 18.31, "fid_g": 3.28, "div_k": 9.40, "pfc": 0.853}  # the reference row (docs/results.md)
TARGETS = {"fid_k": ("<=", 2 * REAL["fid_k"]), "fid_g": ("<=", 15.0), "div_k": (">=", 0.67 * REAL["div_k"]),
           "pfc": ("<=", 1.2 * REAL["pfc"])}


def seconds(stamp: str) -> float:
    return float(stamp) if stamp.replace(".", "").isdigit() else datetime.fromisoformat(stamp).timestamp()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoints", nargs="+", help="CHECKPOINT@TIME[@SERIES]")
    parser.add_argument("--start", required=True, help="when the run started (ISO or Unix time)")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--label", default="SGMD")
    args = parser.parse_args()
    scoring = ScoringSet.from_clips(load_dataset(args.data))
    start = seconds(args.start)
    points = []
    print(TABLE_HEADER.format(label="checkpoint (hours)"), flush=True)
    for item in args.checkpoints:
        path, stamp, series = (item.split("@") + [args.label])[:3]
        generator = load_backend("sgmd", path)
        report, _ = score_generator(generator, scoring, options={"steps": 10, "guidance": 2.0})
        hours = float(stamp[1:]) if stamp.startswith("+") else (seconds(stamp) - start) / 3600
        points.append((hours, generator.trained_steps, report, series))
        print(table_row(f"{series}: step {generator.trained_steps} ({hours:.2f} h)", report), flush=True)
    points.sort(key=lambda p: p[0])
    figure, axes = plt.subplots(1, 4, figsize=(16, 3.6))
    for axis, key in zip(axes, TARGETS):
        direction, target = TARGETS[key]
        for series in dict.fromkeys(p[3] for p in points):
            mine = [p for p in points if p[3] == series]
            axis.plot([p[0] for p in mine], [getattr(p[2], key) for p in mine], "o-", label=series)
        axis.axhline(target, color="green", linestyle="--", label=f"target ({direction} {target:.3g})")
        axis.axhline(REAL[key], color="grey", linestyle=":", label=f"real test motion ({REAL[key]:.3g})")
        axis.set_title(key.replace("_", " ").upper().replace("DIV", "Div").replace(" K", "_k").replace(" G", "_g"))
        axis.set_xlabel("training wall-clock hours (2 CPU cores)")
        axis.legend(fontsize=7)
    for hours, step, report, _ in points:
        axes[0].annotate(f"{step}", (hours, report.fid_k), fontsize=6)
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=90)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
