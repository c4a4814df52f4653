"""The learnt parts of ChoreoGraph in one module, and their self-describing checkpoint."""

from __future__ import annotations

from pathlib import Path

import torch
from torch import nn

from choreo.errors import InputError
from choreo.fileio import atomic_path

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
    state = {"format_version": FORMAT_VERSION, "generator": GENERATOR_NAME, "model_config": model.config.to_dict(),
             "state_dict": model.state_dict(), **(extra or {})}
    with atomic_path(path) as tmp:
        torch.save(state, tmp)


def load_checkpoint(path: str | Path) -> tuple[ChoreoGraphModel, dict]:
    """The model (eval mode) and the checkpoint's other entries; one-line errors on bad files."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"checkpoint {path} does not exist")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:
        raise InputError(f"{path} is not a readable checkpoint ({type(error).__name__})") from None
    if not isinstance(state, dict) or state.get("generator") != GENERATOR_NAME:
        other = state.get("generator") if isinstance(state, dict) else None
        raise InputError(f"{path} is not a ChoreoGraph checkpoint" + (f" (it is for {other!r})" if other else ""))
    if state.get("format_version") != FORMAT_VERSION:
        raise InputError(f"{path} has checkpoint format {state.get('format_version')}, expected {FORMAT_VERSION}")
    model = ChoreoGraphModel(ModelConfig.from_dict(state["model_config"]))
    model.load_state_dict(state["state_dict"])
    return model.eval(), state
