"""SGMD's metrics against training time, beside the issue's targets: how far each target is.

    python -m experiments.training_curve --start 2026-12-03T08:35:10 --out docs/report/sgmd_training_curve.png \
        CHECKPOINT@TIME[@SERIES] [CHECKPOINT@TIME[@SERIES] ...]
    python -m experiments.training_curve --measured docs/report/sgmd_recon_curve.csv \
        --out docs/report/sgmd_recon_curve.png

Each CHECKPOINT (a copy of a run's last.pt taken when it was written, TIME its ISO time or a Unix
time, or +HOURS for a run timed elsewhere; SERIES names its line, default --label) is scored like the reference row (M2D test windows against the train split; DDIM 10,
guidance 2, sampling seed 0) and placed at its wall-clock hours since --start. Prints one
markdown row per checkpoint and plots FID_k, FID_g, Div_k and PFC, each with its target line
(FID_k <= 2 x real, FID_g <= 15, Div_k >= 0.67 x real, PFC <= 1.2 x real).

With --measured, the points are read from a CSV of scores measured earlier (columns series,
step, hours, fid_k, fid_g, div_k, pfc and optionally genre, a fraction), for runs whose
intermediate checkpoints were not kept; the genre panel (target 80 %) is drawn when given.
"""

from __future__ import annotations

import argparse
import csv
from datetime import datetime
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from choreo import load_backend  # noqa: E402
from choreo.datasets import load_dataset  # noqa: E402
from choreo.metrics.protocol import TABLE_HEADER, ScoringSet, score_generator, table_row  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
# the reference row (docs/history/results-2026-12-01-to-2026-12-04.md, "Reference row: M2D ground truth")
REAL = {"fid_k": 18.31, "fid_g": 3.28, "div_k": 9.40, "pfc": 0.853}
TARGETS = {"fid_k": ("<=", 2 * REAL["fid_k"]), "fid_g": ("<=", 15.0), "div_k": (">=", 0.67 * REAL["div_k"]),
           "pfc": ("<=", 1.2 * REAL["pfc"]), "genre": (">=", 0.80)}
TITLES = {"fid_k": "FID_k", "fid_g": "FID_g", "div_k": "Div_k", "pfc": "PFC", "genre": "requested genre recognised"}


def seconds(stamp: str) -> float:
    return float(stamp) if stamp.replace(".", "").isdigit() else datetime.fromisoformat(stamp).timestamp()


def scored_points(items: list[str], start: float, data: str, label: str) -> list[tuple]:
    """Score each CHECKPOINT@TIME[@SERIES] like the reference row: (hours, step, metrics, series)."""
    scoring = ScoringSet.from_clips(load_dataset(data))
    points = []
    print(TABLE_HEADER.format(label="checkpoint (hours)"), flush=True)
    for item in items:
        path, stamp, series = (item.split("@") + [label])[:3]
        generator = load_backend("sgmd", path)
        report, _ = score_generator(generator, scoring, options={"steps": 10, "guidance": 2.0})
        hours = float(stamp[1:]) if stamp.startswith("+") else (seconds(stamp) - start) / 3600
        metrics = {key: getattr(report, key) for key in TARGETS if hasattr(report, key)}
        points.append((hours, generator.trained_steps, metrics, series))
        print(table_row(f"{series}: step {generator.trained_steps} ({hours:.2f} h)", report), flush=True)
    return points


def measured_points(path: Path) -> list[tuple]:
    """Read (hours, step, metrics, series) rows from a CSV of scores measured earlier."""
    with open(path, newline="") as file:
        rows = list(csv.DictReader(file))
    return [(float(row["hours"]), int(row["step"]),
             {key: float(row[key]) for key in TARGETS if row.get(key, "") != ""}, row["series"]) for row in rows]


def plot_curve(points: list[tuple], out: Path) -> None:
    """One panel per metric that every point has, each with its target and the real motion's value."""
    points = sorted(points, key=lambda p: p[0])
    keys = [key for key in TARGETS if all(key in p[2] for p in points)]
    figure, axes = plt.subplots(1, len(keys), figsize=(4 * len(keys), 3.6))
    for axis, key in zip(axes, keys):
        direction, target = TARGETS[key]
        for series in dict.fromkeys(p[3] for p in points):
            mine = [p for p in points if p[3] == series]
            axis.plot([p[0] for p in mine], [p[2][key] for p in mine], "o-", label=series)
        axis.axhline(target, color="green", linestyle="--", label=f"target ({direction} {target:.3g})")
        if key in REAL:
            axis.axhline(REAL[key], color="grey", linestyle=":", label=f"real test motion ({REAL[key]:.3g})")
        axis.set_title(TITLES[key])
        axis.set_xlabel("training wall-clock hours (CPU)")
        axis.legend(fontsize=7)
    for hours, step, metrics, _ in points:
        axes[0].annotate(f"{step}", (hours, metrics[keys[0]]), fontsize=6)
    figure.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, dpi=90)
    print(f"wrote {out}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoints", nargs="*", help="CHECKPOINT@TIME[@SERIES]")
    parser.add_argument("--start", help="when the run started (ISO or Unix time); with checkpoints")
    parser.add_argument("--measured", type=Path, help="a CSV of scores measured earlier, instead of checkpoints")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--label", default="SGMD")
    args = parser.parse_args()
    if args.measured:
        points = measured_points(args.measured)
    elif args.checkpoints and args.start:
        points = scored_points(args.checkpoints, seconds(args.start), args.data, args.label)
    else:
        parser.error("give CHECKPOINT@TIME ... with --start, or --measured CSV")
    plot_curve(points, args.out)


if __name__ == "__main__":
    main()
