"""SGMD: style-guided motion diffusion (Wang et al.), the `choreo generate` backend.

The bundled checkpoint (``weights/``) was trained on the M2D train split by the command in
docs/sgmd.md; `choreo generate` uses it unless given ``--checkpoint``.
"""

from __future__ import annotations

from pathlib import Path

from choreo.generator import GeneratorPlugin
from choreo.lazy import lazy_exports

from choreo.options import forwarded

from .options import MUSIC_GUIDANCE, SamplingOptions, TrainOptions

__all__ = [
    "DEFAULT_CHECKPOINT", "plugin", "build_generator", "train_from_dataset", "SamplingOptions", "TrainOptions",
    "MUSIC_GUIDANCE",
    # below: what scripts and benchmarks reach past `choreo.load_backend("sgmd")` for (issue 39)
    "train", "Trainer", "TrainConfig", "DiffusionConfig", "model_config", "WindowTensors", "windows_to_tensors",
    "export_for_inference", "genre_styles",
]

# Loaded on first use (PEP 562), so `import choreo_sgmd` (every CLI start finds the plugin) stays torch-free.
_LAZY = {
    "train": ".training",  # train on prepared WindowTensors (tests/fuzz/inputs.py: a tiny checkpoint in seconds)
    "Trainer": ".training",  # one optimiser step at a time (benchmarks/train_step.py: seconds per training step)
    "TrainConfig": ".config",  # what `train` and `Trainer` take: the training run's settings
    "DiffusionConfig": ".config",  # ... the noise schedule and loss
    "model_config": ".config",  # ... a network preset by name ("cpu", "small", "tiny")
    "WindowTensors": ".data",  # ... the training windows as tensors
    "windows_to_tensors": ".data",  # dataset clips cut into WindowTensors (as `train_from_dataset` does)
    "export_for_inference": ".checkpoint",  # a training checkpoint's EMA-only inference copy (what weights/ holds)
    "genre_styles": ".evaluation",  # style vectors for per-window genres (scripts that probe the network directly)
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())


def train_from_dataset(data_dir: str | Path, out_dir: str | Path, options: TrainOptions = TrainOptions(),
                       resume: bool = False, progress=None, load_progress=None) -> Path:
    """Train on a dataset folder (M2D, AIST++ or BVH+audio): its train split, validated on its test split."""
    from dataclasses import replace

    from choreo.datasets import TEST, TRAIN, WindowConfig, load_dataset
    from choreo.music import FEATURE_DIM, RHYTHM_DIM

    from .config import DiffusionConfig, ModelConfig, TrainConfig, model_config
    from .data import Augmentation, windows_to_tensors
    from .style import style_dim
    from .training import train

    renamed = {"max_steps": options.steps, "validation_every": options.checkpoint_every}
    train_config = replace(TrainConfig(prompt_kind=options.prompt), **forwarded(TrainConfig, options),
                           **{name: value for name, value in renamed.items() if value is not None})
    rhythm = {"music_dim": FEATURE_DIM + RHYTHM_DIM} if options.rhythm else {}
    model = model_config(options.config, style_dim=style_dim(options.prompt), **forwarded(ModelConfig, options), **rhythm)
    diffusion = DiffusionConfig(**forwarded(DiffusionConfig, options))
    clips = load_dataset(data_dir, progress=load_progress)
    train_clips = [c for c in clips if c.split in (TRAIN, None)]
    test_clips = [c for c in clips if c.split == TEST]
    if options.hold_out_validation:
        train_clips, test_clips = _without_validation(train_clips)
        train_config = replace(train_config, held_out=tuple(sorted(c.name for c in test_clips)))
    windows = WindowConfig(seconds=model.window_frames * model.frame_stride / 30,
                           stride_seconds=train_config.window_stride_seconds)
    augmentation = Augmentation(mirror=train_config.mirror, stretch=train_config.stretch, turns=train_config.turns)
    train_data = windows_to_tensors(train_clips, windows, options.prompt, model.music_dim, augmentation, model.frame_stride)
    validation = (windows_to_tensors(test_clips, WindowConfig(seconds=5, stride_seconds=2.5), options.prompt,
                                     model.music_dim,
                                     frame_stride=model.frame_stride) if test_clips else None)
    return train(model, train_config, train_data, validation, out_dir, resume=resume, diffusion_config=diffusion,
                 progress=progress, init_from=options.init_from)


def _without_validation(train_clips):
    """(training clips, validation clips): the M2D validation clips taken out of training and
    validated on, so the test split plays no part in the run."""
    from choreo.datasets.m2d import validation_clips

    held = set(validation_clips())
    if not held & {c.name for c in train_clips}:
        raise ValueError("--hold-out-validation needs the M2D dataset (its validation clips were not found)")
    return [c for c in train_clips if c.name not in held], [c for c in train_clips if c.name in held]


def build_generator(checkpoint: str | Path, **options):
    from .generator import SGMDGenerator

    return SGMDGenerator(checkpoint, **options)


DEFAULT_CHECKPOINT = Path(__file__).parent / "weights" / "sgmd-cpu-m2d.pt"

def describe_run(meta: dict) -> str:
    """'ddim 10 steps, guidance 2, style guidance 2, seed 0': how a dance was sampled."""
    styled = meta.get("style") and meta.get("style_guidance", 1.0) != 1.0
    guidance = f"guidance {meta['guidance']:g}" + (f", style guidance {meta['style_guidance']:g}" if styled else "")
    return f"{meta.get('sampler')} {meta.get('steps')} steps, {guidance}, seed {meta.get('seed')}"


plugin = GeneratorPlugin(
    name="sgmd",
    summary="style-guided transformer motion diffusion (choreo generate)",
    ready=DEFAULT_CHECKPOINT.is_file(),
    status="" if DEFAULT_CHECKPOINT.is_file() else f"bundled checkpoint {DEFAULT_CHECKPOINT} is missing; pass --checkpoint",
    factory=build_generator,
    train=train_from_dataset,
    default_checkpoint=DEFAULT_CHECKPOINT,
    options=SamplingOptions,
    train_options=TrainOptions,
    constraints=True,
    describe=describe_run,
)
