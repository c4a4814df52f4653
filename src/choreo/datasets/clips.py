"""Small helpers every dataset reader needs to turn files into clips."""

from __future__ import annotations

import numpy as np

from ..errors import DatasetError
from ..motion import Motion

MAX_LENGTH_MISMATCH_SECONDS = 2.0  # music and motion lengths may differ a little, not a lot


def align_music_and_motion(motion: Motion, features: np.ndarray, name: str) -> tuple[Motion, np.ndarray]:
    """Trim motion and features (both starting at the same instant) to their common length."""
    frames = min(motion.num_frames, len(features))
    if frames == 0:
        raise DatasetError(f"{name}: motion or music is empty")
    if (motion.num_frames - len(features)) / motion.fps > MAX_LENGTH_MISMATCH_SECONDS:
        raise DatasetError(f"{name}: music ({len(features) / motion.fps:.1f} s) is much shorter than the "
                           f"motion ({motion.duration:.1f} s)")
    return motion.slice_frames(0, frames), features[:frames]


def place_on_floor(motion: Motion, percentile: float = 50.0) -> Motion:
    """Shift vertically so the lowest joint of a typical frame touches y = 0.

    Per frame, the lowest joint stands in for the supporting foot; the ``percentile`` of those
    heights (the median by default, not the minimum, which one noisy frame would set) goes to 0.
    """
    lowest = motion.joint_positions()[..., 1].min(axis=1)
    return motion.translated([0.0, -float(np.percentile(lowest, percentile)), 0.0])


def leg_length(skeleton) -> float:
    """Hip to ankle along the bones, averaged over both legs (metres)."""
    lengths = skeleton.bone_lengths()
    return float((lengths[4] + lengths[7] + lengths[5] + lengths[8]) / 2)


def retarget_root(root_positions: np.ndarray, source, target) -> np.ndarray:
    """Scale a root trajectory by the legs' length ratio, so steps keep their feet planted.

    Rotations carry over between skeletons unchanged; the root path must stretch with the legs,
    or a longer-legged body slides its feet and sinks into the floor.
    """
    return root_positions * (leg_length(target) / leg_length(source))
