"""Pace: a dance that travels much faster or slower than real dancers of its genre is brought
toward their pace by scaling its travel, never by more than ``max_scale``.

Real M2D dancers keep a steady pace along their ground track (the root's floor path low-passed at
1 Hz), and within a genre they spread little around its median (`python
scripts/real_speed_limits.py`). SGMD, on songs it has not heard, travels much faster
(docs/results.md, "Whole songs"). This pass scales the ground track's displacement from its start
(the sway and turns around the track stay as they are) toward the genre's pace, by a factor
within [1 / max_scale, max_scale]. A pace is a property of a dance of at least ``min_seconds``:
over a few seconds real dancers keep no one pace, so shorter dances keep their travel. Why it
pulls all the way rather than into the real clips' spread, and the figures behind both bounds:
docs/results.md, "Whole songs". It runs on free dances only: a dance with frames a user fixed
keeps the travel that reaches them. The pace before and after is kept in the dance's metadata
(``pace``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..motion.travel import FLOOR_AXES, ground_track, track_pace

# Median pace of the M2D train split's clips by genre, and of all of them (a dance without a genre):
# m/s along the ground track (scripts/real_speed_limits.py).
REAL_PACE = {"cha-cha": 0.448, "rumba": 0.443, "tango": 1.227, "waltz": 0.497}
ANY_GENRE_PACE = 0.494


@dataclass(frozen=True, kw_only=True)
class PaceConfig:
    max_scale: float = 1.25  # the travel is scaled by at most this, or at least its inverse
    min_seconds: float = 30.0  # shorter dances are left alone: over a few seconds real dancers keep no one pace

    def __post_init__(self):
        if not self.max_scale >= 1:
            raise ParameterError("pace: max_scale must be >= 1")


def target_pace(genre: str | None) -> float | None:
    """The pace real dancers of ``genre`` keep (None for a genre without one, or a style schedule)."""
    return ANY_GENRE_PACE if genre is None else REAL_PACE.get(genre)


def travel_scale(pace: float, target: float, config: PaceConfig = PaceConfig()) -> float:
    """The factor that brings ``pace`` to ``target``, within the scale bounds."""
    if pace <= 0:
        return 1.0
    return float(np.clip(target / pace, 1 / config.max_scale, config.max_scale))


def pace(motion: Motion, fixed: np.ndarray | None = None, config: PaceConfig = PaceConfig()) -> Motion:
    """``motion`` with its travel scaled toward its genre's pace (its metadata's ``genre``, which a
    backend sets: None for a dance without a style; a motion without the key is left alone)."""
    target = target_pace(motion.metadata["genre"]) if "genre" in motion.metadata else None
    if (target is None or motion.duration < config.min_seconds
            or (fixed is not None and np.asarray(fixed, bool).any())):
        return motion
    track = ground_track(motion.root_positions, motion.fps)
    before = track_pace(track, motion.fps)
    scale = travel_scale(before, target, config)
    root = motion.root_positions.astype(np.float64)
    root[:, list(FLOOR_AXES)] += (scale - 1.0) * (track - track[:1])
    metadata = dict(motion.metadata, pace={"model": round(before, 4), "finished": round(before * scale, 4)})
    return motion.replace(root_positions=root.astype(motion.root_positions.dtype), metadata=metadata)
