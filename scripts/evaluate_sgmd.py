"""Score an SGMD checkpoint on the M2D test split against the train split (the reference row's setup).

    python scripts/evaluate_sgmd.py CHECKPOINT [--guidance 2] [--steps 50] [--seed 0] [--no-style]

One 5 s dance per test window (2.5 s stride), generated from that window's music and the clip's
genre, scored like scripts/reference_row.py so the numbers sit beside the reference row.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np
import torch

from choreo.datasets import TEST, TRAIN, load_dataset
from choreo.metrics import Dance, MetricWarning, evaluate
from choreo.motion import vector_to_motion
from choreo.music import BEAT_COLUMN
from choreo_sgmd.generator import SGMDGenerator
from choreo_sgmd.sampling import SamplingOptions, sample_independent
from choreo_sgmd.style import resolve_style

REPO = Path(__file__).resolve().parents[1]
sys_path = str(REPO / "scripts")
import sys  # noqa: E402

sys.path.insert(0, sys_path)
from reference_row import WINDOWS, fmt, windows_as_dances  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--guidance", type=float, default=2.0)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-style", action="store_true")
    args = parser.parse_args()
    started = time.time()
    generator = SGMDGenerator(args.checkpoint)
    clips = load_dataset(args.data)
    truth = windows_as_dances([c for c in clips if c.split == TEST])
    train = windows_as_dances([c for c in clips if c.split == TRAIN])
    from choreo.datasets import WindowedDataset

    windows = list(WindowedDataset([c for c in clips if c.split == TEST], WINDOWS))
    music = generator.music_scaler(torch.from_numpy(np.stack([w.features for w in windows])).float())
    styles, keep = [], []
    for w in windows:
        style = resolve_style(None if args.no_style else w.genre, generator.prompt_kind)
        styles.append(np.zeros(generator.model_config.style_dim, np.float32) if style.vector is None else style.vector)
        keep.append(style.vector is not None)
    options = SamplingOptions(steps=args.steps, guidance=args.guidance, seed=args.seed)
    x0 = sample_independent(generator.model, generator.schedule, music, torch.from_numpy(np.stack(styles)),
                            torch.tensor(keep), generator.model_config.frame_dim, options)
    vectors = generator.normalizer.denormalize(x0).numpy()
    dances = []
    for w, v in zip(windows, vectors):
        motion, _ = vector_to_motion(v)
        dances.append(Dance(f"{w.clip}@{w.start_frame}", motion.joint_positions(),
                            np.flatnonzero(w.features[:, BEAT_COLUMN] > 0.5)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        report = evaluate(dances, train, fps=WINDOWS.fps)
    label = f"SGMD {Path(args.checkpoint).name} step {generator.trained_steps}, w={args.guidance:g}, {args.steps} steps" + (
        ", no style" if args.no_style else "")
    print(f"| {label} | {report.generated_count} | {fmt(report.beat_align)} | {fmt(report.pfc)} | {fmt(report.fid_k)} | "
          f"{fmt(report.fid_g)} | {fmt(report.div_k)} | {fmt(report.div_g)} | {fmt(report.motion_to_music)} | "
          f"{fmt(report.music_to_motion)} |")
    print(f"({len(truth)} test windows; ground truth: {len(train)} train windows; {time.time() - started:.0f} s)")


if __name__ == "__main__":
    main()
