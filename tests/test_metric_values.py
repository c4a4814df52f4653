"""Metric values pinned by independent computations: closed forms, literal loops, hand-made cases.

Each test here fails if its metric loses a term, changes a constant or swaps an axis.
"""

import itertools

import numpy as np
import pytest

from choreo.metrics import beat_align_score, diversity, foot_contact_score, frechet_distance, motion_beats
from choreo.motion import Motion


def test_fid_equals_the_closed_form_for_diagonal_gaussians():
    # For diagonal covariances, tr(Sa + Sb - 2 sqrt(Sa Sb)) = sum (sd_a - sd_b)^2.
    rng = np.random.default_rng(0)
    a = rng.normal([0.0, 1.0, -2.0], [1.0, 2.0, 0.5], size=(4000, 3))
    b = rng.normal([0.5, 1.0, 0.0], [1.5, 1.0, 0.5], size=(4000, 3))
    # exactly diagonal sample covariances: decorrelate each set's columns by construction
    a = (a - a.mean(0)) @ np.linalg.inv(np.linalg.cholesky(np.cov(a, rowvar=False))).T * [1.0, 2.0, 0.5] + [0.0, 1.0, -2.0]
    b = (b - b.mean(0)) @ np.linalg.inv(np.linalg.cholesky(np.cov(b, rowvar=False))).T * [1.5, 1.0, 0.5] + [0.5, 1.0, 0.0]
    expected = (0.5**2 + 0 + 2.0**2) + ((1.0 - 1.5) ** 2 + (2.0 - 1.0) ** 2 + 0.0)
    assert frechet_distance(a, b) == pytest.approx(expected, rel=1e-9)


def test_fid_mean_term_alone():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(500, 4))
    assert frechet_distance(a, a + [3.0, 0.0, -4.0, 0.0]) == pytest.approx(25.0, rel=1e-9)


def test_diversity_is_the_mean_pairwise_distance():
    points = np.array([[0.0, 0.0], [3.0, 4.0], [6.0, 8.0]])
    assert diversity(points) == pytest.approx((5 + 10 + 5) / 3)


def test_beat_align_default_sigma_is_three_frames():
    # music beats at 10 and 40; motion beats 3 frames off the first, on the second
    value = beat_align_score(np.array([10, 40]), np.array([13, 40]))
    assert value == pytest.approx((np.exp(-9 / (2 * 3.0**2)) + 1.0) / 2)
    # it averages over MUSIC beats: an extra motion beat far away changes nothing
    assert beat_align_score(np.array([10, 40]), np.array([13, 40, 90])) == pytest.approx(value)


def test_motion_beats_are_minima_of_the_smoothed_mean_joint_speed():
    frames = 120
    t = np.arange(frames)
    speed = 1.0 + np.cos(2 * np.pi * t / 30)  # minima at 15, 45, 75, 105 (frame-to-frame step)
    x = np.concatenate([[0.0], np.cumsum(speed[:-1])]) * 0.01
    positions = np.zeros((frames, 24, 3))
    positions[..., 0] = x[:, None]
    beats = motion_beats(positions)
    assert beats.tolist() == [15, 45, 75, 105]


def literal_pfc(positions_y_up: np.ndarray) -> float:
    """EDGE's PFC term written as a plain loop over frames, on Z-up data (x, y horizontal)."""
    z_up = np.stack([positions_y_up[..., 0], -positions_y_up[..., 2], positions_y_up[..., 1]], axis=-1)
    dt = 1 / 30
    root = z_up[:, 0]
    accelerations = []
    for t in range(1, len(root) - 1):
        a = (root[t + 1] - 2 * root[t] + root[t - 1]) / dt**2
        a[2] = max(a[2], 0.0)
        accelerations.append(np.linalg.norm(a))
    peak = max(accelerations)
    total = 0.0
    for t in range(1, len(root) - 1):
        slides = []
        for ankle, toe in ((7, 10), (8, 11)):
            slides.append(min(np.linalg.norm(z_up[t + 1, j, :2] - z_up[t, j, :2]) for j in (ankle, toe)))
        total += slides[0] * slides[1] * accelerations[t - 1] / peak
    return total / (len(root) - 2)


def test_pfc_equals_a_literal_loop_and_ignores_vertical_foot_motion():
    rng = np.random.default_rng(3)
    positions = np.repeat(Motion.rest(1).joint_positions(), 40, axis=0) + rng.normal(scale=0.02, size=(40, 24, 3))
    assert foot_contact_score(positions) == pytest.approx(literal_pfc(positions), rel=1e-9)
    lifting = np.repeat(Motion.rest(1).joint_positions(), 40, axis=0)
    lifting[:, 0, 0] += 0.3 * np.sin(np.arange(40) / 4)  # the root accelerates sideways
    lifting[:, [7, 8, 10, 11], 1] += 0.05 * np.abs(np.sin(np.arange(40) / 3))[:, None]  # feet go up and down only
    assert foot_contact_score(lifting) == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("axis", [0, 2])
def test_pfc_counts_both_horizontal_axes(axis):
    sliding = np.repeat(Motion.rest(1).joint_positions(), 40, axis=0)
    path = 0.3 * np.sin(np.arange(40) / 4)
    sliding[:, :, axis] += path[:, None]
    assert foot_contact_score(sliding) == pytest.approx(literal_pfc(sliding), rel=1e-9)
    assert foot_contact_score(sliding) > 1e-5


def test_all_pairs_of_diversity_are_unordered():
    rng = np.random.default_rng(4)
    points = rng.normal(size=(6, 3))
    pairs = [np.linalg.norm(p - q) for p, q in itertools.combinations(points, 2)]
    assert diversity(points) == pytest.approx(np.mean(pairs))
