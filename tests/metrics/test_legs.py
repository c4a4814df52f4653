"""The legs figures and the classifier two-sample test (choreo.metrics.legs, .two_sample), on motions
whose answers are known by construction."""

import numpy as np
import pytest

from choreo.metrics.legs import ankle_lift, feet_speed, foot_jerk, legs, mean_legs, pelvis_speed
from choreo.metrics.two_sample import classifier_test, windows_of
from choreo.motion import Motion
from choreo.skeleton.smpl import FOOT_JOINTS, LEFT_ANKLE, RIGHT_ANKLE

FPS = 30.0


def still_body(frames=300):
    positions = np.zeros((frames, 24, 3))
    positions[:, :, 1] = np.linspace(0.0, 1.6, 24)  # a column of joints, the feet on the floor
    positions[:, list(FOOT_JOINTS), 1] = 0.05
    return positions


def test_feet_circling_the_pelvis_move_at_their_circles_speed():
    positions = still_body()
    t = np.arange(len(positions)) / FPS
    radius, hertz = 0.2, 1.0
    for joint in FOOT_JOINTS:
        positions[:, joint, 0] += radius * np.cos(2 * np.pi * hertz * t)
        positions[:, joint, 2] += radius * np.sin(2 * np.pi * hertz * t)
    assert feet_speed(positions, FPS) == pytest.approx(2 * np.pi * radius * hertz, rel=1e-2)
    assert pelvis_speed(positions, FPS) == 0.0


def test_a_body_gliding_with_its_feet_still_under_it_has_no_feet_speed():
    positions = still_body()
    positions[:, :, 0] += np.arange(len(positions))[:, None] / FPS * 0.5  # 0.5 m/s, every joint along
    assert feet_speed(positions, FPS) == pytest.approx(0.0, abs=1e-9)
    assert pelvis_speed(positions, FPS) == pytest.approx(0.5)
    assert foot_jerk(positions, FPS) == pytest.approx(0.0, abs=1e-6)  # constant velocity


def test_ankle_lift_is_each_ankles_height_over_its_own_floor():
    positions = still_body(200)
    positions[:, LEFT_ANKLE, 1] += 0.5  # one ankle stands higher: its own floor, not the other's
    positions[::2, LEFT_ANKLE, 1] += 0.2  # half its frames 0.2 m up
    positions[::2, RIGHT_ANKLE, 1] += 0.1
    assert ankle_lift(positions) == pytest.approx((0.2 + 0.1) / 2)
    positions[5, RIGHT_ANKLE, 1] += 3.0  # one spike does not move a percentile
    assert ankle_lift(positions) == pytest.approx(0.15)


def test_too_short_dances_have_no_figures_and_the_mean_skips_them():
    assert np.isnan(legs(still_body(3), FPS).feet_speed)
    mean = mean_legs([legs(still_body(3), FPS), legs(still_body(30), FPS)])
    assert mean.feet_speed == 0.0 and mean.pelvis_speed == 0.0


def dancer(seed, swing=0.4, seconds=30.0):
    """An SMPL dancer whose legs swing by ``swing`` radians, each dance at its own tempo and phase."""
    rng = np.random.default_rng(seed)
    frames = int(seconds * FPS)
    t = np.arange(frames)[:, None] / FPS
    hertz, phase = rng.uniform(0.8, 1.6), rng.uniform(0, 2 * np.pi)
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 1, 0] = swing * np.sin(2 * np.pi * hertz * t[:, 0] + phase)  # hips
    axis_angle[:, 2, 0] = -swing * np.sin(2 * np.pi * hertz * t[:, 0] + phase)
    axis_angle[:, 16:18, 2] = 0.3 * np.sin(2 * np.pi * hertz / 2 * t + phase)  # shoulders
    axis_angle += rng.normal(scale=0.01, size=axis_angle.shape)
    root = np.concatenate([0.1 * np.sin(t), 0.9 + 0 * t, 0.05 * t], axis=1)
    return Motion.from_axis_angle(root, axis_angle, fps=FPS).joint_positions()


def test_the_classifier_cannot_tell_one_kind_of_dancer_from_itself():
    result = classifier_test([dancer(i) for i in range(8)], [dancer(100 + i) for i in range(8)], FPS)
    assert result.windows == result.reference_windows == 8 * len(windows_of(dancer(0), FPS)) and result.folds == 5
    assert 0.3 <= result.accuracy <= 0.7


def test_the_classifier_tells_shuffling_legs_from_stepping_ones():
    result = classifier_test([dancer(i, swing=0.1) for i in range(8)], [dancer(100 + i) for i in range(8)], FPS)
    assert result.accuracy > 0.95


def test_windows_of_one_dance_never_train_the_fold_that_scores_them():
    """Each dance its own tempo: a classifier that saw a dance's other windows would know its set
    from its tempo alone. Grouped, it cannot; with every window its own group, it could."""
    dances, reference = [dancer(i) for i in range(6)], [dancer(100 + i) for i in range(6)]
    grouped = classifier_test(dances, reference, FPS)
    leaky = classifier_test([w for d in dances for w in windows_of(d, FPS)],
                            [w for d in reference for w in windows_of(d, FPS)], FPS)
    assert grouped.accuracy < 0.75 and leaky.accuracy > grouped.accuracy + 0.15


def test_too_few_groups_give_no_accuracy():
    assert np.isnan(classifier_test([dancer(0)], [dancer(1), dancer(2)], FPS).accuracy)
