"""The learnt parts of ChoreoGraph in one module, and their self-describing checkpoint."""

from __future__ import annotations

from pathlib import Path

import torch
from torch import nn

from choreo.generator.checkpoint import read_checkpoint, write_checkpoint

from .config import CLIP_FRAMES, NUM_JOINTS, WINDOW_FRAMES, ModelConfig
from .style import StyleModel
from .tempo import MotionTempoEstimator, MusicTempoEstimator

FORMAT_VERSION = 1
GENERATOR_NAME = "graph"


class ChoreoGraphModel(nn.Module):
    def __init__(self, config: ModelConfig):
        super().__init__()
        self.config = config
        self.style = StyleModel(config.style)
        self.motion_tempo = MotionTempoEstimator(config.tempo, CLIP_FRAMES, NUM_JOINTS * 3)
        self.music_tempo = MusicTempoEstimator(config.tempo, WINDOW_FRAMES, config.style.n_mels)

    @torch.no_grad()
    def motion_style(self, positions: torch.Tensor) -> torch.Tensor:
        return self.style.motion(positions)

    @torch.no_grad()
    def music_style(self, mel: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Style vectors and predicted motion-beat counts of 4 s music windows."""
        style = self.style.music(mel)
        return style, self.style.beats(style)

    @torch.no_grad()
    def motion_tempo_density(self, positions: torch.Tensor) -> torch.Tensor:
        return self.motion_tempo.encode_motion(positions.flatten(2))[0]

    @torch.no_grad()
    def music_tempo_density(self, mel: torch.Tensor) -> torch.Tensor:
        return self.music_tempo(mel)


def save_checkpoint(model: ChoreoGraphModel, path: str | Path, extra: dict | None = None) -> None:
    state = {"model_config": model.config.to_dict(), "state_dict": model.state_dict(), **(extra or {})}
    write_checkpoint(state, path, GENERATOR_NAME, FORMAT_VERSION)


def load_checkpoint(path: str | Path) -> tuple[ChoreoGraphModel, dict]:
    """The model (eval mode) and the checkpoint's other entries; one-line errors on bad files."""
    state = read_checkpoint(path, GENERATOR_NAME, "a ChoreoGraph", FORMAT_VERSION)
    model = ChoreoGraphModel(ModelConfig.from_dict(state["model_config"]))
    model.load_state_dict(state["state_dict"])
    return model.eval(), state
