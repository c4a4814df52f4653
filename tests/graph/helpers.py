"""Helpers shared by the tests in this folder."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np


def count(module):
    return sum(p.numel() for p in module.parameters())


def toy_repertoire(seed=0, clips=5, joints=4):
    """Smooth random poses (so motion beats are spread out), clips cut from two motions 60 frames apart."""
    rng = np.random.default_rng(seed)
    t = np.arange(240)[None, :, None, None] / 30
    poses = np.sin(rng.uniform(0.5, 3, (clips, 1, joints, 3)) * 2 * np.pi * t + rng.uniform(0, 6, (clips, 1, joints, 3)))
    names = np.array([f"{'ab'[c % 2]}@{60 * (c // 2)}" for c in range(clips)])
    sources, starts = np.array([c % 2 for c in range(clips)]), np.array([60 * (c // 2) for c in range(clips)])
    return SimpleNamespace(style=rng.random((clips, 2)), poses=(0.3 * poses).astype(np.float16),
                           origins=(sources, starts), names=names)
