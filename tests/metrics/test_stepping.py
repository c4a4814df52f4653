"""Stepping figures (choreo.metrics.stepping) on dances whose feet we choose frame by frame."""

import numpy as np
import pytest

from choreo.metrics import evaluate
from choreo.metrics.evaluate import Dance
from choreo.metrics.stepping import PLANTED_SPEED, pooled, pace_and_feet_by_genre, stepping
from choreo.skeleton import LEFT_ANKLE_FOOT, RIGHT_ANKLE_FOOT

FPS = 30.0


def body(root_x: np.ndarray, left_x: np.ndarray, right_x: np.ndarray) -> np.ndarray:
    """(T, 24, 3): every joint at the root but the feet, which stand apart on the floor."""
    positions = np.zeros((len(root_x), 24, 3))
    positions[:, :, 0] = root_x[:, None]
    positions[:, :, 1] = 0.9
    for joints, x, z in ((LEFT_ANKLE_FOOT, left_x, 0.1), (RIGHT_ANKLE_FOOT, right_x, -0.1)):
        positions[:, list(joints), 0] = x[:, None]
        positions[:, list(joints), 1] = 0.05
        positions[:, list(joints), 2] = z
    return positions


def walker(seconds: float = 4.0, speed: float = 1.0, step_seconds: float = 0.5) -> np.ndarray:
    """The root moves at ``speed``; each foot stands for one step, then swings to catch up at twice
    the speed, left and right alternating: one foot always carries the body."""
    t = np.arange(int(seconds * FPS)) / FPS
    root = speed * t
    phase = (t / step_seconds) % 2.0  # 0-1: left stands, 1-2: left swings
    left = np.where(phase < 1, np.floor(t / (2 * step_seconds)) * 2 * step_seconds * speed,
                    np.floor(t / (2 * step_seconds)) * 2 * step_seconds * speed + 2 * speed * step_seconds * (phase - 1))
    right = np.roll(left, int(step_seconds * FPS)) + speed * step_seconds
    right[: int(step_seconds * FPS)] = speed * step_seconds  # right stands while left takes its first step
    return body(root, left, right)


def test_a_skater_glides_and_a_walker_steps():
    t = np.arange(120) / FPS
    skater = stepping(body(1.0 * t, 1.0 * t + 0.1, 1.0 * t - 0.1), FPS)
    assert skater.planted_share == 0.0
    assert skater.support_slide == pytest.approx(1.0)
    walk = stepping(walker(), FPS)
    assert walk.planted_share > 0.9  # one foot stands in (almost) every frame
    assert walk.support_slide < 0.1  # the supporting foot barely moves while the root covers 4 m
    assert walk.root_travel == pytest.approx(119 / FPS, rel=1e-6)


def test_correlation_follows_the_root_for_skaters_only():
    t = np.arange(150) / FPS
    pace = 1.0 + 0.5 * np.sin(2 * np.pi * t)  # a root that speeds up and slows down
    root = np.cumsum(pace) / FPS
    assert stepping(body(root, root, root), FPS).foot_root_correlation == pytest.approx(1.0)
    walk = stepping(walker(seconds=5.0), FPS)  # a root at constant speed: nothing to correlate with
    assert np.isnan(walk.foot_root_correlation)


def test_threshold_is_horizontal_speed_of_the_slower_foot_joint():
    t = np.arange(60) / FPS
    slow = 0.9 * PLANTED_SPEED
    still = body(np.zeros(60), slow * t, np.full(60, 1.0))
    assert stepping(still, FPS).planted_share == 1.0
    lifted = still.copy()
    lifted[:, list(RIGHT_ANKLE_FOOT), 1] += 0.3 * t[:, None]  # rising straight up does not count as moving
    assert stepping(lifted, FPS).planted_share == 1.0
    both_fast = body(np.zeros(60), 1.2 * PLANTED_SPEED * t, -1.2 * PLANTED_SPEED * t)
    assert stepping(both_fast, FPS).planted_share == 0.0
    toe_pivot = both_fast.copy()
    toe_pivot[:, RIGHT_ANKLE_FOOT[1], 0] = 0.0  # the right toe stays: a pivot, the foot is planted
    assert stepping(toe_pivot, FPS).planted_share == 1.0


def test_pooled_weighs_frames_and_metres_not_dances():
    t = np.arange(120) / FPS
    skater = stepping(body(t, t, t), FPS)
    standing = stepping(body(np.zeros(30), np.zeros(30), np.zeros(30)), FPS)
    share, correlation, slide = pooled([skater, standing])
    assert share == pytest.approx(29 / (119 + 29))
    assert slide == pytest.approx(1.0)  # the standing dance travels no metres to weigh
    assert np.isnan(standing.support_slide) and np.isnan(standing.foot_root_correlation)
    assert np.isnan(correlation)  # no dance with a correlation (the skater's root speed is constant)


def test_short_dances_score_without_failing():
    assert stepping(np.zeros((2, 24, 3)), FPS).frames == 1
    assert stepping(np.zeros((0, 24, 3)), FPS).frames == 0


def test_evaluation_report_carries_stepping_for_both_sets():
    t = np.arange(150) / FPS
    skaters = [Dance(f"s{i}", body(t * (1 + i), t * (1 + i), t * (1 + i))) for i in range(3)]
    walkers = [Dance(f"w{i}", walker(seconds=5.0, speed=1 + 0.2 * i)) for i in range(3)]
    report = evaluate(skaters, walkers)
    assert report.planted_share == 0.0 and report.ground_truth_planted_share > 0.9
    assert report.support_slide == pytest.approx(1.0) and report.ground_truth_support_slide < 0.1
    assert report.clips[0].stepping.frames == 149
    assert "planted_frames" in report.to_dict()["clips"][0]["stepping"]


def test_by_genre_reports_each_genres_pace_and_feet_beside_the_real_ones():
    t = np.arange(150) / FPS
    pace = 1.0 + 0.5 * np.sin(2 * np.pi * t)
    root = np.cumsum(pace) / FPS
    skater = body(root, root, root)  # feet travel with the root: correlation 1
    slow = body(0.5 * t, 0.5 * t + 0.1, 0.5 * t - 0.1)  # constant pace 0.5 m/s: no correlation to take
    line = pace_and_feet_by_genre([skater, slow], [slow, skater], ["rumba", "waltz"], FPS)
    speeds, feet = line.split("; ")
    assert speeds == f"root m/s rumba {np.median(pace[1:]):.2f} (0.50), waltz 0.50 ({np.median(pace[1:]):.2f})"
    assert feet == "foot~root rumba 1.00 (nan), waltz nan (1.00)"
