"""How large is the legs term (choreo_sgmd.losses.legs_error) beside the other terms, by noise level?

    python -m experiments.legs_term_scale [--checkpoint generators/choreo_sgmd/weights/sgmd-train-state.pt]

64 train windows (seed 0), noised to t = 20, 100, 300, 600 and 900, denoised by the training
state's EMA weights; prints every loss term (unweighted) at each t. What set --legs-weight 0.5
(docs/sgmd.md, "Legs").
"""

from __future__ import annotations

import argparse
from pathlib import Path

import torch

from choreo.datasets import TRAIN, WindowConfig, load_dataset
from choreo_sgmd.config import DiffusionConfig, TrainConfig, model_config
from choreo_sgmd.data import Augmentation, windows_to_tensors
from choreo_sgmd.losses import diffusion_losses
from choreo_sgmd.style import style_dim
from choreo_sgmd.training import Trainer, restore

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkpoint", default=str(REPO / "generators/choreo_sgmd/weights/sgmd-train-state.pt"))
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    args = parser.parse_args()
    clips = [c for c in load_dataset(args.data) if c.split in (TRAIN, None)]
    model = model_config("cpu", style_dim=style_dim("description"))
    data = windows_to_tensors(clips, WindowConfig(seconds=5, stride_seconds=0.5), "description", model.music_dim,
                              Augmentation(), 1)
    trainer = Trainer(model, DiffusionConfig(legs_weight=1.0), TrainConfig(), data, None)
    restore(trainer, Path(args.checkpoint), resume=False)
    generator = torch.Generator().manual_seed(0)
    x0, music, _, noise, keep_music, keep_style, style, pace = trainer.batch(
        generator, data, torch.randint(0, len(data), (64,), generator=generator))
    for step in (20, 100, 300, 600, 900):
        t = torch.full((64,), step)
        with torch.no_grad():
            predicted = trainer.ema(trainer.schedule.q_sample(x0, t, noise), t, music, style, keep_music=keep_music,
                                    keep_style=keep_style, pace=pace)
            terms = diffusion_losses(predicted, x0, trainer.normalizer)
        alpha_bar = float(trainer.schedule.alpha_bar(t)[0])
        print(f"t={step} alpha_bar={alpha_bar:.3f} " + " ".join(f"{k}={float(v):.4f}" for k, v in vars(terms).items()))


if __name__ == "__main__":
    main()
