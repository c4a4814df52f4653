"""Does an SGMD checkpoint denoise, or recall? One number per noise level.

    python scripts/denoiser_probe.py CHECKPOINT [CHECKPOINT ...] [--split train] [--windows 64]
                                     [--without music|style|both] [--parts]

Real windows are noised to step t and the model's x0 prediction is compared with the truth,
beside the trivial denoiser x_t / sqrt(alpha_bar) (which knows nothing about dance). A model that
denoises beats the trivial one at low noise, and its error grows with t; a model that recalls x0
from the music alone has the same error at every t. Also printed: how fast the ankles move
relative to the pelvis (m/s) in the prediction and in the truth, since legs that stop moving are
what recall-from-music looks like in a dance.

`--without music` (or style, or both) gives the model its null condition instead, which tells
whether a flat error comes from the music or from the network itself; `--parts` splits the error
into foot contacts, root and joint rotations, each beside that part's own variance.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import torch

from choreo import load_backend
from choreo.datasets import TEST, TRAIN, load_dataset
from choreo.metrics.protocol import scoring_windows
from choreo.motion import motion_to_vector, vector_to_motion
from choreo.motion.vector import CONTACT_SLICE, ROOT_SLICE, ROTATION_SLICE
from choreo_sgmd import genre_styles

REPO = Path(__file__).resolve().parents[1]
ANKLES, PELVIS = [7, 8], 0
STEPS = (10, 50, 200, 500, 800, 999)
PARTS = {"contacts": CONTACT_SLICE, "root": ROOT_SLICE, "rotations": ROTATION_SLICE}


def ankle_swing(vectors: np.ndarray, fps: float = 30.0) -> float:
    """Mean horizontal speed (m/s) of the ankles relative to the pelvis."""
    speeds = []
    for vector in vectors:
        joints = vector_to_motion(vector)[0].joint_positions()
        relative = joints[:, ANKLES][..., [0, 2]] - joints[:, [PELVIS]][..., [0, 2]]
        speeds.append(np.linalg.norm(np.diff(relative, axis=0), axis=-1).mean() * fps)
    return float(np.mean(speeds))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoints", nargs="+")
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "m2d"))
    parser.add_argument("--split", choices=["train", "test"], default="test")
    parser.add_argument("--windows", type=int, default=64)
    parser.add_argument("--without", choices=["music", "style", "both"], help="give the model its null condition for these")
    parser.add_argument("--parts", action="store_true", help="also print the error of contacts, root and rotations")
    args = parser.parse_args()
    clips = [c for c in load_dataset(args.data) if c.split == (TRAIN if args.split == "train" else TEST)]
    windows = scoring_windows(clips)
    windows = [windows[i] for i in np.linspace(0, len(windows) - 1, min(args.windows, len(windows))).astype(int)]
    vectors = np.stack([motion_to_vector(w.motion) for w in windows])
    print(f"{len(windows)} {args.split} windows; real ankle swing {ankle_swing(vectors):.2f} m/s")
    part_names = list(PARTS) if args.parts else []
    print("| checkpoint | t | model error | x_t / sqrt(alpha_bar) error | ankle swing of the prediction (m/s) |"
          + "".join(f" {name} (variance) |" for name in part_names))
    print("| --- | ---: | ---: | ---: | ---: |" + " ---: |" * len(part_names))
    for checkpoint in args.checkpoints:
        generator = load_backend("sgmd", checkpoint)
        stride = generator.model_config.frame_stride  # a 15 fps model sees every other frame
        x0 = generator.normalizer.normalize(torch.from_numpy(vectors[:, ::stride]).float())
        styles, keep_style = genre_styles(generator, [w.genre for w in windows])
        keep_music = torch.ones(len(windows), dtype=torch.bool)
        if args.without in ("music", "both"):
            keep_music[:] = False
        if args.without in ("style", "both"):
            keep_style[:] = False
        variance = x0.var(dim=(0, 1))
        noise_draws = torch.Generator().manual_seed(0)
        with torch.no_grad():
            conditioning = generator.model.condition(generator.music_tensor(np.stack([w.features for w in windows])),
                                                     styles, keep_music=keep_music, keep_style=keep_style)
            for t in STEPS:
                steps = torch.full((len(x0),), t)
                x_t = generator.schedule.q_sample(x0, steps, torch.randn(x0.shape, generator=noise_draws))
                predicted = generator.model.denoise(x_t, steps, conditioning)
                trivial = x_t / generator.schedule.alphas_cumprod[t].float().sqrt()
                swing = ankle_swing(generator.normalizer.denormalize(predicted).numpy(), 30.0 / stride)
                error = ((predicted - x0) ** 2).mean(dim=(0, 1))
                parts = "".join(f" {float(error[PARTS[name]].mean()):.4f} ({float(variance[PARTS[name]].mean()):.4f}) |"
                                for name in part_names)
                print(f"| {Path(checkpoint).name} (step {generator.trained_steps}) | {t} | "
                      f"{float(error.mean()):.4f} | {float(((trivial - x0) ** 2).mean()):.4f} | {swing:.2f} |{parts}",
                      flush=True)


if __name__ == "__main__":
    main()
