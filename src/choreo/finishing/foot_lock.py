"""Foot lock: planted feet carry the body instead of sliding under it.

Generated dances, re-timed dances and graph seams let a planted foot drift across the floor
while the body moves on (PFC counts it). Where the contacts (choreo.motion.foot_contacts) say a
foot is planted, its horizontal drift is taken off the root instead, so the foot stays and the
dancer's body travels by pushing off it; with both feet planted, their mean drift. The
correction fades back towards the original path with a time constant of ``recovery_seconds``
(the dance keeps going where it was going), and it is zero on every frame a user fixed, with a
straight ramp between fixed frames, so those stay exactly as given.

Measured and left out (docs/results.md): pinning each planted ankle with two-bone leg IK and
blends in and out. Without moving the root, the drift a foot had is only postponed to the blend
frames, where it happens faster, and PFC rose on both generators.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..motion import Motion, foot_contacts
from .beat_lock import free_spans

LEFT_FOOT_CHANNELS, RIGHT_FOOT_CHANNELS = (0, 2), (1, 3)  # foot_contacts' columns: l_ankle, r_ankle, l_foot, r_foot
LEFT_FOOT_JOINTS, RIGHT_FOOT_JOINTS = (7, 10), (8, 11)  # ankle and toe in SMPL-24
HORIZONTAL = np.array([1.0, 0.0, 1.0])  # Y is up: only x and z are corrected


@dataclass(frozen=True, kw_only=True)
class FootLockConfig:
    speed_threshold: float = 0.6  # m/s: a foot joint slower than this is planted
    recovery_seconds: float = 0.65  # time constant of the return to the original path

    def __post_init__(self):
        if self.speed_threshold <= 0 or self.recovery_seconds <= 0:
            raise ParameterError("foot lock: speed threshold and recovery time must be positive")


def planted_drift(joint_positions: np.ndarray, fps: float, speed_threshold: float) -> np.ndarray:
    """(T-1, 3) horizontal step of the planted feet between frames (their mean; 0 when none is planted)."""
    contacts = foot_contacts(joint_positions, fps, speed_threshold)
    planted = np.stack([contacts[:, LEFT_FOOT_CHANNELS].max(axis=1), contacts[:, RIGHT_FOOT_CHANNELS].max(axis=1)], 1)
    feet = np.stack([joint_positions[:, LEFT_FOOT_JOINTS].mean(axis=1), joint_positions[:, RIGHT_FOOT_JOINTS].mean(axis=1)], 1)
    steps = np.diff(feet, axis=0) * HORIZONTAL  # (T-1, 2, 3)
    weights = planted[:-1]
    return (steps * weights[..., None]).sum(axis=1) / np.maximum(weights.sum(axis=1, keepdims=True), 1.0)


def root_correction(drift: np.ndarray, fps: float, fixed: np.ndarray, recovery_seconds: float) -> np.ndarray:
    """(T, 3) offsets that cancel the drift, leaking back to 0, and exactly 0 on fixed frames."""
    keep = np.exp(-1.0 / (recovery_seconds * fps))
    correction = np.zeros((len(drift) + 1, 3))
    for t in range(1, len(correction)):
        correction[t] = keep * correction[t - 1] - drift[t - 1]
    if not fixed.any():
        return correction
    out = np.zeros_like(correction)
    for start, stop in free_spans(fixed):
        span = correction[start: stop + 1] - correction[start]
        ramp = np.linspace(0.0, 1.0, len(span))[:, None] * span[-1] if fixed[stop] else 0.0
        out[start: stop + 1] = span - ramp
    out[fixed] = 0.0
    return out


def foot_lock(motion: Motion, fixed: np.ndarray | None = None, config: FootLockConfig = FootLockConfig()) -> Motion:
    """The dance with its planted feet's drift moved onto the root; frames in ``fixed`` unchanged."""
    fixed = np.zeros(motion.num_frames, bool) if fixed is None else np.asarray(fixed, bool)
    if fixed.shape != (motion.num_frames,):
        raise ParameterError(f"fixed frames must be a ({motion.num_frames},) mask, got {fixed.shape}")
    if motion.num_frames < 3:
        return motion
    drift = planted_drift(motion.joint_positions(), motion.fps, config.speed_threshold)
    correction = root_correction(drift, motion.fps, fixed, config.recovery_seconds)
    return motion.replace(root_positions=motion.root_positions + correction, metadata=dict(motion.metadata))
