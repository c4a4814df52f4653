"""The training loop: diffusion on 5 s windows with condition dropout, EMA weights, validation,
atomic checkpoints and exact resumption (batches and noise are drawn from per-step seeds, so a
resumed run sees what an uninterrupted one would have).

Under ``torchrun`` (WORLD_SIZE > 1) it trains with DistributedDataParallel: every rank draws the
same global batch from the step's seed and keeps its own slice of it, gradients are averaged,
and rank 0 alone validates and writes checkpoints. So N processes follow the same trajectory as
one process with the same global batch, up to the order of floating-point sums.
"""

from __future__ import annotations

import copy
import math
import os
import stat
import time
from dataclasses import asdict
from pathlib import Path
from typing import Callable

import torch
import torch.distributed as dist
from torch.nn.parallel import DistributedDataParallel

from choreo.errors import ParameterError
from choreo.fileio import check_output_folder
from choreo.generator import TrainProgress
from choreo.generator.checkpoint import damaged_checkpoint
from choreo.threads import choose_threads

from .checkpoint import load_checkpoint, save_checkpoint
from .config import DiffusionConfig, ModelConfig, TrainConfig
from .data import MusicScaler, WindowTensors
from .losses import diffusion_losses, snr_weights
from .model import Denoiser
from .normalizer import Normalizer
from .schedule import NoiseSchedule
from .style import GENRES

VALIDATION_WINDOWS = 64
BEFORE_AUGMENTATION = {"mirror": False, "stretch": (1.0,), "turns": (0.0,), "genre_balance": 0.0}  # what older checkpoints trained with


class SettingsDiffer(ParameterError, ValueError):
    """A training state made under other settings than this run's: the user's choice, not damage."""


def _step_generator(seed: int, step: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed * 1_000_003 + step)


