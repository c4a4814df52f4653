"""A genre classifier on motion alone, for style adherence: does a dance asked to be a waltz
look like the waltzes of the data?

Multinomial logistic regression on the FID features of a clip (72 kinetic + 32 geometric,
standardised), classes weighted by their inverse frequency so a genre with few clips still
counts. Trained on real motion; its accuracy on real test clips says how much a "recognised as
the requested genre" share can be trusted.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import torch

from .fid import motion_features


def clip_features(positions: Sequence[np.ndarray]) -> np.ndarray:
    """(N, 104) kinetic + geometric features, one row per clip of (T, 24, 3) joint positions."""
    return np.stack([np.concatenate(motion_features(p)) for p in positions]).astype(np.float64)


@dataclass
class GenreClassifier:
    genres: list[str]
    mean: np.ndarray
    std: np.ndarray
    weights: np.ndarray  # (F, G)
    bias: np.ndarray  # (G,)

    @classmethod
    def fit(cls, positions: Sequence[np.ndarray], genres: Sequence[str], l2: float = 1e-2) -> "GenreClassifier":
        names = sorted(set(genres))
        features = clip_features(positions)
        mean, std = features.mean(0), features.std(0) + 1e-8
        x = torch.from_numpy((features - mean) / std)
        y = torch.tensor([names.index(g) for g in genres])
        counts = torch.bincount(y, minlength=len(names)).double()
        class_weight = counts.sum() / (len(names) * counts)
        weights = torch.zeros(x.shape[1], len(names), dtype=torch.float64, requires_grad=True)
        bias = torch.zeros(len(names), dtype=torch.float64, requires_grad=True)
        optimizer = torch.optim.LBFGS([weights, bias], max_iter=500, line_search_fn="strong_wolfe")

        def closure():
            optimizer.zero_grad()
            loss = torch.nn.functional.cross_entropy(x @ weights + bias, y, weight=class_weight) + l2 * weights.square().sum()
            loss.backward()
            return loss

        optimizer.step(closure)
        return cls(names, mean, std, weights.detach().numpy(), bias.detach().numpy())

    def predict(self, positions: Sequence[np.ndarray]) -> list[str]:
        logits = ((clip_features(positions) - self.mean) / self.std) @ self.weights + self.bias
        return [self.genres[i] for i in logits.argmax(1)]

    def agreement(self, positions: Sequence[np.ndarray], genres: Sequence[str]) -> float:
        """Share of clips recognised as ``genres`` (accuracy on real clips, adherence on generated ones)."""
        return float(np.mean([p == g for p, g in zip(self.predict(positions), genres)]))
