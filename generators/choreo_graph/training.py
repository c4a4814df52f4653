"""Training ChoreoGraph's learnt parts in the paper's order: style embedding (eq. 1), then the
motion tempo-density autoencoder (eq. 2), then the music tempo-density estimator (eq. 3) against
the frozen motion estimator."""

from __future__ import annotations

import time
from dataclasses import asdict
from pathlib import Path
from typing import Callable, Iterator

import numpy as np
import torch
from torch.nn import functional as F

from choreo.generator import TrainProgress

from .config import CLIP_FRAMES, ModelConfig, TrainConfig
from .data import Excerpts
from .model import ChoreoGraphModel, save_checkpoint
from .repertoire import MIDDLE
from .style import style_loss
from .tempo import random_time_warp, tempo_autoencoder_loss

STYLE_STRIDE = 15  # 4 s style pairs every half second


def batches(count: int, batch_size: int, rng: np.random.Generator) -> Iterator[np.ndarray]:
    """Endless shuffled mini-batches of indices (every example once per epoch)."""
    while True:
        order = rng.permutation(count)
        for first in range(0, count - batch_size + 1, batch_size):
            yield order[first : first + batch_size]


def run_stage(name: str, steps: int, step_loss: Callable[[np.ndarray], dict], parameters, config: TrainConfig,
              count: int, rng: np.random.Generator, progress: Callable[[TrainProgress], None] | None) -> list[float]:
    """Adam on one stage's loss; returns the loss curve (one value per step)."""
    optimizer = torch.optim.Adam(parameters, lr=config.learning_rate)
    curve, started = [], time.perf_counter()
    batch_size = min(config.batch_size, count)
    for step, indices in zip(range(1, steps + 1), batches(count, batch_size, rng)):
        loss = step_loss(indices)["loss"]
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        optimizer.step()
        curve.append(float(loss.detach()))
        if progress and (step % 20 == 0 or step == steps):
            rate = step * batch_size / (time.perf_counter() - started)
            progress(TrainProgress(step, steps, float(np.mean(curve[-20:])), rate, None, stage=name))
    return curve


@torch.no_grad()
def style_retrieval(model: ChoreoGraphModel, data: Excerpts, pool: int = 32, seed: int = 0) -> float:
    """Top-1 accuracy of finding a music window's own dance among ``pool`` (chance = 1 / pool)."""
    model.eval()
    rng = np.random.default_rng(seed)
    hits, total = 0, 0
    for _ in range(max(1, len(data) // pool)):
        idx = rng.choice(len(data), size=min(pool, len(data)), replace=False)
        music = model.style.music(torch.from_numpy(data.mel[idx]))
        motion = model.style.motion(torch.from_numpy(data.positions[idx]))
        hits += int((torch.cdist(music, motion).argmin(1) == torch.arange(len(idx))).sum())
        total += len(idx)
    model.train()
    return hits / total


def train_graph(style_data: Excerpts, clip_data: Excerpts, validation: tuple[Excerpts, Excerpts] | None,
                out_dir: str | Path, model_config: ModelConfig = ModelConfig(), config: TrainConfig = TrainConfig(),
                progress: Callable[[TrainProgress], None] | None = None) -> Path:
    """All three stages; writes OUT/graph.pt after each (the last one is the usable checkpoint)."""
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "graph.pt"
    model = ChoreoGraphModel(model_config).train()
    report: dict = {"train_config": asdict(config), "style_pairs": len(style_data), "clip_pairs": len(clip_data)}

    def save() -> None:
        save_checkpoint(model, path, {"training": report})

    def style_step(idx):
        return style_loss(model.style, torch.from_numpy(style_data.mel[idx]), torch.from_numpy(style_data.positions[idx]),
                          torch.from_numpy(style_data.beats[idx]))

    report["style_curve"] = run_stage("style", config.style_steps, style_step, model.style.parameters(), config,
                                      len(style_data), rng, progress)[::50]
    if validation:
        report["style_retrieval_top1_of_32"] = style_retrieval(model, validation[0])
    report["style_retrieval_train_top1_of_32"] = style_retrieval(model, style_data)
    save()

    motion = clip_data.positions.reshape(len(clip_data), CLIP_FRAMES, -1)

    def tempo_step(idx):
        warped = np.stack([random_time_warp(clip_data.positions[i], model_config.tempo.max_shift, rng) for i in idx])
        return tempo_autoencoder_loss(model.motion_tempo, torch.from_numpy(motion[idx]),
                                      torch.from_numpy(warped.reshape(len(idx), CLIP_FRAMES, -1)).float(),
                                      model_config.tempo.content_weight)

    report["motion_tempo_curve"] = run_stage("motion tempo", config.motion_tempo_steps, tempo_step,
                                             model.motion_tempo.parameters(), config, len(clip_data), rng, progress)[::50]
    save()

    targets = target_tempo(model, clip_data)
    mel = clip_data.mel[:, MIDDLE]

    def music_step(idx):
        prediction = model.music_tempo(torch.from_numpy(mel[idx]))
        return {"loss": F.mse_loss(prediction, torch.from_numpy(targets[idx]))}

    report["music_tempo_curve"] = run_stage("music tempo", config.music_tempo_steps, music_step,
                                            model.music_tempo.parameters(), config, len(clip_data), rng, progress)[::50]
    report["music_tempo_variance"] = float(targets.var())
    if validation:
        report["music_tempo_validation_mse"] = music_tempo_error(model, validation[1])
    report["music_tempo_train_mse"] = music_tempo_error(model, clip_data)
    save()
    return path


@torch.no_grad()
def target_tempo(model: ChoreoGraphModel, clips: Excerpts) -> np.ndarray:
    """Middle 4 s of the frozen motion estimator's tempo-density for every 8 s excerpt (eq. 3's target)."""
    model.eval()
    curves = [model.motion_tempo_density(torch.from_numpy(clips.positions[i : i + 64])).numpy()
              for i in range(0, len(clips), 64)]
    model.train()
    return np.concatenate(curves)[:, MIDDLE].astype(np.float32)


@torch.no_grad()
def music_tempo_error(model: ChoreoGraphModel, clips: Excerpts) -> float:
    targets = target_tempo(model, clips)
    model.eval()
    predictions = np.concatenate([model.music_tempo_density(torch.from_numpy(clips.mel[i : i + 64, MIDDLE])).numpy()
                                  for i in range(0, len(clips), 64)])
    model.train()
    return float(np.mean((predictions - targets) ** 2))

