"""The pace condition (docs/sgmd.md, "Pace"): each window's travel speed as one more input."""

import math
import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch

from choreo.datasets import WindowConfig, load_dataset, window_starts
from choreo.errors import ParameterError
from choreo.finishing.pace import ANY_GENRE_PACE
from choreo.generator import GenerationRequest
from choreo.music import Music
from choreo.motion.travel import ground_track, track_pace
from choreo_sgmd.checkpoint import load_checkpoint
from choreo_sgmd.config import DiffusionConfig, TrainConfig, model_config
from choreo_sgmd.data import windows_to_tensors
from choreo_sgmd.generator import SGMDGenerator
from choreo_sgmd.model import Denoiser
from choreo_sgmd.options import SamplingOptions
from choreo_sgmd.training import Trainer, _step_generator

from tests.conftest import synthetic_windows
from tests.sgmd.test_training import FIXTURES, train_command

TINY = model_config("tiny", style_dim=8)
PACED = replace(TINY, pace_condition=True)
NAN = float("nan")


def test_a_new_pace_branch_leaves_the_network_as_it_was():
    torch.manual_seed(0)
    plain, paced = Denoiser(TINY), Denoiser(PACED)
    missing = paced.load_state_dict(plain.state_dict(), strict=False).missing_keys
    assert missing and all(key.startswith(("pace_mlp.", "null_pace")) for key in missing)
    x_t, music, style = torch.randn(3, 150, TINY.frame_dim), torch.randn(3, 150, TINY.music_dim), torch.randn(3, 8)
    t = torch.tensor([10, 500, 900])
    with torch.no_grad():
        expected = plain(x_t, t, music, style)
        for pace in (None, torch.tensor([0.2, 0.8, NAN])):
            torch.testing.assert_close(paced(x_t, t, music, style, pace=pace), expected)
        for parameter in paced.parameters():  # once it has learnt something, the pace and its absence count
            parameter.add_(0.1 * torch.randn_like(parameter))
        given, none = paced(x_t, t, music, style, pace=torch.tensor([0.2, 0.2, 0.2])), paced(x_t, t, music, style)
    assert not torch.allclose(given, none)


def test_every_window_carries_the_pace_of_its_stretch_of_track():
    clips = [c for c in load_dataset(FIXTURES) if c.features is not None]
    config = WindowConfig(seconds=2, stride_seconds=1)
    windows = windows_to_tensors(clips, config, "onehot")
    expected = []
    for clip in clips:
        track = ground_track(clip.motion.root_positions, clip.motion.fps)
        expected += [track_pace(track[s:s + config.length], clip.motion.fps) for s in window_starts(clip.motion.num_frames, config)]
    torch.testing.assert_close(windows.pace, torch.tensor(expected, dtype=torch.float32))
    assert windows.pace.min() >= 0 and windows.pace.max() > 0.05  # the fixtures' dancers travel


def test_training_shows_the_pace_to_a_paced_network_only_and_drops_some():
    data = synthetic_windows(count=64)
    data.pace = torch.linspace(0.1, 1.0, 64)
    indices = torch.arange(64)
    dropping = DiffusionConfig(pace_dropout=0.5)
    paced = Trainer(PACED, dropping, TrainConfig(batch_size=64), data, None).batch(_step_generator(0, 3), data, indices)[-1]
    shown = ~torch.isnan(paced)
    assert 10 < shown.sum() < 54  # about half dropped
    torch.testing.assert_close(paced[shown], data.pace[shown])
    plain = Trainer(TINY, dropping, TrainConfig(batch_size=64), data, None).batch(_step_generator(0, 3), data, indices)[-1]
    assert torch.isnan(plain).all()
    with pytest.raises(ValueError, match="pace_dropout"):
        DiffusionConfig(pace_dropout=1.0)


def test_a_trained_network_gains_a_pace_condition_and_is_asked_for_its_genres_pace(tmp_path):
    plain = tmp_path / "plain"
    subprocess.run(train_command(plain, "--steps", "10"), check=True, capture_output=True)
    paced = tmp_path / "paced"
    tuned = subprocess.run(train_command(paced, "--steps", "12", "--pace-condition", "--init-from", str(plain / "last.pt")),
                           capture_output=True, text=True)
    assert tuned.returncode == 0, tuned.stderr[-2000:]
    state = load_checkpoint(paced / "last.pt")
    assert state["model_config"]["pace_condition"] and state["step"] == 12
    assert state["started_from"] == {"checkpoint": "last.pt", "step": 10}
    assert any(key.startswith("pace_mlp.") for key in state["ema_state_dict"])
    refused = subprocess.run(train_command(tmp_path / "back", "--steps", "14", "--init-from", str(paced / "last.pt")),
                             capture_output=True, text=True)
    assert refused.returncode != 0 and "pace_condition True -> False" in refused.stderr  # a pace is not dropped

    song = Path(__file__).parents[2] / "examples" / "drum_and_bass_174bpm.wav"
    music = Music.from_file(song, end=6.0)
    generator = SGMDGenerator(paced / "last.pt")
    free = generator.generate(GenerationRequest(music, seed=0, options={"steps": 2}))
    assert free.metadata["pace_asked"] == ANY_GENRE_PACE  # no style: all real dancers' median pace
    popping = generator.generate(GenerationRequest(music, style="pop", seed=0, options={"steps": 2}))
    assert popping.metadata["genre"] == "pop" and popping.metadata["pace_asked"] is None  # M2D has no pop dancers
    asked = generator.generate(GenerationRequest(music, seed=0, options={"steps": 2, "pace": 0.2}))
    assert asked.metadata["pace_asked"] == 0.2
    assert not np.array_equal(asked.root_positions, free.root_positions)


def test_a_pace_for_a_network_without_one_is_refused(tiny_generator):
    with pytest.raises(ParameterError, match="not trained with a pace condition"):
        tiny_generator.for_genres(SamplingOptions(pace=0.4), ["waltz"])
    assert tiny_generator.for_genres(SamplingOptions(), ["waltz"]).pace is None
    for bad in (-0.1, NAN, 4.0):
        with pytest.raises(ValueError, match="pace"):
            SamplingOptions(pace=bad)
    assert not math.isnan(SamplingOptions(pace=0.0).pace)
