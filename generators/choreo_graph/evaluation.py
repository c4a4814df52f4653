"""Scoring ChoreoGraph the way the reference row is scored: one dance per 5 s test window,
danced from that window's music alone, with a repertoire cut from the training clips."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from choreo.datasets import Clip
from choreo.metrics import Dance
from choreo.metrics.protocol import window_dance

from .config import GraphConfig
from .data import clip_mel
from .generator import ChoreoGraphGenerator
from .model import ChoreoGraphModel
from .repertoire import Repertoire, build_repertoire


def clips_repertoire(model: ChoreoGraphModel, clips: Sequence[Clip], stride: int, source: str) -> Repertoire:
    """Every 8 s clip (``stride`` frames apart) of dataset clips, described by ``model``."""
    return build_repertoire([(c.name, c.motion, c.genre) for c in clips], model, stride, source)


def window_mels(clips: Sequence[Clip]) -> dict[str, np.ndarray]:
    """The log-mel of every clip that has audio, by clip name (windows are cut from these)."""
    return {c.name: clip_mel(c) for c in clips if c.audio_path}


def generate_window_dances(generator: ChoreoGraphGenerator, windows: Sequence, mels: dict[str, np.ndarray],
                           config: GraphConfig = GraphConfig(), finished: bool = False,
                           foot_lock: bool = False) -> list[Dance]:
    """A dance for every scoring window, scored against that window's music beats (``finished``:
    after the beat lock, as `choreo graph` writes it, and the foot lock when asked)."""
    dances = []
    for w in windows:
        motion = generator.dance(mels[w.clip][w.start_frame: w.start_frame + len(w.features)], config)
        dances.append(window_dance(w, motion, finished, foot_lock))
    return dances
