"""SGMD: style-guided motion diffusion (Wang et al.), the `choreo generate` backend.

The bundled checkpoint (``weights/``) was trained on the M2D train split by the command in
docs/sgmd.md; `choreo generate` uses it unless given ``--checkpoint``.
"""

from __future__ import annotations

from pathlib import Path

from choreo.generator import GeneratorPlugin

from .options import SamplingOptions


def train_from_dataset(data_dir: str | Path, out_dir: str | Path, config: str = "cpu", resume: bool = False,
                       max_steps: int | None = None, prompt_kind: str = "description", batch_size: int | None = None,
                       style_mode: str | None = None, style_init: str | None = None, style_dropout: float | None = None,
                       checkpoint_every: int | None = None, seed: int | None = None, mirror: bool | None = None,
                       stretch: tuple[float, ...] | None = None, turns: tuple[float, ...] | None = None,
                       genre_balance: float | None = None,
                       rhythm: bool | None = None, prediction: str | None = None, snr_gamma: float | None = None,
                       sigma_data: float | None = None,
                       progress=None,
                       load_progress=None) -> Path:
    """Train on a dataset folder (M2D, AIST++ or BVH+audio): its train split, validated on its test split."""
    from dataclasses import replace

    from choreo.datasets import TEST, TRAIN, WindowConfig, load_dataset

    from .config import DiffusionConfig, TrainConfig, model_config
    from choreo.music import FEATURE_DIM

    from .data import Augmentation, windows_to_tensors
    from .style import style_dim
    from .training import train

    train_overrides = {"max_steps": max_steps, "batch_size": batch_size, "seed": seed,
                       "checkpoint_every": checkpoint_every, "validation_every": checkpoint_every,
                       "mirror": mirror, "stretch": stretch, "turns": turns, "genre_balance": genre_balance}
    train_config = replace(TrainConfig(prompt_kind=prompt_kind), **{k: v for k, v in train_overrides.items() if v is not None})
    model_overrides = {"style_mode": style_mode, "style_init": style_init,
                       "music_dim": FEATURE_DIM if rhythm is False else None}
    model = model_config(config, style_dim=style_dim(prompt_kind), **{k: v for k, v in model_overrides.items() if v})
    diffusion_overrides = {"style_dropout": style_dropout, "prediction": prediction, "snr_gamma": snr_gamma,
                           "sigma_data": sigma_data}
    diffusion = DiffusionConfig(**{k: v for k, v in diffusion_overrides.items() if v is not None})
    clips = load_dataset(data_dir, progress=load_progress)
    train_clips = [c for c in clips if c.split in (TRAIN, None)]
    test_clips = [c for c in clips if c.split == TEST]
    windows = WindowConfig(seconds=model.window_frames * model.frame_stride / 30,
                           stride_seconds=train_config.window_stride_seconds)
    augmentation = Augmentation(mirror=train_config.mirror, stretch=train_config.stretch, turns=train_config.turns)
    train_data = windows_to_tensors(train_clips, windows, prompt_kind, model.music_dim, augmentation, model.frame_stride)
    validation = (windows_to_tensors(test_clips, WindowConfig(seconds=5, stride_seconds=2.5), prompt_kind, model.music_dim,
                                     frame_stride=model.frame_stride) if test_clips else None)
    return train(model, train_config, train_data, validation, out_dir, resume=resume, diffusion_config=diffusion,
                 progress=progress)


def build_generator(checkpoint: str | Path, **options):
    from .generator import SGMDGenerator

    return SGMDGenerator(checkpoint, **options)


DEFAULT_CHECKPOINT = Path(__file__).parent / "weights" / "sgmd-cpu-m2d.pt"

plugin = GeneratorPlugin(
    name="sgmd",
    summary="style-guided transformer motion diffusion (choreo generate)",
    ready=DEFAULT_CHECKPOINT.is_file(),
    status="" if DEFAULT_CHECKPOINT.is_file() else f"bundled checkpoint {DEFAULT_CHECKPOINT} is missing; pass --checkpoint",
    factory=build_generator,
    train=train_from_dataset,
    default_checkpoint=DEFAULT_CHECKPOINT,
    options=SamplingOptions,
    constraints=True,
)