class Trainer:
    def __init__(self, model_config: ModelConfig, diffusion_config: DiffusionConfig, train_config: TrainConfig,
                 train: WindowTensors, validation: WindowTensors | None, device: torch.device | None = None,
                 rank: int = 0, world: int = 1):
        torch.manual_seed(train_config.seed)
        if train_config.batch_size % world:
            raise ValueError(f"batch size {train_config.batch_size} does not split over {world} processes")
        self.model_config, self.diffusion_config, self.config = model_config, diffusion_config, train_config
        self.device, self.rank, self.world = device or torch.device("cpu"), rank, world
        self.schedule = NoiseSchedule(diffusion_config)
        self.model = Denoiser(model_config, diffusion_config.prediction, self.schedule.alphas_cumprod,
                              diffusion_config.sigma_data).to(self.device)
        self.network = self.model if world == 1 else DistributedDataParallel(self.model)
        self.ema = copy.deepcopy(self.model).eval().requires_grad_(False)
        self.optimizer = torch.optim.AdamW(self.model.parameters(), lr=train_config.learning_rate,
                                           weight_decay=train_config.weight_decay)
        self.normalizer = Normalizer.fit(train.motion.reshape(-1, train.motion.shape[-1])).to(self.device)
        self.music_scaler = MusicScaler.fit(train.music).to(self.device)
        self.train, self.validation = train, validation
        self.weights = train.sampling_weights(train_config.genre_balance)
        self.step = 0
        self.history: list[list[float]] = []  # [step, train loss, validation loss or -1]
        self.started_from: dict | None = None  # {"checkpoint", "step"} of a fine-tuning run's starting point

    def batch(self, generator: torch.Generator, data: WindowTensors, indices: torch.Tensor, share: slice = slice(None)):
        """The random draws of a whole batch (from the CPU generator, so any device and any number of
        processes see the same ones), then this process's ``share`` of it, on its device."""
        t = torch.randint(0, self.schedule.timesteps, (len(indices),), generator=generator)
        noise = torch.randn((len(indices), *data.motion.shape[1:]), generator=generator)
        keep_music = torch.rand(len(indices), generator=generator) >= self.diffusion_config.music_dropout
        keep_style = (torch.rand(len(indices), generator=generator) >= self.diffusion_config.style_dropout)
        keep_style &= data.has_style[indices]
        pace = self.paces(generator, data, indices)
        indices = indices[share]
        on_device = [x[share].to(self.device) for x in (t, noise, keep_music, keep_style, pace)]
        x0 = self.normalizer.normalize(data.motion[indices].to(self.device))
        music = self.music_scaler(data.music[indices].to(self.device))
        return x0, music, *on_device[:4], data.style[indices].to(self.device), on_device[4]

    def paces(self, generator: torch.Generator, data: WindowTensors, indices: torch.Tensor) -> torch.Tensor:
        """The windows' paces, NaN (none given) for the dropped share; all NaN for a network without
        a pace condition, or windows without paces. Drawn either way, so the other draws stay the same."""
        keep = torch.rand(len(indices), generator=generator) >= self.diffusion_config.pace_dropout
        if not self.model_config.pace_condition or data.pace is None:
            return torch.full((len(indices),), float("nan"))
        return torch.where(keep, data.pace[indices], torch.tensor(float("nan")))

    def loss(self, model, x0, music, t, noise, keep_music, keep_style, style, pace=None) -> torch.Tensor:
        x_t = self.schedule.q_sample(x0, t, noise)
        predicted = model(x_t, t, music, style, keep_music=keep_music, keep_style=keep_style, pace=pace)
        gamma = self.diffusion_config.snr_gamma
        weights = snr_weights(self.schedule.alpha_bar(t).to(x0.dtype), gamma) if gamma else None
        clean_share = self.schedule.alpha_bar(t).to(x0.dtype) if self.diffusion_config.legs_weight else None
        terms = diffusion_losses(predicted, x0, self.normalizer, weights, self.diffusion_config.contact_source,
                                 self.diffusion_config.leg_weight, clean_share)
        return terms.total(self.diffusion_config)

    def train_step(self) -> float:
        generator = _step_generator(self.config.seed, self.step)
        if self.weights is None:
            indices = torch.randint(0, len(self.train), (self.config.batch_size,), generator=generator)
        else:
            indices = torch.multinomial(self.weights, self.config.batch_size, replacement=True, generator=generator)
        self.model.train()
        loss = self.loss(self.network, *self.batch(generator, self.train, indices, slice(self.rank, None, self.world)))
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()  # DDP averages the gradients of the ranks' equal shares: the whole batch's gradient
        torch.nn.utils.clip_grad_norm_(self.model.parameters(), 1.0)
        self.optimizer.step()
        self._update_ema()
        self.step += 1
        loss = loss.detach()
        if self.world > 1:
            dist.all_reduce(loss)
            loss /= self.world
        return float(loss)

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
        x0, music, t, noise, _, _, style, _ = self.batch(generator, self.validation, indices)
        keep = torch.ones(count, dtype=torch.bool, device=self.device)
        pace = self.validation.pace[indices].to(self.device) if self.validation.pace is not None else None
        return float(self.loss(self.ema, x0, music, t, noise, keep, keep & self.validation.has_style[indices].to(self.device),
                               style, pace))

    def state(self) -> dict:
        return {
            "model_config": asdict(self.model_config), "diffusion_config": asdict(self.diffusion_config),
            "train_config": asdict(self.config), "genres": list(GENRES), "prompt_kind": self.config.prompt_kind,
            "trained_genres": sorted({g for g in self.train.genres if g}),  # so --style can say what it never saw
            "state_dict": self.model.state_dict(), "ema_state_dict": self.ema.state_dict(),
            "optimizer": self.optimizer.state_dict(), "normalizer": self.normalizer.state_dict(),
            "music_scaler": self.music_scaler.state_dict(), "step": self.step, "history": self.history,
            **({"started_from": self.started_from} if self.started_from else {}),
        }  # fmt: skip

    def check_resumable(self, state: dict) -> None:
        """Refuse to continue a run under other settings: the result would match neither run.
        Only the step budget, the thread count and how often to checkpoint may change on resume."""
        stored = {"model": asdict(ModelConfig(**state["model_config"])),
                  "diffusion": asdict(DiffusionConfig(**state["diffusion_config"])),
                  "train": asdict(TrainConfig(**{**BEFORE_AUGMENTATION, **state["train_config"]}))}
        wanted = {"model": asdict(self.model_config), "diffusion": asdict(self.diffusion_config), "train": asdict(self.config)}
        free = {"max_steps", "num_threads", "checkpoint_every", "validation_every"}
        changed = [f"{key} {stored[part][key]!r} -> {value!r}" for part in wanted for key, value in wanted[part].items()
                   if key not in free and stored[part].get(key) != value]
        if changed:
            raise SettingsDiffer(f"cannot resume: the checkpoint was trained with other settings ({'; '.join(changed)})")

    def load_state(self, state: dict) -> None:
        """Everything is checked against this run as it is loaded: torch takes optimiser moments and
        statistics of any shape, and only the first training step would fail on them."""
        self.model.load_state_dict(state["state_dict"])
        self.ema.load_state_dict(state["ema_state_dict"])
        self.optimizer.load_state_dict(state["optimizer"])
        check_optimizer_fits(self.optimizer)
        self.normalizer = same_shapes(Normalizer.from_state_dict(state["normalizer"]), self.normalizer,
                                      "normalizer").to(self.device)
        self.music_scaler = same_shapes(MusicScaler.from_state_dict(state["music_scaler"]), self.music_scaler,
                                        "music_scaler").to(self.device)
        self.step, self.history = step_count(state["step"]), loss_history(state["history"])
        self.started_from = state.get("started_from")
        if not isinstance(self.started_from, (dict, type(None))):
            raise TypeError(f"started_from is a {type(self.started_from).__name__}, not a dict")

    def start_from(self, state: dict, name: str) -> None:
        """Fine-tune: another run's weights, optimiser and step, under this run's losses and data
        settings. The network must be the same, or that network given a pace condition: then its
        weights are loaded into the new one, whose pace branch starts silent, and the optimiser starts afresh.
        A generation checkpoint (EMA weights only, ``choreo_sgmd.checkpoint.inference_state``) is
        started from too: its EMA weights become the raw ones as well, and the optimiser starts afresh."""
        if "state_dict" not in state:
            weights = {key: value.float() for key, value in state["ema_state_dict"].items()}
            state = {**state, "state_dict": weights, "ema_state_dict": dict(weights),
                     "optimizer": {"state": {}, "param_groups": self.optimizer.state_dict()["param_groups"]}}
        stored = asdict(ModelConfig(**state["model_config"]))
        adds_pace = self.model_config.pace_condition and not stored["pace_condition"]
        free = {"dropout"} | ({"pace_condition"} if adds_pace else set())  # no weight depends on them
        changed = [f"{key} {value!r} -> {getattr(self.model_config, key)!r}" for key, value in stored.items()
                   if getattr(self.model_config, key) != value and key not in free]
        if changed:
            raise SettingsDiffer(f"cannot start from {name}: its network differs ({'; '.join(changed)})")
        if adds_pace:
            state = {**state, "optimizer": self.optimizer.state_dict(),
                     **{key: {**self.model.state_dict(), **state[key]} for key in ("state_dict", "ema_state_dict")}}
        self.load_state(state)
        self.started_from = {"checkpoint": name, "step": int(state["step"])}


