"""Helpers shared by the tests in this folder."""

import numpy as np

from choreo.motion import Motion


def numbered_motion(frames=6, fps=30.0):
    """Root x = frame number, every joint turned about z by an angle of its own per frame."""
    root = np.zeros((frames, 3))
    root[:, 0] = np.arange(frames)
    root[:, 1] = 0.9
    root[:, 2] = -0.5 * np.arange(frames)
    half = 0.01 * (np.arange(frames)[:, None] + 1) * (np.arange(24)[None] + 1)  # half angles
    rotations = np.zeros((frames, 24, 4))
    rotations[..., 0] = np.cos(half)
    rotations[..., 3] = np.sin(half)
    return Motion(root, rotations, fps=fps)
