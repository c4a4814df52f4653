"""Tests of choreo.metrics.pfc.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

import numpy as np
import pytest

from choreo.metrics import (
    foot_contact_score,
    motion_beats,
)
from choreo.metrics.pfc import Y_UP_TO_Z_UP, to_z_up
from choreo.metrics.reference_loops import random_dances
from choreo.motion import Motion
from tests.metrics.helpers import literal_pfc_z_up, no_warnings, sliding_body, z_up_of


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


def test_sliding_feet_with_accelerating_root_score_worse_than_planted_feet():
    frames = 90
    t = np.arange(frames) / 30
    base = np.repeat(Motion.rest(1).joint_positions(), frames, axis=0)
    root_path = np.stack([0.5 * np.sin(2 * np.pi * t), 0.05 * np.sin(4 * np.pi * t), np.zeros(frames)], -1)
    planted = base.copy()
    planted[:, [0, 3, 6, 9, 12, 15]] += root_path[:, None]  # the upper body sways, feet stay put
    sliding = base + root_path[:, None]  # everything, feet included, slides with the root
    assert foot_contact_score(planted) == pytest.approx(0.0, abs=1e-12)
    assert foot_contact_score(sliding) > 1e-4


def test_z_up_and_y_up_give_the_same_numbers():
    dances = random_dances(6, seed=5)
    z_up = [p @ Y_UP_TO_Z_UP.T for p in dances]
    for y, z in zip(dances, z_up):
        assert foot_contact_score(y, up_axis="y") == pytest.approx(foot_contact_score(z, up_axis="z"), rel=1e-9)
        np.testing.assert_array_equal(motion_beats(y), motion_beats(z))


@pytest.mark.survivor
def test_pfc_on_exactly_three_frames_is_scored():
    positions = sliding_body(3, [0.0, 0.1, 0.3])  # one acceleration, so it is its own peak
    with no_warnings():
        # one frame: each foot's smaller slide is 0.2 m, times an acceleration at its peak (1)
        assert foot_contact_score(positions) == pytest.approx(0.2 * 0.2, rel=1e-12)


@pytest.mark.survivor
def test_pfc_is_zero_when_the_root_never_accelerates_upward_or_sideways():
    t = np.arange(12.0)
    steady = sliding_body(12, 0.25 * t)  # constant velocity, exact in binary: no acceleration at all
    falling = sliding_body(12, 0.25 * t)
    falling[:, 0, 1] -= 0.0625 * t**2  # the root accelerates downward only, clamped to 0
    with no_warnings():
        assert foot_contact_score(steady) == 0.0
        assert foot_contact_score(falling) == 0.0


@pytest.mark.survivor
def test_pfc_with_a_gentle_root_acceleration_below_one():
    t = np.arange(30.0)
    positions = sliding_body(30, 1e-4 * np.sin(t / 3))  # peak acceleration about 0.1 m/s^2
    assert 0 < np.abs(np.diff(positions[:, 0, 0], 2)).max() * 900 < 1
    assert foot_contact_score(positions) == pytest.approx(literal_pfc_z_up(z_up_of(positions)), rel=1e-9)
    assert foot_contact_score(positions) > 0


@pytest.mark.survivor
def test_pfc_of_float32_positions_is_computed_in_float64():
    rng = np.random.default_rng(7)
    z_up = (np.repeat(Motion.rest(1).joint_positions(), 25, axis=0) + rng.normal(scale=0.05, size=(25, 24, 3))).astype(np.float32)
    assert foot_contact_score(z_up, up_axis="z") == pytest.approx(literal_pfc_z_up(z_up), rel=1e-12)


@pytest.mark.survivor
def test_to_z_up_turns_y_up_by_default():
    positions = np.arange(24.0).reshape(2, 4, 3)
    np.testing.assert_array_equal(to_z_up(positions), z_up_of(positions))
    np.testing.assert_array_equal(to_z_up(positions, "z"), positions)


@pytest.mark.survivor
def test_unknown_up_axis_is_refused_by_name():
    with pytest.raises(ValueError, match="^up axis must be 'y' or 'z', got 'x'$"):
        foot_contact_score(sliding_body(3, [0.0, 0.1, 0.3]), up_axis="x")
