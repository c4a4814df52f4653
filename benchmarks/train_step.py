"""Seconds per SGMD training step of each model preset, measured side by side in one run.

    python benchmarks/train_step.py [--presets cpu small cpu15] [--steps 10] [--rounds 3]

Why: comparing presets "at the same wall-clock time" needs their step-time ratio on this CPU,
and a ratio measured in one run survives a busy machine (a training beside it slows both
presets alike). Each round times ``--steps`` optimiser steps of every preset in turn (batch 32
windows of 5 s, the training defaults) on random windows of the real shapes; the median round
is printed, with each preset's time relative to the first.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from choreo_sgmd import DiffusionConfig, Trainer, TrainConfig, WindowTensors, model_config



def random_windows(config, count: int = 64) -> WindowTensors:
    """Windows of the preset's own length (150 frames at 30 fps; 75 for a 15 fps preset)."""
    generator = torch.Generator().manual_seed(0)
    frames = config.window_frames
    return WindowTensors(motion=torch.randn(count, frames, config.frame_dim, generator=generator),
                         music=torch.randn(count, frames, config.music_dim, generator=generator),
                         style=torch.randn(count, config.style_dim, generator=generator),
                         has_style=torch.ones(count, dtype=torch.bool))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["cpu", "small"])
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    trainers = {}
    for name in args.presets:
        config = model_config(name)
        trainers[name] = Trainer(config, DiffusionConfig(), TrainConfig(genre_balance=0.0), random_windows(config), None)
        trainers[name].train_step()  # warm-up
    seconds = {name: [] for name in trainers}
    for _ in range(args.rounds):
        for name, trainer in trainers.items():
            started = time.perf_counter()
            for _ in range(args.steps):
                trainer.train_step()
            seconds[name].append((time.perf_counter() - started) / args.steps)
    first = np.median(seconds[args.presets[0]])
    print(f"threads: {torch.get_num_threads()}")
    print("| preset | parameters | s per step (median of rounds) | x first |")
    print("| --- | ---: | ---: | ---: |")
    for name, trainer in trainers.items():
        parameters = sum(p.numel() for p in trainer.model.parameters())
        median = float(np.median(seconds[name]))
        print(f"| {name} | {parameters / 1e6:.2f} M | {median:.2f} | {median / first:.2f} |")


if __name__ == "__main__":
    main()
