"""Shared fixtures: a tiny SGMD checkpoint trained in seconds on synthetic windows."""

import os
from pathlib import Path

import numpy as np
import pytest
import torch

from choreo.music import FEATURE_DIM
from choreo_sgmd.data import WindowTensors

# Dances with the same seed are equal only at the same thread count (float32 sums in another order),
# and the thread policy (choreo.threads) follows the machine's load: tests comparing two runs pin it,
# here and in every CLI process they start. tests/test_threads.py tests the policy itself.
os.environ.setdefault("OMP_NUM_THREADS", "2")


def synthetic_windows(count=4, frames=150, seed=0, music_dim=FEATURE_DIM) -> WindowTensors:
    g = torch.Generator().manual_seed(seed)
    t = torch.arange(frames) / 30.0
    motion = torch.zeros(count, frames, 151)
    motion[..., 4:7] = torch.stack([torch.sin(t), 0.9 + 0.05 * torch.sin(4 * t), torch.cos(t)], -1)
    motion[..., 7:] = torch.tensor([1.0, 0, 0, 0, 1, 0]).repeat(24) + 0.1 * torch.sin(3 * t)[:, None]
    return WindowTensors(motion, torch.randn(count, frames, music_dim, generator=g), torch.randn(count, 8, generator=g),
                         torch.ones(count, dtype=torch.bool))


@pytest.fixture(scope="session")
def tiny_checkpoint(tmp_path_factory):
    """Five training steps of the tiny configuration, one-hot styles: enough to exercise every code path."""
    from choreo_sgmd.config import TrainConfig, model_config
    from choreo_sgmd.training import train

    out = tmp_path_factory.mktemp("tiny")
    config = TrainConfig(batch_size=4, max_steps=5, validation_every=5, checkpoint_every=5, prompt_kind="onehot")
    data = synthetic_windows()
    data.style = torch.eye(14)[:4]
    return train(model_config("tiny", style_dim=14), config, data, None, out)


@pytest.fixture(scope="session")
def tiny_generator(tiny_checkpoint):
    from choreo_sgmd.generator import SGMDGenerator

    return SGMDGenerator(tiny_checkpoint)


def wandering_dance(seed: int, frames: int = 40, fps: float = 30.0):
    """A wandering, turning dance on a performer with their own proportions (not the template's):
    what a retargeting or export test must carry over, bone by bone."""
    from choreo.motion import Motion
    from choreo.skeleton import SMPL24

    rng = np.random.default_rng(seed)
    axis_angle = np.cumsum(rng.normal(scale=0.08, size=(frames, 24, 3)), axis=0)
    axis_angle[:, 0, 1] += np.linspace(0, 3 * np.pi, frames)
    root = np.cumsum(rng.normal(scale=0.02, size=(frames, 3)), axis=0) + [0.3, 0.95, -0.2]
    skeleton = SMPL24.with_offsets(SMPL24.offsets * rng.uniform(0.9, 1.1, size=(24, 1)))
    return Motion.from_axis_angle(root, axis_angle, fps=fps, skeleton=skeleton)


@pytest.fixture
def source(tmp_path) -> Path:
    """A small BVH to read (the tests of where outputs go: tests/test_fileio.py, tests/render/test_video.py)."""
    from choreo.formats import write_motion
    from tests.outputs import dance

    path = tmp_path / "source.bvh"
    write_motion(dance(), path)
    return path
