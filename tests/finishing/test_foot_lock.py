"""Foot lock: a planted foot's drift moves onto the root; fixed frames stay; moving feet are left alone."""

import math

import numpy as np
import pytest

from choreo.errors import ParameterError
from choreo.finishing import FootLockConfig, foot_lock
from choreo.finishing.foot_lock import planted_drift, root_correction
from choreo.metrics import foot_contact_score
from choreo.motion import Motion


def gliding(speed: float, frames: int = 90) -> Motion:
    """A dancer standing still in the rest pose while the whole body glides along x at ``speed`` m/s."""
    root = np.zeros((frames, 3))
    root[:, 0] = speed * np.arange(frames) / 30.0
    root[:, 1] = 0.9
    return Motion.rest(frames).replace(root_positions=root)


def horizontal_foot_steps(motion: Motion) -> np.ndarray:
    feet = motion.joint_positions()[:, [7, 8]] * [1.0, 0.0, 1.0]
    return np.linalg.norm(np.diff(feet, axis=0), axis=-1)


def test_drift_of_planted_feet_is_measured_horizontally():
    drift = planted_drift(gliding(0.3).joint_positions(), 30.0, 0.6)
    np.testing.assert_allclose(drift[:, 0], 0.01)  # 0.3 m/s = 1 cm per frame
    np.testing.assert_allclose(drift[:, 1:], 0.0)
    assert not planted_drift(gliding(1.5).joint_positions(), 30.0, 0.6).any()  # too fast to be planted


def test_sliding_feet_are_held_while_the_correction_lasts():
    dance = gliding(0.3)
    locked = foot_lock(dance)
    before, after = horizontal_foot_steps(dance), horizontal_foot_steps(locked)
    assert after[0] == pytest.approx(0.0, abs=1e-9)  # the first step is cancelled entirely
    tau = FootLockConfig().recovery_seconds * 30
    assert after[: int(tau)].mean() < 0.5 * before[: int(tau)].mean()
    # the correction leaks back: on a steady glide the body settles a fixed distance behind its own
    # path (the geometric series of 1 cm steps kept at exp(-1/tau) per frame), instead of stopping
    offset = 0.01 / (1 - np.exp(-1 / tau))
    assert np.abs(locked.root_positions[-1, 0] - dance.root_positions[-1, 0]) == pytest.approx(offset, rel=0.02)


def test_root_correction_matches_a_literal_loop():
    drift = np.zeros((5, 3))
    drift[:, 0] = [0.01, 0.02, 0.0, -0.01, 0.0]
    keep = np.exp(-1 / (0.5 * 30))
    expected, c = [0.0], 0.0
    for d in drift[:, 0]:
        c = keep * c - d
        expected.append(c)
    np.testing.assert_allclose(root_correction(drift, 30.0, np.zeros(6, bool), 0.5)[:, 0], expected)


def test_fixed_frames_keep_their_root_and_the_path_ramps_between_them():
    dance = gliding(0.3)
    fixed = np.zeros(dance.num_frames, bool)
    fixed[[0, 45, 89]] = True
    locked = foot_lock(dance, fixed)
    np.testing.assert_array_equal(locked.root_positions[fixed], dance.root_positions[fixed])
    steps = np.linalg.norm(np.diff(locked.root_positions, axis=0), axis=-1)
    assert steps.max() < 0.02  # no jump at the fixed frames
    assert not np.allclose(locked.root_positions, dance.root_positions)


def test_foot_lock_lowers_pfc_of_a_gliding_dancer():
    dance = gliding(0.3)
    root = dance.root_positions.copy()
    root[:, 0] += 0.05 * np.sin(np.arange(dance.num_frames) / 3.0)  # the root accelerates, so PFC counts the glide
    dance = dance.replace(root_positions=root)
    assert foot_contact_score(foot_lock(dance).joint_positions()) < 0.5 * foot_contact_score(dance.joint_positions())


def test_bad_settings_are_refused():
    with pytest.raises(ParameterError):
        FootLockConfig(recovery_seconds=0)
    with pytest.raises(ParameterError):
        foot_lock(gliding(0.3), np.zeros(3, bool))


