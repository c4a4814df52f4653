"""Style vectors for scoring windows, for the scripts that probe the network directly.

Scoring itself goes through the core's protocol (`choreo.metrics.protocol.score_generator`), which
dances every window in one batch with `SGMDGenerator.generate_windows`.
"""

from __future__ import annotations

from typing import Sequence

import torch

from .generator import SGMDGenerator


def genre_styles(generator: SGMDGenerator, genres: Sequence[str | None]) -> tuple[torch.Tensor, torch.Tensor]:
    """Style vectors (N, S) and keep flags (N,) for per-window genres (None: no style)."""
    resolved = [generator.style_vector(genre) for genre in genres]
    return torch.stack([vector for vector, _ in resolved]), torch.tensor([s.vector is not None for _, s in resolved])
