"""SGMD's generation options (no torch here: the CLI checks flags against them before loading)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

from choreo.generator.base import check_seed
from choreo.numbers import shown

SAMPLERS = ("ddim", "ddpm")
# With style guidance, music guidance on the low-noise 60 % of the chain only: as good, measured over three
# seeds, and 26 network evaluations per window instead of 30 (docs/results.md, "Style guidance").
STYLED_MUSIC_INTERVAL = (0.0, 0.6)
# The style term lifts the genre recognised in free dances from 72 to 80 %, but under seed motion or
# in-betweening it worsens FID_g and PFC in every seed measured: it pulls away from the given frames.
FREE_STYLE_GUIDANCE, CONSTRAINED_STYLE_GUIDANCE = 2.0, 1.0
# Music guidance, chosen on whole songs: 2.5 (chosen on 5 s windows) rushes whole dances to 1.5 x the real
# dancers' pace; 1.5 keeps it but loses kinetic realism (docs/results.md, "Whole songs").
MUSIC_GUIDANCE = 2.0
# Guidance weights past this only amplify the network's error (at 1e308 the noise overflowed to NaN and
# the whole dance was sampled before the NaN frames were refused); NaN and inf are refused with them.
MAX_GUIDANCE = 20.0
# The longest noise chain a checkpoint may have (checkpoint.DIFFUSION_LIMITS), so the most steps any sampler
# takes: 2^63 steps overflowed torch's linspace (exit 70). The bundled checkpoint's chain is known before it loads.
MAX_STEPS, BUNDLED_TIMESTEPS = 100_000, 1000


@dataclass(frozen=True)
class SamplingOptions:
    steps: int = 10  # DDIM steps; docs/results.md has the quality-against-steps curve behind 10 (DDPM: 1000)
    guidance: float = MUSIC_GUIDANCE  # classifier-free guidance weight w on music (paper eq. 6)
    sampler: str = "ddim"
    eta: float = 1.0  # DDIM stochasticity: 1 as EDGE samples, 0 deterministic
    seed: int = 0
    chunk_windows: int = 32  # windows per network call
    block_windows: int = 48  # windows denoised together (2 min of song); longer songs go block by block
    # Noise levels t/T where music guidance applies (elsewhere w = 1); None: STYLED_MUSIC_INTERVAL when
    # the style is guided too, every level otherwise.
    guidance_interval: tuple[float, float] | None = None
    # Guidance weight on the style (1: none, one evaluation fewer); None: FREE_STYLE_GUIDANCE for a free
    # dance, CONSTRAINED_STYLE_GUIDANCE under constraints (`resolved`; docs/results.md, "Style guidance").
    style_guidance: float | None = None
    style_guidance_interval: tuple[float, float] = (0.0, 1.0)  # noise levels t/T where style guidance applies
    resample: int = 1  # with constraints: run each step this many times, re-noising in between (RePaint)
    bundled_timesteps: ClassVar[int] = BUNDLED_TIMESTEPS  # the CLI checks steps on it before the checkpoint loads

    def __post_init__(self):
        for name in ("guidance", "style_guidance"):
            weight = getattr(self, name)
            if weight is not None and not 0 <= weight <= MAX_GUIDANCE:  # NaN too
                raise ValueError(f"{name} must be 0 to {MAX_GUIDANCE:g}, got {weight:g}")
        if isinstance(self.steps, bool) or not isinstance(self.steps, int) or not 1 <= self.steps <= MAX_STEPS:
            raise ValueError(f"steps must be 1 to {MAX_STEPS:,}, got {shown(str(self.steps))}")
        check_seed(self.seed)
        if self.sampler not in SAMPLERS:
            raise ValueError(f"unknown sampler {self.sampler!r} (use ddim or ddpm)")
        if self.guidance_interval is not None:
            object.__setattr__(self, "guidance_interval", _checked_interval("guidance_interval", self.guidance_interval))
        object.__setattr__(self, "style_guidance_interval",
                           _checked_interval("style_guidance_interval", self.style_guidance_interval))
        if min(self.chunk_windows, self.block_windows, self.resample) < 1:
            raise ValueError("chunk_windows, block_windows and resample must be >= 1")

    def resolved(self, constrained: bool) -> "SamplingOptions":
        """These options with the style guidance decided for a free or a constrained dance."""
        style = CONSTRAINED_STYLE_GUIDANCE if constrained else FREE_STYLE_GUIDANCE
        return replace(self, style_guidance=style if self.style_guidance is None else self.style_guidance)

    def on_chain(self, timesteps: int, steps_given: bool = True) -> "SamplingOptions":
        """These options on a chain of ``timesteps`` noise levels: DDPM without ``steps_given`` walks the
        whole chain; steps the sampler cannot take are a ValueError now, not after the song's analysis."""
        if self.sampler == "ddpm" and not steps_given:
            return replace(self, steps=timesteps)
        if self.sampler == "ddpm" and self.steps != timesteps:
            raise ValueError(f"ddpm runs all {timesteps} steps of the chain: leave out --steps, or use ddim for fewer")
        if self.steps > timesteps:
            raise ValueError(f"steps must be 1 to {timesteps} (the checkpoint's noise levels), got {self.steps}")
        return self

    def guided_steps(self, timesteps: int, style_guided: bool = False) -> tuple[int, int]:
        """The diffusion steps t (inclusive) where music guidance applies, for T = ``timesteps``;
        ``style_guided``: whether the style is guided too (it picks the default interval)."""
        interval = self.guidance_interval
        if interval is None:
            interval = STYLED_MUSIC_INTERVAL if style_guided else (0.0, 1.0)
        return _steps_inside(interval, timesteps)

    def style_guided_steps(self, timesteps: int) -> tuple[int, int]:
        """The diffusion steps t (inclusive) inside ``style_guidance_interval``."""
        return _steps_inside(self.style_guidance_interval, timesteps)


