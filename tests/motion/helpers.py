"""Helpers shared by the tests in this folder."""

import re

import numpy as np

from choreo.motion import (
    Motion,
)
from choreo.skeleton import Skeleton


def short_random_motion(frames=20, fps=30.0, seed=0, scale=0.4):
    """Smooth random rotations: cumulative small steps keep consecutive frames close, like real motion."""
    rng = np.random.default_rng(seed)
    axis_angle = np.cumsum(rng.normal(scale=scale / 10, size=(frames, 24, 3)), axis=0)
    root = np.cumsum(rng.normal(scale=0.01, size=(frames, 3)), axis=0) + [0, 0.9, 0]
    return Motion.from_axis_angle(root, axis_angle, fps=fps)


def counting_motion(frames, fps=30.0, metadata=None):
    """Identity rotations, root x = frame index: a frame's content names the frame."""
    root = np.stack([np.arange(frames, dtype=np.float64), np.full(frames, 0.9), np.zeros(frames)], axis=1)
    rotations = np.tile([1.0, 0.0, 0.0, 0.0], (frames, 24, 1))
    return Motion(root, rotations, fps=fps, metadata=dict(metadata or {}))


def two_joint_skeleton(bone=(0.0, 1.0, 0.0)):
    return Skeleton(("hips", "head"), (-1, 0), np.array([[0.0, 0.0, 0.0], list(bone)]))


def exactly(message):
    return "^" + re.escape(message) + "$"


def gram_schmidt(six):
    """Literal Gram-Schmidt of (..., 6) rows (a1 | a2) into rotation matrices with rows b1, b2, b3."""
    out = np.zeros(six.shape[:-1] + (3, 3))
    for index in np.ndindex(six.shape[:-1]):
        a1, a2 = six[index][:3].astype(np.float64), six[index][3:].astype(np.float64)
        b1 = a1 / np.sqrt(a1 @ a1)
        a2 = a2 - (b1 @ a2) * b1
        b2 = a2 / np.sqrt(a2 @ a2)
        out[index] = [b1, b2, np.cross(b1, b2)]
    return out


FPS = 30.0


def wobbly_walk(seconds: float = 20.0, speed: float = 0.5, wobble: float = 0.03, seed: int = 0,
                genre: str | None = "rumba") -> Motion:
    """A dancer walking a straight line at ``speed`` whose root wobbles by ``wobble`` metres at 4-8 Hz."""
    frames = int(seconds * FPS)
    t = np.arange(frames) / FPS
    rng = np.random.default_rng(seed)
    root = np.zeros((frames, 3))
    root[:, 0] = speed * t
    root[:, 1] = 0.9
    for axis in range(3):
        for hz in (4.0, 6.0, 8.0):
            root[:, axis] += wobble / 3 * np.sin(2 * np.pi * hz * t + rng.uniform(0, 2 * np.pi))
    rotations = np.zeros((frames, 24, 3))
    rotations[:, 16:22] = 0.3 * np.sin(2 * np.pi * 1.0 * t)[:, None, None]  # arms swinging on a 1 Hz beat
    motion = Motion.from_axis_angle(root, rotations, fps=FPS)
    motion.metadata = {"genre": genre}
    return motion
