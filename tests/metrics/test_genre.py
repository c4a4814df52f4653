"""Tests of choreo.metrics.genre.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""


import numpy as np
import pytest

from choreo.metrics import (
    genre,
)


def test_genre_classifier_tells_fast_from_slow_dances():
    from choreo.metrics.genre import GenreClassifier

    rng = np.random.default_rng(0)
    t = np.arange(150) / 30
    body = rng.normal(size=(1, 24, 3)) * 0.3

    def dance(speed):
        positions = np.tile(body, (150, 1, 1))
        positions[:, 20:22, 1] += 0.4 * np.sin(2 * np.pi * speed * t + rng.uniform(0, 6))[:, None]
        return positions + rng.normal(scale=0.01, size=positions.shape)

    train = [dance(0.5) for _ in range(30)] + [dance(3.0) for _ in range(10)]
    labels = ["slow"] * 30 + ["fast"] * 10
    classifier = GenreClassifier.fit(train, labels)
    assert classifier.agreement([dance(0.5) for _ in range(5)] + [dance(3.0) for _ in range(5)],
                                ["slow"] * 5 + ["fast"] * 5) >= 0.9
    assert classifier.agreement([dance(3.0)], ["slow"]) == 0.0


def reference_fit(features: np.ndarray, labels: list, l2: float = 1e-2):
    """The class-weighted multinomial logistic regression, written in numpy and solved by BFGS."""
    import scipy.optimize

    names = sorted(set(labels))
    y = np.array([names.index(g) for g in labels])
    classes, dims = len(names), features.shape[1]
    mean = features.sum(0) / len(features)
    std = np.sqrt(((features - mean) ** 2).sum(0) / len(features)) + 1e-8
    x = (features - mean) / std
    per_class = len(y) / (classes * np.bincount(y))  # inverse frequency: n / (G * n_c)
    sample_weight = per_class[y] / per_class[y].sum()

    def loss(theta):
        weights, bias = theta[: dims * classes].reshape(dims, classes), theta[dims * classes:]
        z = x @ weights + bias
        z = z - z.max(1, keepdims=True)
        log_p = z - np.log(np.exp(z).sum(1, keepdims=True))
        value = -(sample_weight * log_p[np.arange(len(y)), y]).sum() + l2 * (weights**2).sum()
        residual = np.exp(log_p)
        residual[np.arange(len(y)), y] -= 1
        residual *= sample_weight[:, None]
        return value, np.concatenate([(x.T @ residual + 2 * l2 * weights).ravel(), residual.sum(0)])

    solution = scipy.optimize.minimize(loss, np.zeros(dims * classes + classes), jac=True, method="BFGS",
                                       options={"gtol": 1e-12, "maxiter": 10_000}).x
    return names, mean, std, solution[: dims * classes].reshape(dims, classes), solution[dims * classes:]


@pytest.mark.survivor
def test_genre_classifier_fit_is_the_weighted_logistic_regression(monkeypatch):
    rng = np.random.default_rng(1)
    features = rng.normal(size=(30, 40)) * np.linspace(0.5, 3.0, 40) + np.linspace(-5.0, 5.0, 40)
    labels = ["a"] * 18 + ["b"] * 8 + ["c"] * 4  # unbalanced: the class weights matter
    features[:18, :5] += 0.5
    features[18:26, 5:10] -= 0.5
    features[:, 7] = 2.5  # a constant feature: standardised by the epsilon alone
    monkeypatch.setattr(genre, "clip_features", lambda positions: np.asarray(positions, dtype=np.float64))
    classifier = genre.GenreClassifier.fit(features, labels)
    names, mean, std, weights, bias = reference_fit(features, labels)
    assert classifier.genres == names == ["a", "b", "c"]
    np.testing.assert_allclose(classifier.mean, mean, rtol=1e-12)
    np.testing.assert_allclose(classifier.std, std, rtol=1e-12, atol=0)
    assert classifier.std[7] == 1e-8
    assert classifier.weights.dtype == np.float64 and classifier.bias.dtype == np.float64
    np.testing.assert_allclose(classifier.weights, weights, atol=2e-4)
    np.testing.assert_allclose(classifier.bias, bias, atol=2e-4)
    assert np.abs(bias).max() > 0.1


@pytest.mark.survivor
def test_genre_classifier_predicts_from_standardised_features(monkeypatch):
    monkeypatch.setattr(genre, "clip_features", lambda positions: np.asarray(positions, dtype=np.float64))
    classifier = genre.GenreClassifier(["slow", "fast"], mean=np.array([1.0, 2.0]), std=np.array([2.0, 4.0]),
                                       weights=np.array([[1.0, -1.0], [0.0, 0.0]]), bias=np.array([0.0, 0.5]))
    # x = (f - mean) / std; logits (x0, -x0 + 0.5): "slow" when x0 > 0.25, i.e. f0 > 1.5
    assert classifier.predict(np.array([[1.6, 0.0], [1.4, 0.0], [0.0, 9.0]])) == ["slow", "fast", "fast"]
    # with x multiplied by std instead, f0 = 1.2 would give x0 = 0.4 and "slow"
    assert classifier.predict(np.array([[1.2, 0.0]])) == ["fast"]