def _checked_interval(name: str, interval) -> tuple[float, float]:
    interval = tuple(float(b) for b in interval)
    low, high = interval if len(interval) == 2 else (1.0, 0.0)
    if not 0.0 <= low <= high <= 1.0:
        raise ValueError(f"{name} must be two noise levels 0 <= low <= high <= 1, got {interval}")
    return interval


def _steps_inside(interval: tuple[float, float], timesteps: int) -> tuple[int, int]:
    low, high = interval
    return round(low * (timesteps - 1)), round(high * (timesteps - 1))


@dataclass(frozen=True)
class TrainOptions:
    """What `choreo train sgmd` takes. None leaves the setting at its configuration's default
    (config.py: TrainConfig, DiffusionConfig, the model preset), so each default lives there only."""

    config: str = "cpu"  # model preset (config.PRESETS)
    steps: int | None = None
    batch_size: int | None = None
    prompt: str = "description"  # style prompt kind
    style_mode: str | None = None
    style_init: str | None = None
    style_dropout: float | None = None
    checkpoint_every: int | None = None  # also the validation interval
    seed: int | None = None
    mirror: bool | None = None
    stretch: tuple[float, ...] | None = None
    turns: tuple[float, ...] | None = None
    genre_balance: float | None = None
    rhythm: bool | None = None  # True: beat phase and tempo channels beside the 35-d features
    prediction: str | None = None
    sigma_data: float | None = None
    snr_gamma: float | None = None
    reconstruction_weight: float | None = None  # the x0 term's weight (EDGE: 0.636), the one term on every rotation
    foot_weight: float | None = None  # the foot term's weight (EDGE: 10.942)
    contact_source: str | None = None  # contacts the foot term pins: "predicted" (EDGE) or "target" (the data's)
    stepping_weight: float | None = None  # feet's world speeds against the data's (0: off)
    leg_weight: float | None = None  # the legs' rotation channels' weight in the x0 term (1: as every channel)
    root_speed_weight: float | None = None  # the root's horizontal speed against the data's (0: off)
    init_from: str | None = None  # a training state to fine-tune from (same network)
    hold_out_validation: bool = False  # M2D: train without the validation clips, validate on them
