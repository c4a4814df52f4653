"""The model's own frame rate: every ``stride``-th frame of choreo's 30 fps motion and music.

Why a model might dance at 15 fps: 60 % of M2D (its waltz) was captured at 5.9 fps and holds
nothing a 15 fps model cannot represent, and half the frames halve the sequence the transformer
attends over, so a step costs about half. Music and constraints are brought down to the model's
rate on the way in, and the sampled frame vectors are interpolated back to 30 fps on the way out
(rotations as 6D vectors, re-orthonormalised when they become matrices).

Model frame k is 30 fps frame ``k * stride``. Continuous music columns are read at those frames;
a beat or onset peak (one-hot columns) moves to the nearest model frame, so none is lost.
"""

from __future__ import annotations

import math

import numpy as np

from choreo.motion.motion import frame_chunks, frames_between
from choreo.music import BEAT_COLUMN, PEAK_COLUMN

EVENT_COLUMNS = (PEAK_COLUMN, BEAT_COLUMN)  # one-hot columns of the 35-d features (the rhythm channels come after)


def model_frames(num_frames: int, stride: int) -> int:
    """How many model frames cover ``num_frames`` 30 fps frames."""
    return math.ceil(num_frames / stride)


def music_at_model_rate(music: np.ndarray, stride: int) -> np.ndarray:
    """(..., T, D) music input at 30 fps -> (..., ceil(T / stride), D) at the model's rate."""
    if stride == 1:
        return music
    pooled = music[..., ::stride, :].copy()
    for column in EVENT_COLUMNS:
        pooled[..., column] = 0
        frames = np.nonzero(music[..., column] > 0.5)
        nearest = np.minimum(np.floor(frames[-1] / stride + 0.5).astype(int), pooled.shape[-2] - 1)
        pooled[(*frames[:-1], nearest, column)] = 1
    return pooled


def known_at_model_rate(values: np.ndarray, mask: np.ndarray, stride: int) -> tuple[np.ndarray, np.ndarray]:
    """Constraint values and mask (..., T, D) at 30 fps -> model rate. A model frame takes the
    first known value of its ``stride`` frames, dimension by dimension, so a key on an odd frame
    still reaches the sampler (choreo's final overwrite puts it back on its exact frame)."""
    if stride == 1:
        return values, mask
    count = model_frames(values.shape[-2], stride)
    out_values = np.zeros((*values.shape[:-2], count, values.shape[-1]), values.dtype)
    out_mask = np.zeros(out_values.shape, bool)
    for offset in range(stride):
        part_values, part_mask = values[..., offset::stride, :], mask[..., offset::stride, :]
        rows = part_mask.shape[-2]
        take = part_mask & ~out_mask[..., :rows, :]
        out_values[..., :rows, :][take] = part_values[take]
        out_mask[..., :rows, :] |= part_mask
    return out_values, out_mask


def frames_at_full_rate(vectors: np.ndarray, stride: int, num_frames: int) -> np.ndarray:
    """(..., Tm, D) model-rate frame vectors -> (..., num_frames, D) by linear interpolation
    (frames past the last model frame hold it)."""
    if stride == 1:
        return vectors[..., :num_frames, :]
    position = np.minimum(np.arange(num_frames) / stride, vectors.shape[-2] - 1)
    lower, upper, weight = frames_between(position, vectors.shape[-2])
    weight = weight[:, None].astype(vectors.dtype)
    out = np.empty((*vectors.shape[:-2], num_frames, vectors.shape[-1]), np.result_type(vectors.dtype, weight.dtype))
    for chunk in frame_chunks(num_frames):
        out[..., chunk, :] = vectors[..., lower[chunk], :] * (1 - weight[chunk]) + vectors[..., upper[chunk], :] * weight[chunk]
    return out