@pytest.mark.survivor
def test_one_planted_foot_carries_its_whole_drift():
    joints = np.zeros((10, 24, 3))
    t = np.arange(10)
    joints[:, [7, 10], 0] = 0.01 * t[:, None]  # left ankle and toe: 0.3 m/s, planted
    joints[:, [8, 11], 0] = 0.1 * t[:, None]  # right: 3 m/s, swinging
    drift = planted_drift(joints, 30.0, 0.6)
    np.testing.assert_allclose(drift, np.tile([0.01, 0.0, 0.0], (9, 1)), atol=1e-12)


def literal_correction(drift_x, keep):
    c, out = 0.0, [0.0]
    for d in drift_x:
        c = keep * c - d
        out.append(c)
    return np.array(out)


@pytest.mark.survivor
def test_root_correction_after_a_fixed_first_frame_runs_free_to_the_end():
    drift = np.zeros((5, 3))
    drift[:, 0] = [0.01, 0.02, 0.0, -0.01, 0.03]
    keep = math.exp(-1 / (0.5 * 30))
    fixed = np.array([1, 0, 0, 0, 0, 0], bool)
    got = root_correction(drift, 30.0, fixed, 0.5)
    np.testing.assert_allclose(got[:, 0], literal_correction(drift[:, 0], keep), atol=1e-15)
    np.testing.assert_array_equal(got[:, 1:], 0.0)


@pytest.mark.survivor
def test_root_correction_between_two_fixed_frames_ramps_to_zero():
    drift = np.zeros((5, 3))
    drift[:, 0] = [0.01, 0.02, 0.0, -0.01, 0.03]
    c = literal_correction(drift[:, 0], math.exp(-1 / (0.5 * 30)))
    fixed = np.array([1, 0, 0, 0, 0, 1], bool)
    expected = [c[t] - t / 5 * c[5] for t in range(6)]  # a straight line from 0 to c[5] taken off
    np.testing.assert_allclose(root_correction(drift, 30.0, fixed, 0.5)[:, 0], expected, atol=1e-15)


@pytest.mark.survivor
def test_foot_lock_takes_a_mask_of_ones_and_zeros():
    frames = 12
    root = np.zeros((frames, 3))
    root[:, 0] = 0.01 * np.arange(frames)  # a standing dancer gliding at 0.3 m/s: the feet drift 1 cm a frame
    root[:, 1] = 0.9
    dance = Motion.rest(frames).replace(root_positions=root)
    locked = foot_lock(dance, [1] + [0] * (frames - 1))  # frame 0 fixed, the rest free to the end
    keep = math.exp(-1 / (0.65 * 30))
    expected = root[:, 0] + literal_correction([0.01] * (frames - 1), keep)
    np.testing.assert_allclose(locked.root_positions[:, 0], expected, atol=1e-9)
    assert locked.root_positions[1, 0] == pytest.approx(0.0, abs=1e-9)  # the first step cancelled


@pytest.mark.survivor
@pytest.mark.parametrize("settings", [dict(speed_threshold=0.0), dict(recovery_seconds=0.0)])
def test_foot_lock_needs_positive_settings(settings):
    with pytest.raises(ParameterError, match="^foot lock: speed threshold and recovery time must be positive$"):
        FootLockConfig(**settings)


def walking(frames: int) -> Motion:
    t = np.arange(frames)[:, None]
    return Motion.rest(frames).replace(root_positions=np.hstack([0.02 * t, np.full_like(t, 0.9, float), 0 * t]),
                                       metadata={"genre": "waltz"})


@pytest.mark.survivor
def test_foot_lock_works_from_three_frames_and_keeps_metadata():
    short = walking(2)
    assert foot_lock(short) is short  # nothing to correct in two frames
    three = walking(3)
    locked = foot_lock(three, config=FootLockConfig(speed_threshold=5.0))  # the standing feet count as planted
    assert not np.allclose(locked.root_positions, three.root_positions)
    assert locked.metadata == {"genre": "waltz"} and locked.metadata is not three.metadata


@pytest.mark.survivor
def test_foot_lock_refuses_a_mask_of_another_length():
    with pytest.raises(ParameterError, match=r"^fixed frames must be a \(10,\) mask, got \(9,\)$"):
        foot_lock(walking(10), np.zeros(9, bool))
