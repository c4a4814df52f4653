"""Scoring a checkpoint the way the reference row is scored: one 5 s dance per test window.

Each window is generated on its own from its music and its clip's genre (as papers score 5 s
AIST++ clips), so the numbers compare directly with the real test windows'.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import torch

from choreo.constraints import Constraints
from choreo.metrics import Dance
from choreo.metrics.protocol import window_dance
from choreo.motion import Motion, vector_to_motion

from .frame_rate import known_at_model_rate
from .generator import SGMDGenerator
from .sampling import Inpainting, SamplingOptions, sample_independent


def genre_styles(generator: SGMDGenerator, genres: Sequence[str | None]) -> tuple[torch.Tensor, torch.Tensor]:
    """Style vectors (N, S) and keep flags (N,) for per-window genres (None: no style)."""
    resolved = [generator.style_vector(genre) for genre in genres]
    return torch.stack([vector for vector, _ in resolved]), torch.tensor([s.vector is not None for _, s in resolved])


def generate_window_motions(generator: SGMDGenerator, windows: Sequence, options: SamplingOptions,
                            with_style: bool = True, constraints: Sequence[Constraints] | None = None) -> list[Motion]:
    """A generated motion for every scoring window (under that window's constraints, if given)."""
    music = generator.music_tensor(np.stack([w.features for w in windows]))
    styles, keep = genre_styles(generator, [w.genre if with_style else None for w in windows])
    inpainting, values, mask = None, None, None
    if constraints is not None:
        values, mask = (np.stack(parts) for parts in zip(*(c.frame_vectors() for c in constraints)))
        model_values, model_mask = known_at_model_rate(values, mask, generator.model_config.frame_stride)
        inpainting = Inpainting(generator.normalizer.normalize(torch.from_numpy(model_values).float()),
                                torch.from_numpy(model_mask))
    x0 = sample_independent(generator.model, generator.schedule, music, styles, keep,
                            generator.model_config.frame_dim, options, inpainting)
    vectors = generator.at_full_rate(generator.normalizer.denormalize(x0).numpy(), windows[0].features.shape[0])
    if mask is not None:
        vectors[mask] = values[mask]
    return [vector_to_motion(v)[0] for v in vectors]


def generate_window_dances(generator: SGMDGenerator, windows: Sequence, options: SamplingOptions,
                           with_style: bool = True, finished: bool = False, foot_lock: bool = False) -> list[Dance]:
    """A generated dance for every scoring window, scored against that window's music beats
    (``finished``: after the beat lock, as `choreo generate` writes it, and the foot lock when asked)."""
    motions = generate_window_motions(generator, windows, options, with_style)
    return [window_dance(w, m, finished, foot_lock) for w, m in zip(windows, motions)]
