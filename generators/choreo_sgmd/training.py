"""The training loop: diffusion on 5 s windows with condition dropout, EMA weights, validation,
atomic checkpoints and exact resumption (batches and noise are drawn from per-step seeds, so a
resumed run sees what an uninterrupted one would have)."""

from __future__ import annotations

import copy
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import torch


from .checkpoint import load_checkpoint, save_checkpoint
from .config import DiffusionConfig, ModelConfig, TrainConfig
from .data import MusicScaler, WindowTensors
from .losses import diffusion_losses
from .model import Denoiser
from .normalizer import Normalizer
from .schedule import NoiseSchedule
from .style import GENRES

VALIDATION_WINDOWS = 64


@dataclass
class TrainProgress:
    step: int
    max_steps: int
    loss: float
    windows_per_second: float
    validation_loss: float | None


def _step_generator(seed: int, step: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed * 1_000_003 + step)


class Trainer:
    def __init__(self, model_config: ModelConfig, diffusion_config: DiffusionConfig, train_config: TrainConfig,
                 train: WindowTensors, validation: WindowTensors | None):
        torch.manual_seed(train_config.seed)
        self.model_config, self.diffusion_config, self.config = model_config, diffusion_config, train_config
        self.model = Denoiser(model_config)
        self.ema = copy.deepcopy(self.model).eval().requires_grad_(False)
        self.optimizer = torch.optim.AdamW(self.model.parameters(), lr=train_config.learning_rate,
                                           weight_decay=train_config.weight_decay)
        self.schedule = NoiseSchedule(diffusion_config)
        self.normalizer = Normalizer.fit(train.motion.reshape(-1, train.motion.shape[-1]))
        self.music_scaler = MusicScaler.fit(train.music)
        self.train, self.validation = train, validation
        self.step = 0
        self.history: list[list[float]] = []  # [step, train loss, validation loss or -1]

    def batch(self, generator: torch.Generator, data: WindowTensors, indices: torch.Tensor):
        x0 = self.normalizer.normalize(data.motion[indices])
        music = self.music_scaler(data.music[indices])
        t = torch.randint(0, self.schedule.timesteps, (len(indices),), generator=generator)
        noise = torch.randn(x0.shape, generator=generator)
        keep_music = torch.rand(len(indices), generator=generator) >= self.diffusion_config.music_dropout
        keep_style = (torch.rand(len(indices), generator=generator) >= self.diffusion_config.style_dropout)
        return x0, music, t, noise, keep_music, keep_style & data.has_style[indices]

    def loss(self, model, x0, music, style, t, noise, keep_music, keep_style) -> torch.Tensor:
        x_t = self.schedule.q_sample(x0, t, noise)
        predicted = model(x_t, t, music, style, keep_music=keep_music, keep_style=keep_style)
        return diffusion_losses(predicted, x0, self.normalizer).total(self.diffusion_config)

    def train_step(self) -> float:
        generator = _step_generator(self.config.seed, self.step)
        indices = torch.randint(0, len(self.train), (self.config.batch_size,), generator=generator)
        x0, music, t, noise, keep_music, keep_style = self.batch(generator, self.train, indices)
        self.model.train()
        loss = self.loss(self.model, x0, music, self.train.style[indices], t, noise, keep_music, keep_style)
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.model.parameters(), 1.0)
        self.optimizer.step()
        self._update_ema()
        self.step += 1
        return float(loss.detach())

    @torch.no_grad()
    def _update_ema(self) -> None:
        decay = min(self.config.ema_decay, (1 + self.step) / (10 + self.step))  # warm up the average
        for ema, raw in zip(self.ema.parameters(), self.model.parameters()):
            ema.lerp_(raw, 1 - decay)

    @torch.no_grad()
    def validation_loss(self) -> float | None:
        """EMA model's loss on fixed validation windows, steps and noise (comparable across runs)."""
        if self.validation is None or len(self.validation) == 0:
            return None
        generator = torch.Generator().manual_seed(12345)
        count = min(VALIDATION_WINDOWS, len(self.validation))
        indices = torch.randperm(len(self.validation), generator=generator)[:count]
        x0, music, t, noise, _, _ = self.batch(generator, self.validation, indices)
        keep = torch.ones(count, dtype=torch.bool)
        return float(self.loss(self.ema, x0, music, self.validation.style[indices], t, noise, keep,
                               keep & self.validation.has_style[indices]))

    def state(self) -> dict:
        return {
            "model_config": asdict(self.model_config), "diffusion_config": asdict(self.diffusion_config),
            "train_config": asdict(self.config), "genres": list(GENRES), "prompt_kind": self.config.prompt_kind,
            "state_dict": self.model.state_dict(), "ema_state_dict": self.ema.state_dict(),
            "optimizer": self.optimizer.state_dict(), "normalizer": self.normalizer.state_dict(),
            "music_scaler": self.music_scaler.state_dict(), "step": self.step, "history": self.history,
        }  # fmt: skip

    def load_state(self, state: dict) -> None:
        self.model.load_state_dict(state["state_dict"])
        self.ema.load_state_dict(state["ema_state_dict"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.normalizer = Normalizer.from_state_dict(state["normalizer"])
        self.music_scaler = MusicScaler.from_state_dict(state["music_scaler"])
        self.step, self.history = int(state["step"]), [list(row) for row in state["history"]]


def train(model_config: ModelConfig, train_config: TrainConfig, train_data: WindowTensors,
          validation_data: WindowTensors | None, out_dir: str | Path, resume: bool = False,
          diffusion_config: DiffusionConfig = DiffusionConfig(),
          progress: Callable[[TrainProgress], None] | None = None) -> Path:
    """Train until ``train_config.max_steps``; checkpoints go to ``out_dir/last.pt`` atomically."""
    if train_config.num_threads:
        torch.set_num_threads(train_config.num_threads)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    checkpoint = out_dir / "last.pt"
    trainer = Trainer(model_config, diffusion_config, train_config, train_data, validation_data)
    if resume and checkpoint.exists():
        trainer.load_state(load_checkpoint(checkpoint))
    started, seen, losses = time.perf_counter(), 0, []
    while trainer.step < train_config.max_steps:
        losses.append(trainer.train_step())
        seen += train_config.batch_size
        validation = None
        if trainer.step % train_config.validation_every == 0 or trainer.step == train_config.max_steps:
            validation = trainer.validation_loss()
        if trainer.step % train_config.checkpoint_every == 0 or trainer.step == train_config.max_steps:
            trainer.history.append([trainer.step, sum(losses) / len(losses), -1.0 if validation is None else validation])
            losses = []
            save_checkpoint(trainer.state(), checkpoint)
        if progress is not None:
            rate = seen / max(time.perf_counter() - started, 1e-9)
            progress(TrainProgress(trainer.step, train_config.max_steps, losses[-1] if losses else trainer.history[-1][1],
                                   rate, validation))
    return checkpoint