def check_optimizer_fits(optimizer: torch.optim.Optimizer) -> None:
    """The optimiser's settings are finite numbers and its moments have their parameters' shapes."""
    for group in optimizer.param_groups:
        numbers = [group.get(key) for key in ("lr", "weight_decay", "eps")] + list(group.get("betas", ()))
        if not all(isinstance(n, (int, float)) and not isinstance(n, bool) and math.isfinite(n) for n in numbers):
            raise ValueError("optimizer settings that are not finite numbers")
        for parameter in group["params"]:
            for name, value in optimizer.state.get(parameter, {}).items():
                if torch.is_tensor(value) and value.dim() and value.shape != parameter.shape:
                    raise ValueError(f"optimizer {name} of shape {tuple(value.shape)} for a parameter of shape "
                                     f"{tuple(parameter.shape)}")


def same_shapes(loaded, current, name: str):
    """``loaded`` (statistics from a checkpoint) if its tensors have the shapes of ``current``'s."""
    for key, value in current.state_dict().items():
        found = loaded.state_dict()[key]
        if not torch.is_tensor(found) or found.shape != value.shape:
            shape = tuple(getattr(found, "shape", ()))
            raise ValueError(f"{name} {key} of shape {shape}, expected {tuple(value.shape)}")
    return loaded


