"""Slow, literal versions of reference metric definitions, kept as oracles.

The vectorised metrics in this package are tested against these loops (tests/metrics/)
and timed against them (benchmarks/bench_eval.py); nothing in choreo's own path calls them.
"""

from __future__ import annotations

import numpy as np

from ..motion import Motion


def random_dances(count: int, frames: int = 150, seed: int = 0) -> list[np.ndarray]:
    """(frames, 24, 3) joint positions of random-walk dances: inputs with every joint moving."""
    rng = np.random.default_rng(seed)
    dances = []
    for _ in range(count):
        axis_angle = np.cumsum(rng.normal(scale=0.05, size=(frames, 24, 3)), axis=0)
        root = np.cumsum(rng.normal(scale=0.02, size=(frames, 3)), axis=0) + [0, 0.9, 0]
        dances.append(Motion.from_axis_angle(root, axis_angle).joint_positions())
    return dances


def literal_kinetic(positions: np.ndarray, dt: float = 1 / 60, window: int = 2) -> np.ndarray:
    """The reference kinetic features, frame by frame and joint by joint as first written
    (slip included), against which :func:`choreo.metrics.kinetic_features` is checked and timed."""
    T = len(positions)
    out = []
    for joint in range(24):
        h = v = e = 0.0
        for i in range(1, T):
            total, count = np.zeros(3), 0
            for j in range(-window, window + 1):
                if i + j - 1 < 0 or i + j >= T:
                    continue
                total += positions[i + j, joint] - positions[i + j - 1, joint]
                count += 1
            velocity = total / (count * dt)
            h += velocity[0] ** 2 + velocity[2] ** 2
            v += velocity[1] ** 2
            acc, count = np.zeros(3), 0
            for j in range(-window, window + 1):
                if i + j - 1 < 0 or i + j + 1 >= T:
                    continue
                later = (positions[i + j + 1, joint] - positions[i + j, joint]) / dt
                earlier = positions[i + j, joint] - positions[i + j - 1, joint] / dt  # the reference's slip
                acc += (later - earlier) / dt
                count += 1
            e += np.linalg.norm(acc / count)
        out += [h / (T - 1), v / (T - 1), e / (T - 1)]
    return np.array(out)
