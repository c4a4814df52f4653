"""Scoring ChoreoGraph the way the reference row is scored: one dance per 5 s test window,
danced from that window's music alone (`choreo.metrics.protocol.score_generator`), with a
repertoire cut from the training clips."""

from __future__ import annotations

from typing import Sequence

from choreo.datasets import Clip

from .model import ChoreoGraphModel
from .repertoire import Repertoire, build_repertoire


def clips_repertoire(model: ChoreoGraphModel, clips: Sequence[Clip], stride: int, source: str) -> Repertoire:
    """Every 8 s clip (``stride`` frames apart) of dataset clips, described by ``model``."""
    return build_repertoire([(c.name, c.motion, c.genre) for c in clips], model, stride, source)
