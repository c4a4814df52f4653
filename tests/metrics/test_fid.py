"""Tests of choreo.metrics.fid.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import itertools

import numpy as np
import pytest

from choreo.metrics import (
    MetricWarning,
    diversity,
    frechet_distance,
    normalise_by_reference,
    prepare_positions,
)
from tests.metrics.helpers import no_warnings


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


def test_all_pairs_of_diversity_are_unordered():
    rng = np.random.default_rng(4)
    points = rng.normal(size=(6, 3))
    pairs = [np.linalg.norm(p - q) for p, q in itertools.combinations(points, 2)]
    assert diversity(points) == pytest.approx(np.mean(pairs))


def test_diversity_of_identical_clips_is_zero():
    assert diversity(np.ones((5, 72))) == 0.0
    points = np.array([[0.0, 0.0], [3.0, 4.0]])
    assert diversity(points) == 5.0


def test_fid_is_finite_with_few_samples_and_warns():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(5, 72)), rng.normal(size=(6, 72))
    a, b = normalise_by_reference(a, b)
    with pytest.warns(MetricWarning, match="singular"):
        value = frechet_distance(a, b)
    assert np.isfinite(value) and isinstance(value, float)


@pytest.mark.survivor
def test_prepare_positions_works_in_float64():
    rng = np.random.default_rng(2)
    positions = rng.uniform(-3, 3, size=(5, 24, 3)).astype(np.float32)
    wide = positions.astype(np.float64)
    expected = wide - wide[0, 0]  # every joint of every frame relative to the frame-0 root
    np.testing.assert_array_equal(prepare_positions(positions), expected)


@pytest.mark.survivor
def test_normalise_by_reference_per_dimension_by_hand():
    reference = np.array([[0.0, 10.0, 5.0], [2.0, 30.0, 5.0]])  # means 1, 20, 5; population stds 1, 10, 0
    generated = np.array([[1.0, 40.0, 5.5], [3.0, 0.0, 4.0]])
    gen, ref = normalise_by_reference(generated, reference)
    np.testing.assert_allclose(gen[:, :2], [[0.0, 2.0], [2.0, -2.0]], rtol=1e-9)
    np.testing.assert_allclose(ref[:, :2], [[-1.0, -1.0], [1.0, 1.0]], rtol=1e-9)
    # a constant reference dimension is divided by the epsilon alone, 1e-10
    np.testing.assert_allclose(gen[:, 2], [0.5e10, -1e10], rtol=1e-12)
    np.testing.assert_array_equal(ref[:, 2], [0.0, 0.0])


@pytest.mark.survivor
def test_fid_with_two_samples_in_one_dimension_is_the_closed_form():
    a, b = np.array([[0.0], [2.0]]), np.array([[1.0], [5.0]])
    with no_warnings():
        # (1 - 3)^2 + var 2 + var 8 - 2 sqrt(2 * 8)
        assert frechet_distance(a, b) == pytest.approx(4 + 2 + 8 - 2 * 4, rel=1e-12)
