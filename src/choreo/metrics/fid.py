"""FID_k, FID_g, Div_k, Div_g as Bailando computes them (``utils/metrics_new.py``).

Pipeline per motion: keep the first 1200 frames, subtract the first frame's root position from
every joint of every frame (no per-frame centring), extract kinetic (72) and geometric (32)
features. Per set: normalise every feature dimension of both sets with the ground-truth set's
mean and population std (+1e-10), then FID between the sets and Div within each.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg
from scipy.spatial.distance import pdist

from .beats import MetricWarning
from .geometric import geometric_features
from .kinetic import kinetic_features

MAX_FRAMES = 1200
NORMALISATION_EPSILON = 1e-10
SQRTM_RETRY_OFFSET = 1e-5


def prepare_positions(positions: np.ndarray) -> np.ndarray:
    """First 1200 frames, relative to the frame-0 root (what the kinetic quirk needs)."""
    positions = np.asarray(positions, dtype=np.float64)[:MAX_FRAMES]
    return positions - positions[:1, :1]


def motion_features(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(72,) kinetic and (32,) geometric features of one motion (T, 24, 3), Y up, metres."""
    prepared = prepare_positions(positions)
    return kinetic_features(prepared), geometric_features(prepared)


def normalise_by_reference(generated: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both (N, D) sets scaled with the reference (ground-truth) set's mean and population std."""
    mean = reference.mean(axis=0)
    std = reference.std(axis=0) + NORMALISATION_EPSILON
    return (generated - mean) / std, (reference - mean) / std


def frechet_distance(a: np.ndarray, b: np.ndarray) -> float:
    """|mu_a - mu_b|^2 + tr(S_a + S_b - 2 sqrtm(S_a S_b)) with ddof=1 covariances; real and finite.

    With fewer samples than dimensions the covariances are singular: a MetricWarning, and the
    small-offset retry below keeps the square root finite.
    """
    if len(a) < 2 or len(b) < 2:
        warnings.warn("FID needs at least 2 samples per set; returning NaN", MetricWarning, stacklevel=2)
        return float("nan")
    if min(len(a), len(b)) <= a.shape[1]:
        warnings.warn(f"FID with {min(len(a), len(b))} samples for {a.shape[1]} feature dimensions: "
                      "covariances are singular, the value is unreliable", MetricWarning, stacklevel=2)
    mu_a, mu_b = a.mean(axis=0), b.mean(axis=0)
    cov_a, cov_b = np.atleast_2d(np.cov(a, rowvar=False)), np.atleast_2d(np.cov(b, rowvar=False))
    root = scipy.linalg.sqrtm(cov_a @ cov_b)
    if not np.isfinite(root).all():
        offset = np.eye(len(cov_a)) * SQRTM_RETRY_OFFSET
        root = scipy.linalg.sqrtm((cov_a + offset) @ (cov_b + offset))
    value = float(np.sum((mu_a - mu_b) ** 2) + np.trace(cov_a) + np.trace(cov_b) - 2 * np.trace(root).real)
    return value


def diversity(features: np.ndarray) -> float:
    """Mean Euclidean distance over all unordered pairs of feature vectors."""
    if len(features) < 2:
        warnings.warn("diversity needs at least 2 samples; returning NaN", MetricWarning, stacklevel=2)
        return float("nan")
    return float(pdist(features).mean())
