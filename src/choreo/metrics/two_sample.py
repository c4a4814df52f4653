"""A classifier two-sample test: how well can a simple model tell a set of dances from a reference set?

Both sets are cut into 5 s windows; each window is described by a fixed set of features (the 72
kinetic and 32 geometric features FID uses, and the three stepping figures); a logistic regression
learns to tell the sets apart, and is scored by its balanced accuracy on windows it did not see
(cross-validated). 0.5: the model cannot tell them apart; 1: every window gives itself away.
Unlike FID it needs no Gaussian assumption and says how separable the sets are, not how far apart
their means lie (Lopez-Paz and Oquab, "Revisiting Classifier Two-Sample Tests", 2017).

Windows overlap and windows of one dance resemble each other, so the folds are grouped: every
window of one group (a dance: one song and one seed) is in the same fold, and a fold never sees its
own dance in training. docs/metrics.md, "Legs and realism".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .fid import motion_features
from .stepping import stepping

WINDOW_SECONDS, HOP_SECONDS = 5.0, 2.5
FOLDS = 5
REGULARISATION = 1.0  # the logistic regression's C: scikit-learn's default, fixed so figures compare


@dataclass(frozen=True)
class TwoSample:
    accuracy: float  # cross-validated balanced accuracy; 0.5 indistinguishable; NaN: too few windows or groups
    windows: int  # windows of the dances
    reference_windows: int
    folds: int


def window_features(positions: np.ndarray, fps: float) -> np.ndarray:
    """(107,) one window's features: kinetic (72), geometric (32), stepping (planted share,
    foot-root correlation, support slide; NaN where the window has none)."""
    kinetic, geometric = motion_features(positions)
    steps = stepping(positions, fps)
    return np.concatenate([kinetic, geometric, [steps.planted_share, steps.foot_root_correlation, steps.support_slide]])


def windows_of(positions: np.ndarray, fps: float) -> list[np.ndarray]:
    """The 5 s windows every 2.5 s of one dance (T, 24, 3); a dance shorter than a window: none."""
    size, hop = round(WINDOW_SECONDS * fps), round(HOP_SECONDS * fps)
    return [positions[start:start + size] for start in range(0, len(positions) - size + 1, hop)]


def classifier_test(dances: Sequence[np.ndarray], reference: Sequence[np.ndarray], fps: float = 30.0,
                    groups: Sequence[str] | None = None, reference_groups: Sequence[str] | None = None) -> TwoSample:
    """The cross-validated balanced accuracy of telling ``dances``' windows from ``reference``'s.
    ``groups`` name each dance's group (song and seed; default: each dance its own); windows of one
    group share a fold. Pooled: every window of every dance in one test."""
    from sklearn.impute import SimpleImputer
    from sklearn.linear_model import LogisticRegression
    from sklearn.metrics import balanced_accuracy_score
    from sklearn.model_selection import StratifiedGroupKFold
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    groups = list(groups) if groups is not None else [f"dance {i}" for i in range(len(dances))]
    reference_groups = (list(reference_groups) if reference_groups is not None
                        else [f"reference {i}" for i in range(len(reference))])
    features, labels, window_groups = [], [], []
    for label, (motions, names) in enumerate(((dances, groups), (reference, reference_groups))):
        for motion, name in zip(motions, names):
            for window in windows_of(np.asarray(motion, dtype=np.float64), fps):
                features.append(window_features(window, fps))
                labels.append(label)
                window_groups.append(f"{label}:{name}")
    labels = np.array(labels)
    counts = (int((labels == 0).sum()), int((labels == 1).sum()))
    folds = min(FOLDS, *(len({g for g, y in zip(window_groups, labels) if y == c}) for c in (0, 1)))
    if folds < 2:
        return TwoSample(float("nan"), *counts, folds)
    model = make_pipeline(SimpleImputer(strategy="median", keep_empty_features=True), StandardScaler(),
                          LogisticRegression(C=REGULARISATION, class_weight="balanced", max_iter=5000))
    predicted = np.empty_like(labels)
    features = np.nan_to_num(np.array(features), nan=np.nan, posinf=np.nan, neginf=np.nan)
    for train, test in StratifiedGroupKFold(n_splits=folds).split(features, labels, window_groups):
        predicted[test] = model.fit(features[train], labels[train]).predict(features[test])
    return TwoSample(float(balanced_accuracy_score(labels, predicted)), *counts, folds)
