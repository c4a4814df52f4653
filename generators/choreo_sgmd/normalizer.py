"""Per-channel min-max scaling of frame vectors to [-1, 1], fitted on the training frames.

Stored in checkpoints as two plain tensors (EDGE pickles a scaler object instead).
"""

from __future__ import annotations

import torch

MIN_RANGE = 1e-4  # channels that never change (e.g. a contact always on) keep a usable scale


class Normalizer:
    def __init__(self, low: torch.Tensor, high: torch.Tensor):
        self.low, self.high = low.float(), high.float()

    @classmethod
    def fit(cls, frames: torch.Tensor) -> "Normalizer":
        """frames (N, D) -> the per-channel range."""
        low, high = frames.min(dim=0).values, frames.max(dim=0).values
        span = (high - low).clamp(min=MIN_RANGE)
        center = (high + low) / 2
        return cls(center - span / 2, center + span / 2)

    def normalize(self, x: torch.Tensor) -> torch.Tensor:
        return (x - self.low) / (self.high - self.low) * 2 - 1

    def denormalize(self, x: torch.Tensor) -> torch.Tensor:
        return (x + 1) / 2 * (self.high - self.low) + self.low

    def to(self, device) -> "Normalizer":
        return Normalizer(self.low.to(device), self.high.to(device))

    def state_dict(self) -> dict[str, torch.Tensor]:
        return {"low": self.low, "high": self.high}

    @classmethod
    def from_state_dict(cls, state: dict[str, torch.Tensor]) -> "Normalizer":
        return cls(state["low"], state["high"])
