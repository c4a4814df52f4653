"""Helpers shared by the tests in this folder."""

import contextlib
import warnings

import numpy as np

from choreo.motion import Motion


@contextlib.contextmanager
def no_warnings():
    """Any warning, a floating-point RuntimeWarning included, fails the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def z_up_of(y_up: np.ndarray) -> np.ndarray:
    """Y up to Z up by +90 degrees about x: (x, y, z) -> (x, -z, y)."""
    return np.stack([y_up[..., 0], -y_up[..., 2], y_up[..., 1]], axis=-1)


def literal_pfc_z_up(z_up: np.ndarray) -> float:
    """EDGE's PFC term as a plain loop over frames on Z-up data (x, y horizontal), float64."""
    z_up = np.asarray(z_up, dtype=np.float64)
    dt = 1 / 30
    root = z_up[:, 0]
    accelerations = []
    for t in range(1, len(root) - 1):
        a = ((root[t + 1] - root[t]) / dt - (root[t] - root[t - 1]) / dt) / dt
        a[2] = max(a[2], 0.0)
        accelerations.append(float(np.sqrt(a @ a)))
    peak = max(accelerations)
    if peak == 0:
        return 0.0
    total = 0.0
    for t in range(1, len(root) - 1):
        slides = []
        for ankle, toe in ((7, 10), (8, 11)):
            slides.append(min(np.hypot(*(z_up[t + 1, j, :2] - z_up[t, j, :2])) for j in (ankle, toe)))
        total += slides[0] * slides[1] * accelerations[t - 1] / peak
    return total / (len(root) - 2)


def sliding_body(frames: int, root_x) -> np.ndarray:
    """Y-up rest pose whose joints all follow ``root_x`` along x (feet slide with the root)."""
    positions = np.repeat(Motion.rest(1).joint_positions(), frames, axis=0)
    positions[..., 0] += np.asarray(root_x)[:, None]
    return positions


def pulsing_positions(frames: int, period: float) -> np.ndarray:
    """A body gliding along x whose speed dips every ``period`` frames (motion beats there)."""
    t = np.arange(frames)
    speed = 1.05 - np.cos(2 * np.pi * t / period)
    positions = np.zeros((frames, 24, 3))
    positions[..., 0] = np.cumsum(speed)[:, None] * 0.01
    return positions
