"""SGMD's generation options (no torch here: the CLI checks flags against them before loading)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

from choreo.generator.base import check_seed
from choreo.options import forwarded, option
from choreo.numbers import shown

SAMPLERS = ("ddim", "ddpm")
# With style guidance, music guidance on the low-noise part of the chain only: as good, and fewer network
# evaluations per window (docs/results.md, "Style guidance").
STYLED_MUSIC_INTERVAL = (0.0, 0.6)
# The style term makes a free dance's genre clearer, but under seed motion or in-betweening it pulls away
# from the given frames (docs/results.md, "Style guidance").
FREE_STYLE_GUIDANCE, CONSTRAINED_STYLE_GUIDANCE = 2.0, 1.0
# Music guidance, chosen on whole songs: more rushes whole dances past the real dancers' pace, less loses
# kinetic realism (docs/results.md, "Whole songs").
MUSIC_GUIDANCE = 2.0
# The share of the guidance terms the root's floor position gets, per style genre (1 for the others, a free-text
# style, none or a schedule of several). The guidance is what rushes the travel: before the pace pass a guided
# waltz travels 1.0-1.4 x its dancer's pace on the validation songs and up to 1.8 x on songs it has not heard,
# beyond what the pass may undo; unguided 0.7-1.0 x, with less jerk (docs/results.md, "The travel's guidance").
GENRE_TRAVEL_GUIDANCE = {"waltz": 0.0}
# Guidance weights past this only amplify the network's error (at 1e308 the noise overflowed to NaN and
# the whole dance was sampled before the NaN frames were refused); NaN and inf are refused with them.
MAX_GUIDANCE = 20.0
# The longest noise chain a checkpoint may have (checkpoint.DIFFUSION_LIMITS), so the most steps any sampler
# takes: 2^63 steps overflowed torch's linspace (exit 70). The bundled checkpoint's chain is known before it loads.
MAX_STEPS, BUNDLED_TIMESTEPS = 100_000, 1000


@dataclass(frozen=True, kw_only=True)
class SamplingOptions:
    # DDIM steps (ddpm: the whole chain); docs/results.md, "Sampler and guidance", has the curve behind the default
    steps: int = option(10, "Sampling steps (ddpm walks the checkpoint's whole chain).")
    # classifier-free guidance weight w on the music (paper eq. 6)
    guidance: float = option(MUSIC_GUIDANCE, "Classifier-free guidance weight on the music (1 = none).")
    sampler: str = option("ddim", f"Sampler: {' or '.join(SAMPLERS)} (ddpm: the full chain, slow).")
    eta: float = 1.0  # DDIM stochasticity: 1 as EDGE samples, 0 deterministic
    seed: int = 0
    chunk_windows: int = 4  # windows per network call: the pieces threads share (choreo.threads)
    block_windows: int = 48  # windows denoised together (2 min of song); longer songs go block by block
    # Noise levels t/T where music guidance applies (elsewhere w = 1); None: STYLED_MUSIC_INTERVAL when
    # the style is guided too, every level otherwise.
    guidance_interval: tuple[float, float] | None = None
    # Guidance weight on the style (1: none, one evaluation fewer); None: FREE_STYLE_GUIDANCE for a free
    # dance, CONSTRAINED_STYLE_GUIDANCE under constraints (`resolved`; docs/results.md, "Style guidance").
    style_guidance: float | None = option(
        None, "Guidance weight on the --style prompt (1 = none).", "--style-guidance",
        default_text=f"{FREE_STYLE_GUIDANCE:g}, or {CONSTRAINED_STYLE_GUIDANCE:g} where frames are given")
    style_guidance_interval: tuple[float, float] = (0.0, 1.0)  # noise levels t/T where style guidance applies
    resample: int = 1  # with constraints: run each step this many times, re-noising in between (RePaint)
    # m/s along the ground track, for a checkpoint trained with a pace condition (docs/sgmd.md, "Pace");
    # None: the genre's real pace (choreo.finishing.pace), or none for a free-text style
    pace: float | None = None
    # the share of the guidance terms the root's floor position gets (0: it travels as the conditional prediction);
    # None: its genre's (GENRE_TRAVEL_GUIDANCE)
    travel_guidance: float | None = option(
        None, "Share of the guidance the root's travel across the floor gets (0 = unguided, 1 = as the body).",
        "--travel-guidance", default_text="0 for waltz, 1 otherwise")
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
        if self.pace is not None and not 0.0 <= self.pace <= 3.0:  # NaN too; real dancers' fastest genre: 1.2
            raise ValueError(f"pace must be 0 to 3 m/s, got {self.pace:g}")
        if self.travel_guidance is not None and not 0.0 <= self.travel_guidance <= 1.0:  # NaN too
            raise ValueError(f"travel_guidance must be 0 to 1, got {self.travel_guidance:g}")
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


@dataclass(frozen=True, kw_only=True)
class TrainOptions:
    """What `choreo train sgmd` takes. None leaves the setting at its configuration's default
    (config.py: TrainConfig, DiffusionConfig, the model preset), so each default lives there only;
    a field of the same name as a configuration's is forwarded to it (``train_from_dataset``)."""

    config: str = option("cpu", "Model configuration: a preset of config.PRESETS (cpu, cpu15, small, paper, tiny).")
    steps: int | None = option(None, "Train until this many optimiser steps.")
    batch_size: int | None = option(None, "Windows per step.")
    prompt: str = option("description", "Style prompt kind: description, name or onehot.")
    style_mode: str | None = option(None, "Style conditioning: modulation (the paper's), concat or none (EDGE).")
    style_init: str | None = option(None, "The style FC's initial weights: random, or zero (starts as the no-style model).")
    style_dropout: float | None = option(None, "Share of training windows shown without their style.")
    dropout: float | None = option(None, "The network's dropout while training (with --init-from it may differ from the "
                                         "started-from network's: the weights are the same).")
    checkpoint_every: int | None = option(None, "Steps between checkpoints and validations.")
    seed: int | None = option(None, "Seed of initialisation, batches and noise.")
    mirror: bool | None = option(None, "Also train on mirrored dances (docs/sgmd.md).", "--mirror/--no-mirror")
    stretch: tuple[float, ...] | None = option(None, "Paces to also train at, the music stretched along, e.g. 0.85,1,1.18.")
    turns: tuple[float, ...] | None = option(None, "Also train on every clip turned by these angles about the vertical, "
                                                   "e.g. 0,90,180,270.")
    genre_balance: float | None = option(None, "0 draws windows uniformly, 1 draws every genre equally.")
    rhythm: bool | None = option(None, "Feed beat phase and tempo to the model.", "--rhythm/--no-rhythm")
    pace_condition: bool | None = option(None, "Give the network each window's pace as a condition (with --init-from: "
                                               "a network without one gains it).", "--pace-condition/--no-pace-condition")
    prediction: str | None = option(None, "What the network predicts: x0 or v.")
    sigma_data: float | None = option(None, "With --prediction v: the data's standard deviation the skip assumes.")
    snr_gamma: float | None = option(None, "Weigh each window's loss by min(SNR, this) (min-SNR; 0: off).")
    reconstruction_weight: float | None = option(None, "Weight of the x0 reconstruction loss.")
    foot_weight: float | None = option(None, "Weight of the foot term: planted feet that move.")
    contact_source: str | None = option(None, "Contacts the foot term pins: predicted (the model's own, EDGE) or "
                                              "target (the data's).")
    stepping_weight: float | None = option(None, "Weight of the feet's world speeds against the data's, in (m/s)^2.")
    leg_weight: float | None = option(None, "Weight of the legs' rotation channels inside the x0 term.")
    root_speed_weight: float | None = option(None, "Weight of the root's horizontal speed against the data's, "
                                                   "direction-free, in (m/s)^2.")
    pace_weight: float | None = option(None, "Weight of each window's pace (its root's floor path over a second) "
                                             "against the data's, in (m/s)^2.")
    legs_weight: float | None = option(None, "Weight of the knees, ankles and feet around the pelvis against the data's "
                                             "(positions in m^2 + speeds in (m/s)^2), by each window's signal share.")
    legs_speed_weight: float | None = option(None, "Weight of each window's mean speed of the knees, ankles and feet "
                                                   "around the pelvis against the data's, in (m/s)^2.")
    init_from: str | None = option(None, "Fine-tune from this training state or generation checkpoint (same network; "
                                         "its step count carries on; a generation checkpoint's optimiser starts afresh).",
                                   existing_file=True)
    hold_out_validation: bool = option(False, "On M2D: train without the validation clips (docs/m2d.md) and "
                                              "validate on them.", "--hold-out-validation")

    @staticmethod
    def shown_defaults() -> dict:
        """What each None stands for, as help shows it (imports the configurations)."""
        from .config import DiffusionConfig, TrainConfig, model_config

        train = TrainConfig()
        configs = {**vars(train), **vars(DiffusionConfig()), **vars(model_config("cpu"))}
        return {"steps": train.max_steps, "rhythm": False, **forwarded(TrainOptions, configs)}

