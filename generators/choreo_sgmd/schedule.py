"""Noise schedule and samplers, separate from the network (diffusers' scheduler design).

The network predicts x0. A sampler turns that prediction at step t into the sample at the previous
step: :class:`DDPMSampler` follows the full posterior q(x_{t-1} | x_t, x0) (Ho et al. 2020), and
:class:`DDIMSampler` takes strided steps (Song et al. 2021, eq. 12), stochastic with eta = 1 as
EDGE samples, deterministic with eta = 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from .config import DiffusionConfig


def cosine_alphas_cumprod(timesteps: int, offset: float = 0.008, max_beta: float = 0.999) -> torch.Tensor:
    """(T,) alpha_bar_t of the cosine schedule (Nichol & Dhariwal 2021), betas capped at max_beta."""
    def alpha_bar(step: float) -> float:
        return math.cos((step / timesteps + offset) / (1 + offset) * math.pi / 2) ** 2

    betas = [min(1 - alpha_bar(i + 1) / alpha_bar(i), max_beta) for i in range(timesteps)]
    return torch.cumprod(1 - torch.tensor(betas, dtype=torch.float64), dim=0)


class NoiseSchedule:
    """q(x_t | x0) = N(sqrt(alpha_bar_t) x0, (1 - alpha_bar_t) I) for t = 0..T-1."""

    def __init__(self, config: DiffusionConfig = DiffusionConfig()):
        self.timesteps = config.timesteps
        self.alphas_cumprod = cosine_alphas_cumprod(config.timesteps, config.cosine_offset, config.max_beta)

    def alpha_bar(self, t: torch.Tensor) -> torch.Tensor:
        return self.alphas_cumprod.to(t.device)[t]

    def q_sample(self, x0: torch.Tensor, t: torch.Tensor, noise: torch.Tensor) -> torch.Tensor:
        """Noise clean samples x0 (B, ...) to steps t (B,)."""
        alpha_bar = self.alpha_bar(t).to(x0.dtype).view(-1, *([1] * (x0.dim() - 1)))
        return alpha_bar.sqrt() * x0 + (1 - alpha_bar).sqrt() * noise


@dataclass
class StepOutput:
    prev_sample: torch.Tensor  # x_{t_prev}
    pred_original_sample: torch.Tensor  # the (clipped) x0 used for the step


class DDIMSampler:
    """Strided sampling with ``num_steps`` network evaluations; eta interpolates DDIM (0) to DDPM-like (1)."""

    def __init__(self, schedule: NoiseSchedule, eta: float = 1.0, clip_x0: bool = True):
        self.schedule, self.eta, self.clip_x0 = schedule, eta, clip_x0
        self.timesteps = torch.arange(schedule.timesteps - 1, -1, -1)

    def set_timesteps(self, num_steps: int) -> None:
        if not 1 <= num_steps <= self.schedule.timesteps:
            raise ValueError(f"steps must be in 1..{self.schedule.timesteps}, got {num_steps}")
        steps = torch.linspace(self.schedule.timesteps - 1, 0, num_steps).round().long()
        self.timesteps = torch.unique_consecutive(steps)

    def previous(self, t: int) -> int:
        index = int((self.timesteps == t).nonzero()[0, 0])
        return int(self.timesteps[index + 1]) if index + 1 < len(self.timesteps) else -1

    def step(self, x0: torch.Tensor, t: int, sample: torch.Tensor, generator: torch.Generator | None = None) -> StepOutput:
        if self.clip_x0:
            x0 = x0.clamp(-1, 1)
        t_prev = self.previous(t)
        alpha_bar = float(self.schedule.alphas_cumprod[t])
        if t_prev < 0:
            return StepOutput(x0, x0)
        alpha_bar_prev = float(self.schedule.alphas_cumprod[t_prev])
        eps = (sample - math.sqrt(alpha_bar) * x0) / math.sqrt(1 - alpha_bar)
        sigma = self.eta * math.sqrt((1 - alpha_bar_prev) / (1 - alpha_bar) * (1 - alpha_bar / alpha_bar_prev))
        direction = math.sqrt(max(1 - alpha_bar_prev - sigma**2, 0.0)) * eps
        prev = math.sqrt(alpha_bar_prev) * x0 + direction
        if sigma > 0:
            prev = prev + sigma * torch.randn(sample.shape, generator=generator, dtype=sample.dtype, device=sample.device)
        return StepOutput(prev, x0)


class DDPMSampler(DDIMSampler):
    """Ancestral sampling through every step: x_{t-1} ~ q(x_{t-1} | x_t, x0)."""

    def set_timesteps(self, num_steps: int) -> None:
        if num_steps != self.schedule.timesteps:
            raise ValueError(f"DDPM runs all {self.schedule.timesteps} steps; use DDIM for fewer")
        super().set_timesteps(num_steps)

    def step(self, x0: torch.Tensor, t: int, sample: torch.Tensor, generator: torch.Generator | None = None) -> StepOutput:
        if self.clip_x0:
            x0 = x0.clamp(-1, 1)
        if t == 0:
            return StepOutput(x0, x0)
        alpha_bar, alpha_bar_prev = float(self.schedule.alphas_cumprod[t]), float(self.schedule.alphas_cumprod[t - 1])
        beta = 1 - alpha_bar / alpha_bar_prev
        mean = (math.sqrt(alpha_bar_prev) * beta / (1 - alpha_bar)) * x0 + (
            math.sqrt(1 - beta) * (1 - alpha_bar_prev) / (1 - alpha_bar)) * sample
        variance = beta * (1 - alpha_bar_prev) / (1 - alpha_bar)
        noise = torch.randn(sample.shape, generator=generator, dtype=sample.dtype, device=sample.device)
        return StepOutput(mean + math.sqrt(variance) * noise, x0)


def make_sampler(name: str, schedule: NoiseSchedule, steps: int, eta: float = 1.0) -> DDIMSampler:
    sampler = {"ddim": DDIMSampler, "ddpm": DDPMSampler}.get(name)
    if sampler is None:
        raise ValueError(f"unknown sampler {name!r} (use ddim or ddpm)")
    instance = sampler(schedule, eta=eta)
    instance.set_timesteps(steps)
    return instance
