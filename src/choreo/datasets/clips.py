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


MIN_LEG_LENGTH = 0.01  # metres: shorter legs are a degenerate recording, not a body to scale a root path by


def leg_length(skeleton, name: str = "skeleton") -> float:
    """Hip to ankle along the bones, averaged over both legs (metres).

    Root paths are divided by it, so legs of no length (every leg marker at one point, or a BVH
    whose leg offsets are all zero) or of a non-finite one are refused here, in one line.
    """
    lengths = skeleton.bone_lengths()
    length = float((lengths[4] + lengths[7] + lengths[5] + lengths[8]) / 2)
    if not (np.isfinite(length) and length >= MIN_LEG_LENGTH):
        raise DatasetError(f"{name}: the legs have no usable length (hip to ankle {length:.3g} m)")
    return length


def retarget_root(root_positions: np.ndarray, source, target) -> np.ndarray:
    """Scale a root trajectory by the legs' length ratio, so steps keep their feet planted.

    Rotations carry over between skeletons unchanged; the root path must stretch with the legs,
    or a longer-legged body slides its feet and sinks into the floor.
    """
    return root_positions * (leg_length(target, "target") / leg_length(source, "source"))
