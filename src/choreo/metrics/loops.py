"""How seamless a looped dance is, played over and over (``choreo generate --loop``;
scripts/experiments/loop_seam.py)."""

from __future__ import annotations

import numpy as np

from ..motion import Motion
from ..motion.seam import next_cycle
from .form import steps_and_changes


def seam(motion: Motion) -> tuple[float, float]:
    """How a loop's seam compares with its own frame steps, played over and over: (the step from its
    last frame into the next cycle's first, the larger change of velocity there), each over the
    95th percentile of the same figure inside the dance; joints' moves averaged, in metres."""
    steps, changes = steps_and_changes(Motion.concatenate([motion, next_cycle(motion, 2)]).joint_positions())
    last = motion.num_frames - 1  # the step from the last frame into the next cycle
    inside = np.delete(steps, last)
    inside_changes = np.delete(changes, [last - 1, last])
    return (float(steps[last] / np.percentile(inside, 95)),
            float(max(changes[last - 1], changes[last]) / np.percentile(inside_changes, 95)))
