"""Speed limit: joints and root moving faster than any real dancer's are slowed by spreading the
movement over the frames around it.

A generator that commits to one facing, then to another a frame later, makes the whole body spin
by 50-100 degrees between two frames, and the hands move at 30 m/s (SGMD with a heavy
reconstruction term does so every few seconds: docs/results.md); a limb can flip the same way.
Real M2D dancers move a joint faster than 10.4 m/s in one frame of a thousand, and their root
travels at most 12 cm per frame at 30 fps (99.9th percentiles; `python
scripts/real_speed_limits.py`). This pass finds the frames above those limits and smooths every
joint's rotation (or the root's floor position) around them until none is left: the turn or the
dash still happens and ends where it ended, over a few frames instead of one. A sustained
movement faster than the limit is not slowed (only steps that neighbours can absorb are spread).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..motion import Motion
from ..motion.motion import frame_chunks

REFERENCE_FPS = 30.0
REAL_JOINT_SPEED = 10.39  # m/s: real M2D's fastest 0.1 % of frames (any joint) start here
REAL_FLOOR_STEP = 0.123  # metres of root travel on the floor per frame at 30 fps (99.9th percentile)


@dataclass(frozen=True, kw_only=True)
class SpeedLimitConfig:
    joint_speed: float = REAL_JOINT_SPEED
    floor_step: float = REAL_FLOOR_STEP  # per frame at 30 fps
    reach: int = 2  # frames on each side of a step above a limit that each smoothing pass touches
    max_passes: int = 500


def speed_limit(motion: Motion, fixed: np.ndarray | None = None, config: SpeedLimitConfig = SpeedLimitConfig()) -> Motion:
    """``motion`` with its root's floor dashes, then any joint's too-fast frames, spread over
    neighbouring frames; ``fixed`` frames (constraints) keep their values."""
    if motion.num_frames < 3:
        return motion
    movable = np.ones(motion.num_frames, bool) if fixed is None else ~np.asarray(fixed, bool)
    movable[[0, -1]] = False
    root = motion.root_positions.copy()
    floor_limit = config.floor_step * REFERENCE_FPS / motion.fps
    for _ in range(config.max_passes):
        chosen = frames_around(step_lengths(root[:, [0, 2]]) > floor_limit, movable, config.reach)
        if not len(chosen):
            break
        root[chosen[:, None], [0, 2]] = smoothed(root[:, [0, 2]], chosen)
    rotations = motion.rotations.copy()
    positions = np.empty((motion.num_frames, motion.num_joints, 3))
    for chunk in frame_chunks(motion.num_frames):  # no second copy of a song's rotations
        positions[chunk] = motion.replace(root_positions=root[chunk], rotations=motion.rotations[chunk]).joint_positions()
    speed = np.concatenate([step_lengths(positions[steps.start: steps.stop + 1]).max(-1)
                            for steps in frame_chunks(motion.num_frames - 1)]) * motion.fps  # (T-1,), kept up to date where frames move
    for _ in range(config.max_passes):
        chosen = frames_around(speed > config.joint_speed, movable, config.reach)
        if not len(chosen):
            break
        rotations[chosen] = smoothed(rotations, chosen, quaternions=True)
        root[chosen] = smoothed(root, chosen)
        positions[chosen] = motion.replace(root_positions=root[chosen], rotations=rotations[chosen]).joint_positions()
        steps = np.unique(np.concatenate([chosen - 1, chosen]))  # the steps into and out of moved frames
        speed[steps] = np.linalg.norm(positions[steps + 1] - positions[steps], axis=-1).max(-1) * motion.fps
    del positions  # before the new motion's checks copy the rotations once more
    return motion.replace(root_positions=root, rotations=rotations, metadata=dict(motion.metadata))


def step_lengths(values: np.ndarray) -> np.ndarray:
    """(T-1, ...) distance between consecutive frames of (T, ..., D) values."""
    return np.linalg.norm(np.diff(values, axis=0), axis=-1)


def frames_around(over: np.ndarray, movable: np.ndarray, reach: int) -> np.ndarray:
    """Movable frames within ``reach`` of a step flagged in ``over`` (T-1,): step i joins i and i + 1."""
    steps = np.flatnonzero(over)
    near = np.zeros(len(movable), bool)
    for shift in range(-reach, reach + 2):
        near[np.clip(steps + shift, 0, len(near) - 1)] = True
    return np.flatnonzero(near & movable)


def smoothed(values: np.ndarray, chosen: np.ndarray, quaternions: bool = False) -> np.ndarray:
    """[1, 2, 1] / 4 of (T, ...) ``values`` at the ``chosen`` inner frames; unit quaternions are
    averaged on the centre frame's hemisphere and renormalised."""
    before, centre, after = values[chosen - 1], values[chosen], values[chosen + 1]
    if quaternions:  # q and -q are one rotation
        before = before * np.where((before * centre).sum(-1, keepdims=True) < 0, -1.0, 1.0)
        after = after * np.where((after * centre).sum(-1, keepdims=True) < 0, -1.0, 1.0)
    mean = (before + 2 * centre + after) / 4
    return mean / np.linalg.norm(mean, axis=-1, keepdims=True) if quaternions else mean
