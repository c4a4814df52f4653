"""SGMD's generation options (no torch here: the CLI checks flags against them before loading)."""

from __future__ import annotations

from dataclasses import dataclass

SAMPLERS = ("ddim", "ddpm")


@dataclass(frozen=True)
class SamplingOptions:
    steps: int = 10  # DDIM steps; docs/results.md has the quality-against-steps curve behind 10 (DDPM: 1000)
    guidance: float = 2.0  # classifier-free guidance weight w on music (paper eq. 6)
    sampler: str = "ddim"
    eta: float = 1.0  # DDIM stochasticity: 1 as EDGE samples, 0 deterministic
    seed: int = 0
    chunk_windows: int = 32  # windows per network call
    block_windows: int = 48  # windows denoised together (2 min of song); longer songs go block by block
    resample: int = 1  # with constraints: run each step this many times, re-noising in between (RePaint)

    def __post_init__(self):
        if self.guidance < 0 or self.steps < 1:
            raise ValueError("guidance must be >= 0 and steps >= 1")
        if self.sampler not in SAMPLERS:
            raise ValueError(f"unknown sampler {self.sampler!r} (use ddim or ddpm)")
        if min(self.chunk_windows, self.block_windows, self.resample) < 1:
            raise ValueError("chunk_windows, block_windows and resample must be >= 1")
