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