def step_count(value) -> int:
    """The step a state was saved at, a whole number of at least 0 (text or -1 failed only later)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"step {value!r} is not a count of steps")
    return value


def loss_history(rows) -> list[list[float]]:
    """[step, train loss, validation loss] rows, as :meth:`Trainer.state` writes them."""
    numbers = lambda row: all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in row)  # noqa: E731
    if not isinstance(rows, list) or not all(isinstance(r, (list, tuple)) and len(r) == 3 and numbers(r) for r in rows):
        raise ValueError("history is not a list of [step, loss, validation loss] rows")
    return [list(row) for row in rows]


def restore(trainer: Trainer, path: Path, resume: bool) -> None:
    """Continue this run from ``path`` (``resume``), or fine-tune from another run's state. A state
    whose content does not fit is one line naming the file; other settings are refused as such."""
    state = load_checkpoint(path)
    with damaged_checkpoint(path, "SGMD training state"):
        if resume:
            trainer.check_resumable(state)
            trainer.load_state(state)
        else:
            trainer.start_from(state, path.name)


def remove_partial_checkpoints(checkpoint: Path) -> None:
    """Delete temporaries left beside ``checkpoint`` by a run killed while writing one (the
    checkpoint itself is whole). Only files: a folder of that name is not choreo's to remove."""
    for partial in checkpoint.parent.glob(f".{checkpoint.stem}.*.tmp{checkpoint.suffix}"):
        if not stat.S_ISDIR(partial.lstat().st_mode):
            partial.unlink(missing_ok=True)


def process_group() -> tuple[torch.device, int, int]:
    """(device, rank, world size): joins torchrun's process group when WORLD_SIZE > 1 (nccl on
    GPUs, gloo on CPUs); a single process uses the GPU if there is one."""
    world = int(os.environ.get("WORLD_SIZE", "1"))
    cuda = torch.cuda.is_available()
    if world > 1 and not dist.is_initialized():
        dist.init_process_group("nccl" if cuda else "gloo")
    rank = dist.get_rank() if world > 1 else 0
    device = torch.device(f"cuda:{int(os.environ.get('LOCAL_RANK', '0'))}" if cuda else "cpu")
    if cuda:
        torch.cuda.set_device(device)
    return device, rank, world


def train(model_config: ModelConfig, train_config: TrainConfig, train_data: WindowTensors,
          validation_data: WindowTensors | None, out_dir: str | Path, resume: bool = False,
          diffusion_config: DiffusionConfig = DiffusionConfig(),
          progress: Callable[[TrainProgress], None] | None = None, init_from: str | Path | None = None) -> Path:
    """Train until ``train_config.max_steps``; checkpoints go to ``out_dir/last.pt`` atomically.
    ``init_from``: a training state to fine-tune (ignored when resuming this run's own last.pt)."""
    if train_config.num_threads:
        torch.set_num_threads(choose_threads(train_config.num_threads))  # at most the allowed CPUs
    device, rank, world = process_group()
    out_dir = check_output_folder(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    checkpoint = out_dir / "last.pt"
    trainer = Trainer(model_config, diffusion_config, train_config, train_data, validation_data, device, rank, world)
    if rank == 0:
        remove_partial_checkpoints(checkpoint)
    if resume and checkpoint.exists():
        restore(trainer, checkpoint, resume=True)
    elif init_from is not None:
        restore(trainer, Path(init_from), resume=False)
    lead = rank == 0  # validates, writes checkpoints and reports progress
    started, seen, losses = time.perf_counter(), 0, []
    while trainer.step < train_config.max_steps:
        losses.append(trainer.train_step())
        seen += train_config.batch_size
        validation = None
        if lead and (trainer.step % train_config.validation_every == 0 or trainer.step == train_config.max_steps):
            validation = trainer.validation_loss()
        if trainer.step % train_config.checkpoint_every == 0 or trainer.step == train_config.max_steps:
            trainer.history.append([trainer.step, sum(losses) / len(losses), -1.0 if validation is None else validation])
            losses = []
            if lead:
                save_checkpoint(trainer.state(), checkpoint)
        if progress is not None and lead:
            rate = seen / max(time.perf_counter() - started, 1e-9)
            progress(TrainProgress(trainer.step, train_config.max_steps, losses[-1] if losses else trainer.history[-1][1],
                                   rate, validation))
    if world > 1:
        dist.barrier()  # the other ranks leave only once rank 0's last checkpoint is on disk
        dist.destroy_process_group()
    return checkpoint
