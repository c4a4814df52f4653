"""SGMD's sampler pulling each step's predicted travel toward the genre's pace (not kept).

    python scripts/experiments/sampler_pace.py --bound 1.5 [--below 1.0] -- \
        --split validation --checkpoint runs/holdout/last.pt --json pulled.json

Issue 45 (docs/results.md, "What the feet and the beats still miss"). The pace pass scales a
finished dance's travel by 1.25 at most, after the network has posed the legs for the travel it
chose. Here, at every denoising step whose noise level t/T is at most ``below``, the x0 prediction's
ground track (its windows stitched) is measured and its floor travel scaled about the block's first
frame toward the genre's real pace (choreo.finishing.pace), by at most ``bound`` either way: the
next steps then pose the body for that travel. One scale for all windows of a block keeps their
overlaps in agreement. Only free dances (the validation and test songs): under constraints, or from
a song's second block of windows on, the known frames would be scaled too. Everything after ``--``
goes to scripts/evaluate_whole_songs.py, which dances and scores the songs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

from choreo.finishing.pace import target_pace
from choreo.motion.travel import ground_track, track_pace

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "scripts"))
import evaluate_whole_songs  # noqa: E402

from choreo_sgmd import sampling  # noqa: E402
from choreo_sgmd.generator import SGMDGenerator  # noqa: E402

FLOOR = [4, 6]  # the root's x and z in a frame vector (4 contacts | 3 root | 24 x 6D), Y up
FPS = 30.0


class PacePull:
    """A guided denoiser whose x0 predictions travel at the pace asked, within the bound."""

    def __init__(self, denoiser, normalizer, target: float, bound: float, below: float, timesteps: int):
        self.denoiser, self.normalizer, self.target = denoiser, normalizer, target
        self.bound, self.below, self.timesteps = bound, below, timesteps
        self.scales: list[float] = []

    def evaluations_at(self, t: int) -> int:
        return self.denoiser.evaluations_at(t)

    def __call__(self, x_t: torch.Tensor, t: int) -> torch.Tensor:
        x0 = self.denoiser(x_t, t)
        if t / (self.timesteps - 1) > self.below:
            return x0
        frames = (len(x0) - 1) * (x0.shape[1] // 2) + x0.shape[1]
        floor = sampling.stitch(x0[..., FLOOR], frames)
        span = (self.normalizer.high - self.normalizer.low)[FLOOR] / 2  # metres per normalised unit
        root = np.zeros((frames, 3))
        root[:, [0, 2]] = (floor * span).numpy()
        pace = track_pace(ground_track(root, FPS), FPS)
        scale = float(np.clip(self.target / pace, 1 / self.bound, self.bound)) if pace > 0 else 1.0
        self.scales.append(scale)
        origin = x0[:1, :1, FLOOR]
        x0 = x0.clone()
        x0[..., FLOOR] = origin + scale * (x0[..., FLOOR] - origin)
        return x0


def install(bound: float, below: float) -> None:
    """Patch the SGMD generator so that every free dance's sampler pulls toward its genre's pace."""
    generate, guided = SGMDGenerator.generate, sampling.guided_denoiser
    context: dict = {}

    def generate_pulled(self, request, progress=None):
        _, _, genres, _ = self.style_conditioning(request.style, request.music.num_frames, request.music.fps)
        target = target_pace(genres[0]) if len(genres) == 1 else None
        context.update(normalizer=self.normalizer, target=target,
                       free=request.constraints is None or request.constraints.is_empty)
        return generate(self, request, progress)

    def guided_pulled(model, music, styles, keep_style, options, schedule):
        denoiser = guided(model, music, styles, keep_style, options, schedule)
        if context.get("target") is None or not context.get("free"):
            return denoiser
        return PacePull(denoiser, context["normalizer"], context["target"], bound, below, schedule.timesteps)

    SGMDGenerator.generate, sampling.guided_denoiser = generate_pulled, guided_pulled


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bound", type=float, default=1.5, help="the most the travel is scaled by, either way")
    parser.add_argument("--below", type=float, default=1.0, help="pull at noise levels t/T up to this")
    args, rest = parser.parse_known_args()
    install(args.bound, args.below)
    sys.argv = [sys.argv[0], *[a for a in rest if a != "--"]]
    evaluate_whole_songs.main()


if __name__ == "__main__":
    main()
