"""Can the cpu SGMD network learn to pass its input through? Train it on low noise only (t < 50).

    python scripts/experiments/low_noise_training.py full|nolayers [--steps 101] [--lr 4e-4] [--reconstruction-weight W]

At t < 50 the best x0 is nearly x_t itself (the trivial denoiser x_t / sqrt(alpha_bar) has error
0.0007 at t = 10). ``full`` trains the whole network on those steps only; ``nolayers`` removes
the transformer layers (x_t -> linear -> norm -> linear), the smallest network that can copy.
Printed every 25 steps: the training loss and the x0 error at t = 10 on 32 train windows, whole
and for the joint rotations alone (the part the bundled model leaves unread: docs/results.md).
``--reconstruction-weight`` replaces EDGE's 0.636 on the x0 term, which is the only term that
sees every rotation channel directly.
"""

from __future__ import annotations

import argparse
import copy
import time

import torch
import torch.nn as nn

from choreo.datasets import TRAIN, WindowConfig, load_dataset
from choreo.motion.vector import ROTATION_SLICE
from choreo_sgmd import DiffusionConfig, Trainer, TrainConfig, model_config, windows_to_tensors


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("variant", choices=["full", "nolayers"])
    parser.add_argument("--steps", type=int, default=101)
    parser.add_argument("--lr", type=float, default=4e-4)
    parser.add_argument("--reconstruction-weight", type=float, default=DiffusionConfig.reconstruction_weight)
    parser.add_argument("--data", default="../shared/data/m2d")
    args = parser.parse_args()
    clips = [c for c in load_dataset(args.data) if c.split == TRAIN]
    train = windows_to_tensors(clips, WindowConfig(seconds=5, stride_seconds=0.5), "description")
    config = model_config("cpu", style_dim=train.style.shape[1], music_dim=train.music.shape[-1])
    trainer = Trainer(config, DiffusionConfig(reconstruction_weight=args.reconstruction_weight), TrainConfig(genre_balance=0.0, learning_rate=args.lr), train, None)
    if args.variant == "nolayers":
        trainer.model.layers = nn.ModuleList()
        trainer.optimizer = torch.optim.AdamW(trainer.model.parameters(), lr=args.lr)
        trainer.ema = copy.deepcopy(trainer.model)
    full_batch = trainer.batch

    def low_noise_batch(generator, data, indices, share=slice(None)):
        x0, music, t, *rest = full_batch(generator, data, indices, share)
        return (x0, music, t % 50, *rest)

    trainer.batch = low_noise_batch
    probe = torch.arange(0, len(train), max(1, len(train) // 32))[:32]
    x0 = trainer.normalizer.normalize(train.motion[probe])
    music = trainer.music_scaler(train.music[probe])
    t = torch.full((len(probe),), 10)
    x_t = trainer.schedule.q_sample(x0, t, torch.randn(x0.shape, generator=torch.Generator().manual_seed(1)))
    started = time.time()
    for step in range(args.steps):
        loss = trainer.train_step()
        if step % 25 == 0 or step == args.steps - 1:
            with torch.no_grad():
                squared = (trainer.model.eval()(x_t, t, music, train.style[probe]) - x0) ** 2
            print(f"step {step}: loss {loss:.4f}, x0 error at t = 10 {float(squared.mean()):.4f}, rotations "
                  f"{float(squared[..., ROTATION_SLICE].mean()):.4f} ({time.time() - started:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
