"""Tests of choreo.metrics.evaluate.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import warnings

import numpy as np
import pytest
import scipy.linalg

from choreo.metrics import (
    Dance,
    MetricWarning,
    evaluate,
    motion_beats,
    motion_features,
)
from choreo.metrics.evaluate import _mean_of, score_dance
from choreo.metrics.reference_loops import random_dances
from tests.metrics.helpers import literal_pfc_z_up, no_warnings, sliding_body, z_up_of


def test_fid_of_a_set_with_itself_is_zero_and_translation_does_not_change_it():
    generated = random_dances(40, seed=1)
    truth = random_dances(40, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        same = evaluate([Dance(str(i), p) for i, p in enumerate(truth)], [Dance(str(i), p) for i, p in enumerate(truth)])
        # Zero up to sqrtm's round-off on singular covariances (40 samples, 72 dimensions).
        assert abs(same.fid_k) < 1e-4 and abs(same.fid_g) < 1e-4
        base = evaluate([Dance("g", p) for p in generated], [Dance("t", p) for p in truth])
        moved = evaluate([Dance("g", p + [3.0, 0.5, -7.0]) for p in generated], [Dance("t", p) for p in truth])
    assert base.fid_k > 0.1 and np.isfinite(base.fid_k) and np.isfinite(base.fid_g)
    assert moved.fid_k == pytest.approx(base.fid_k, rel=1e-6)
    assert moved.fid_g == pytest.approx(base.fid_g, rel=1e-6)
    assert isinstance(base.fid_k, float)


@pytest.mark.survivor
def test_mean_of_skips_missing_and_non_finite_values():
    assert _mean_of([1.0, None, float("nan"), 4.0, float("inf")]) == 2.5
    assert _mean_of(v for v in [None, float("nan")]) is None
    assert _mean_of([]) is None


BEAT_FRAMES = [15, 45, 75, 105]  # speed minima of beating_positions


def beating_positions() -> np.ndarray:
    t = np.arange(120)
    speed = 1.0 + np.cos(2 * np.pi * t / 30)
    x = np.concatenate([[0.0], np.cumsum(speed[:-1])]) * 0.01
    return sliding_body(120, x)


@pytest.mark.survivor
def test_score_dance_fields_by_hand():
    positions = beating_positions()
    assert motion_beats(positions).tolist() == BEAT_FRAMES
    with no_warnings():
        score = score_dance(Dance("clip", positions, np.array([14, 45, 80])), fps=24.0)
    assert score.name == "clip" and score.frames == 120 and score.seconds == 5.0
    assert score.beat_align == pytest.approx((np.exp(-1 / 18) + 1 + np.exp(-25 / 18)) / 3)
    # motion -> music: 15-14, 45-45, 75-80, 105-80; music -> motion: 14-15, 45-45, 80-75
    assert score.motion_to_music == pytest.approx((1 + 0 + 25 + 625) / 4)
    assert score.music_to_motion == pytest.approx((1 + 0 + 25) / 3)
    assert score.pfc == pytest.approx(literal_pfc_z_up(z_up_of(positions)) * 10_000, rel=1e-9)


def literal_diversity(rows: np.ndarray) -> float:
    distances = [np.sqrt(((rows[i] - rows[j]) ** 2).sum()) for i in range(len(rows)) for j in range(i + 1, len(rows))]
    return sum(distances) / len(distances)


@pytest.mark.survivor
def test_evaluate_report_fields_against_literal_numbers():
    dances = random_dances(6, frames=40, seed=11)
    generated = [Dance("g0", dances[0], np.array([5, 20])), Dance("g1", dances[1]), Dance("g2", dances[2], np.array([8]))]
    truth = [Dance("t0", dances[3], np.array([10, 30])), Dance("t1", dances[4]), Dance("t2", dances[5][:30])]
    calls = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MetricWarning)
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        report = evaluate(generated, truth, fps=20.0, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(i, 6) for i in range(1, 7)]
    assert report.fps == 20.0 and report.generated_count == 3 and report.ground_truth_count == 3
    assert report.mean_clip_seconds == pytest.approx(2.0)
    assert [c.name for c in report.clips] == ["g0", "g1", "g2"]
    assert [(c.name, c.frames) for c in report.ground_truth_clips] == [("t0", 40), ("t1", 40), ("t2", 30)]

    def pfc(d):
        return literal_pfc_z_up(z_up_of(d.positions)) * 10_000

    assert report.pfc == pytest.approx(np.mean([pfc(d) for d in generated]), rel=1e-9)
    assert report.ground_truth_pfc == pytest.approx(np.mean([pfc(d) for d in truth]), rel=1e-9)

    def align(d):
        beats = motion_beats(d.positions)
        return np.mean([np.exp(-min((m - b) ** 2 for b in beats) / 18) for m in d.music_beats])

    def squared(queries, references):
        return np.mean([min((q - r) ** 2 for r in references) for q in queries])

    with_music = [d for d in generated if d.music_beats is not None]
    assert report.beat_align == pytest.approx(np.mean([align(d) for d in with_music]))
    assert report.ground_truth_beat_align == pytest.approx(align(truth[0]))
    assert report.motion_to_music == pytest.approx(np.mean([squared(motion_beats(d.positions), d.music_beats) for d in with_music]))
    assert report.music_to_motion == pytest.approx(np.mean([squared(d.music_beats, motion_beats(d.positions)) for d in with_music]))

    features = [motion_features(d.positions) for d in generated + truth]
    for index, (div, truth_div) in enumerate([("div_k", "ground_truth_div_k"), ("div_g", "ground_truth_div_g")]):
        rows = np.array([f[index] for f in features], dtype=np.float64)
        mean = rows[3:].sum(0) / 3
        std = np.sqrt(((rows[3:] - mean) ** 2).sum(0) / 3) + 1e-10
        assert getattr(report, div) == pytest.approx(literal_diversity((rows[:3] - mean) / std), rel=1e-6)
        assert getattr(report, truth_div) == pytest.approx(literal_diversity((rows[3:] - mean) / std), rel=1e-6)


@pytest.mark.survivor
def test_evaluate_without_generated_dances_reports_zero_seconds():
    truth = [Dance(str(i), p) for i, p in enumerate(random_dances(2, frames=30, seed=4))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = evaluate([], truth)
    assert report.mean_clip_seconds == 0.0 and report.generated_count == 0 and report.clips == []
    assert report.fps == 30.0 and [c.seconds for c in report.ground_truth_clips] == [1.0, 1.0]  # 30 frames at 30 fps
