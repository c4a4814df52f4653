"""Filters over a motion's frames, shared by the finishing passes and the metrics."""

from __future__ import annotations

import numpy as np


def low_pass(values: np.ndarray, fps: float, cutoff_hz: float) -> np.ndarray:
    """Zero-phase low-pass of (T, ...) ``values`` along time: a second-order Butterworth run forwards
    and backwards, so nothing is delayed. The ends are padded by odd reflection over three periods
    of the cut-off, so a dance keeps its first and last frame and a steady drift is not bent there."""
    import scipy.signal  # here, not at import: the formats import this module, and reading a file needs no filter

    values = np.asarray(values, dtype=np.float64)
    if len(values) < 4:
        return values.copy()
    b, a = scipy.signal.butter(2, min(cutoff_hz / (fps / 2.0), 0.99))
    padding = min(len(values) - 1, max(9, round(3 * fps / cutoff_hz)))
    return scipy.signal.filtfilt(b, a, values, axis=0, padtype="odd", padlen=padding)


def fixed_weights(fixed: np.ndarray, fps: float, blend_seconds: float) -> np.ndarray:
    """(T,) 1 away from fixed frames, 0 on them, a linear ramp over ``blend_seconds`` between: how much
    of a correction a pass may apply next to frames a user gave."""
    import scipy.ndimage

    if not fixed.any():
        return np.ones(len(fixed))
    distance = scipy.ndimage.distance_transform_edt(~fixed)  # frames to the nearest fixed one, in O(T)
    return np.clip(distance / max(blend_seconds * fps, 1.0), 0.0, 1.0)
