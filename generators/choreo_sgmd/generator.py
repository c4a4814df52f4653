"""`SGMDGenerator`: a trained checkpoint turned into the core's Generator interface."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import torch

from choreo.errors import ParameterError
from choreo.generator import GenerationRequest, Generator
from choreo.motion import Motion, vector_to_motion

from .checkpoint import load_checkpoint
from .config import DiffusionConfig, ModelConfig
from .data import MusicScaler
from .model import Denoiser
from .normalizer import Normalizer
from .sampling import SamplingOptions, sample_long
from .schedule import NoiseSchedule
from .style import resolve_style


class SGMDGenerator(Generator):
    name = "sgmd"

    def __init__(self, checkpoint: str | Path, use_ema: bool = True):
        state = load_checkpoint(checkpoint)
        self.checkpoint = Path(checkpoint)
        self.model_config = ModelConfig(**state["model_config"])
        self.diffusion_config = DiffusionConfig(**state["diffusion_config"])
        self.prompt_kind = state["prompt_kind"]
        self.model = Denoiser(self.model_config).eval()
        self.model.load_state_dict(state["ema_state_dict" if use_ema else "state_dict"])
        self.normalizer = Normalizer.from_state_dict(state["normalizer"])
        self.music_scaler = MusicScaler.from_state_dict(state["music_scaler"])
        self.schedule = NoiseSchedule(self.diffusion_config)
        self.trained_steps = int(state["step"])

    def generate(self, request: GenerationRequest, progress: Callable[[float], None] | None = None) -> Motion:
        options = SamplingOptions(**{k: v for k, v in request.options.items() if k in SamplingOptions.__dataclass_fields__})
        if request.seed is not None:
            options = SamplingOptions(**{**options.__dict__, "seed": request.seed})
        if options.guidance < 0 or options.steps < 1:
            raise ParameterError("guidance must be >= 0 and steps >= 1")
        style = resolve_style(request.style, self.prompt_kind)
        style_vector = torch.zeros(1, self.model_config.style_dim) if style.vector is None else torch.from_numpy(style.vector)[None].float()
        music = self.music_scaler(torch.from_numpy(request.music.features).float())
        x0, evaluations = sample_long(self.model, self.schedule, music, style_vector, style.vector is not None,
                                      self.model_config.frame_dim, self.model_config.window_frames, options, progress)
        motion, _ = vector_to_motion(self.normalizer.denormalize(x0).numpy(), fps=request.music.fps)
        motion.metadata = {
            "generator": "sgmd", "checkpoint": self.checkpoint.name, "style": request.style, "genre": style.genre,
            "style_notice": style.notice, "seed": options.seed, "steps": options.steps, "guidance": options.guidance,
            "sampler": options.sampler, "network_evaluations": evaluations,
        }  # fmt: skip
        return motion
