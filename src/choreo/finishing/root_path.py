"""Root path: the pelvis's travel low-passed, so the dancer moves along its path instead of
wobbling on it.

SGMD's dances jitter mostly in the root's path: on whole songs the root's own jerk is several times
a real dancer's while the body around the pelvis jerks about as much as real's (docs/results.md,
"Whole songs", "Where the rushing and the jitter came from"). Every joint moves with the root, so the wobble shows in every joint's jerk. This
pass runs a zero-phase low-pass over the root's translation (every joint follows it; rotations are
untouched) with the cut-off measured on whole songs. Frames a user fixed keep their root, the
correction fading in over ``blend_seconds`` next to them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..motion.filters import fixed_weights, low_pass


@dataclass(frozen=True, kw_only=True)
class RootPathConfig:
    cutoff_hz: float = 3.0  # slower travel is kept: whole-body jerk nearest real dancers' (docs/results.md, "Whole songs")
    blend_seconds: float = 0.3  # fade of the correction next to frames a user fixed
    axes: tuple[int, ...] = (0, 1, 2)  # root translation axes smoothed (Y is up)

    def __post_init__(self):
        if not self.cutoff_hz > 0 or not self.blend_seconds > 0:
            raise ParameterError("root path: cutoff_hz and blend_seconds must be positive")


def root_path(motion: Motion, fixed: np.ndarray | None = None, config: RootPathConfig = RootPathConfig()) -> Motion:
    """``motion`` with its root translation low-passed; ``fixed`` frames keep theirs exactly."""
    fixed = np.zeros(motion.num_frames, bool) if fixed is None else np.asarray(fixed, bool)
    if motion.num_frames < 3 or fixed.all():
        return motion
    axes = list(config.axes)
    root = motion.root_positions.astype(np.float64)
    weight = fixed_weights(fixed, motion.fps, config.blend_seconds)[:, None]
    root[:, axes] += (low_pass(root[:, axes], motion.fps, config.cutoff_hz) - root[:, axes]) * weight
    root[fixed] = motion.root_positions[fixed]
    return motion.replace(root_positions=root.astype(motion.root_positions.dtype), metadata=dict(motion.metadata))
