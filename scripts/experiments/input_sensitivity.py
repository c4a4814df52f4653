"""How much does an SGMD checkpoint's x0 prediction depend on its noisy input x_t?

    python scripts/experiments/input_sensitivity.py CHECKPOINT [CHECKPOINT ...]

For the same music and style, the prediction from x_t is compared with the prediction from
x_t plus a little noise (0.1) and from a completely different x_t (fresh noise). A denoiser's
prediction follows its input at low noise; a model that recalls a dance from the music returns
nearly the same prediction whatever x_t is.
"""

from __future__ import annotations

import argparse

import torch

from choreo import load_backend


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoints", nargs="+")
    args = parser.parse_args()
    print("| checkpoint | t | prediction std | change: x_t + 0.1 noise | change: another x_t |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for checkpoint in args.checkpoints:
        generator = load_backend("sgmd", checkpoint)
        model, config = generator.model.eval(), generator.model_config
        draws = torch.Generator().manual_seed(0)
        batch, frames = 4, config.window_frames
        x0 = torch.rand(batch, frames, config.frame_dim, generator=draws) * 2 - 1
        music = torch.randn(batch, frames, config.music_dim, generator=draws)
        with torch.no_grad():
            conditioning = model.condition(music, torch.zeros(batch, config.style_dim))
            for t in (10, 200, 800):
                steps = torch.full((batch,), t)
                x_t = generator.schedule.q_sample(x0, steps, torch.randn(x0.shape, generator=draws))
                base = model.denoise(x_t, steps, conditioning)
                nudged = model.denoise(x_t + 0.1 * torch.randn(x_t.shape, generator=draws), steps, conditioning)
                other = model.denoise(torch.randn(x_t.shape, generator=draws), steps, conditioning)
                print(f"| {checkpoint} (step {generator.trained_steps}) | {t} | {float(base.std()):.3f} | "
                      f"{float((base - nudged).std()):.4f} | {float((base - other).std()):.4f} |", flush=True)


if __name__ == "__main__":
    main()
